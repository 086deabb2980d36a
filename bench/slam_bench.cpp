// slam_bench: the whole static SLAM loop (`emf run`) against Open3D's dense RGB-D SLAM as the
// peer (bench/open3d_peer.py), on the same frames, per dataset and resolution configuration.
//
// For each dataset the frames (at most --frames, resized to the configuration's resolution)
// are first written once as a TUM folder (depth uint16, 5000 units/m, plus ground truth); then
// `emf run --source tum:<folder>` and `python3 bench/open3d_peer.py --data <folder>` run on it
// as child processes, one after the other. Per system: ATE RMSE against the ground truth
// (eval::computeAte, as `emf eval`), ms per frame median/p90 (emf: SlamSystem's stage timer from
// run.json; peer: its own per-frame clock; both exclude image loading), peak RSS (the child's
// ru_maxrss from wait4) and, for emf, the voxel-pool memory. Ends with one line per dataset:
//   slam_bench data=<name> res=WxH voxel_m=.. emf_ate_cm=.. emf_ms=.. emf_p90_ms=.. emf_lost=..
//              peer_ate_cm=.. peer_ms=.. speedup=..
//              emf_vs_peer_ate_cm=.. gt_step_deg=.. emf_step_deg=.. peer_step_deg=..
// (speedup = peer median / emf median; peer fields are "nan" with --no-peer). The last four tell
// how far the ground truth itself is off: the ATE of emf against the peer, and each
// trajectory's own rms rotation error per frame from the three-cornered hat of their pairwise
// one-frame RPEs (eval::threeCorneredHat).
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bench_args.h"
#include "common/error.h"
#include "core/frame_source.h"
#include "eval/eval.h"
#include "io/trajectory.h"
#include "io/tum_writer.h"
#include "pipeline/config.h"
#include "sources/open_source.h"

namespace {

namespace fs = std::filesystem;

struct Resolution {
  int width = 640, height = 480;
  double voxel_m = 0.01;
  int volume_voxels = 512;  // 5.12 m at 1 cm, 5.12 m at 2 cm with 256
};

struct Args {
  std::vector<std::string> data = {"redkitchen", "synth"};
  int frames = 300;
  Resolution res;
  bool peer = true;
  std::string out = "slam_bench_out";
  std::string emf = EMF_CLI_PATH;
  std::string python = "/usr/bin/python3";
  std::string peer_script = EMF_BENCH_DIR "/open3d_peer.py";
  std::string config;
  std::vector<std::string> sets;
  int peer_source_stride = 0;  // 0 = width / 160
};

void usage() {
  std::printf(
      "usage: slam_bench [options]\n"
      "  --data LIST       comma-separated datasets: redkitchen, synth (synth:room), cabinet,\n"
      "                    or a TUM folder path (default redkitchen,synth)\n"
      "  --frames N        frames per dataset (default 300)\n"
      "  --res R           640 (640x480 @ 1 cm, default) or 320 (320x240 @ 2 cm)\n"
      "  --no-peer         run emf only\n"
      "  --out DIR         work folder (default ./slam_bench_out)\n"
      "  --emf PATH        emf executable (default the build's)\n"
      "  --python PATH     interpreter for the peer (default /usr/bin/python3, Debian's Open3D)\n"
      "  --config FILE     emf configuration passed to emf run\n"
      "  --set S.K=V       emf configuration override (repeatable)\n"
      "  --peer-stride N   frame pixels used by the peer's ICP (default width/160)\n");
}

Args parseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw emf::bench::UsageError(k + " needs a value");
      return argv[++i];
    };
    if (k == "--help" || k == "-h") {
      usage();
      std::exit(0);
    } else if (k == "--data") {
      a.data.clear();
      std::stringstream ss(value());
      for (std::string item; std::getline(ss, item, ',');) {
        if (!item.empty()) a.data.push_back(item);
      }
    } else if (k == "--frames") {
      a.frames = static_cast<int>(
          emf::bench::parseInteger(k, value(), static_cast<long>(emf::eval::kMinAtePairs), 100000));
    } else if (k == "--res") {
      const std::string r = value();
      if (r == "640") {
        a.res = Resolution{640, 480, 0.01, 512};
      } else if (r == "320") {
        a.res = Resolution{320, 240, 0.02, 256};
      } else {
        throw emf::bench::UsageError("--res '" + r +
                                     "': use 640 (640x480@1cm) or 320 (320x240@2cm)");
      }
    } else if (k == "--no-peer") {
      a.peer = false;
    } else if (k == "--out") {
      a.out = value();
    } else if (k == "--emf") {
      a.emf = value();
    } else if (k == "--python") {
      a.python = value();
    } else if (k == "--config") {
      a.config = value();
    } else if (k == "--set") {
      a.sets.push_back(value());
    } else if (k == "--peer-stride") {
      a.peer_source_stride = static_cast<int>(emf::bench::parseInteger(k, value(), 1, 64));
    } else {
      throw emf::bench::UsageError("unknown option '" + k + "'");
    }
  }
  return a;
}

struct Dataset {
  std::string name, uri;
  double depth_scale = 5000;
};

Dataset resolveDataset(const std::string& d, const Resolution& res) {
  const std::string shared = EMF_SHARED_DATA_DIR;
  if (d == "redkitchen") return {"redkitchen-0-299", "tum:" + shared + "/redkitchen-0-299", 1000};
  if (d == "cabinet") {
    return {"tum-fr3-cabinet-keyframes", "tum:" + shared + "/tum-fr3-cabinet-keyframes", 5000};
  }
  if (d == "synth" || d == "synth:room") {
    return {"synth-room",
            "synth:room?width=" + std::to_string(res.width) +
                "&height=" + std::to_string(res.height) + "&seed=1",
            5000};
  }
  // The name becomes a folder under --out: one plain component, never "", "." or "..".
  auto folderName = [](std::string name) {
    for (char& c : name) {
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
    }
    return name;
  };
  if (d.rfind("synth:", 0) == 0) return {"synth-" + folderName(d.substr(6)), d, 5000};
  std::error_code ec;
  const std::string name = fs::weakly_canonical(fs::absolute(d), ec).filename().string();
  if (name.empty() || name == "." || name == "..") {
    throw std::runtime_error("--data '" + d + "': cannot name a work folder after it");
  }
  return {folderName(name), "tum:" + d, 5000};
}

/// 2x2-block depth down-sampling by an integer factor: mean of the valid samples within 3 cm
/// of the nearest one (no blending across depth edges).
cv::Mat downsampleDepth(const cv::Mat& depth, int factor) {
  cv::Mat out(depth.rows / factor, depth.cols / factor, CV_32F);
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      float zmin = INFINITY;
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) {
          const float z = depth.at<float>(y * factor + dy, x * factor + dx);
          if (std::isfinite(z) && z > 0) zmin = std::min(zmin, z);
        }
      }
      float sum = 0;
      int n = 0;
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) {
          const float z = depth.at<float>(y * factor + dy, x * factor + dx);
          if (std::isfinite(z) && z > 0 && z - zmin < 0.03f) {
            sum += z;
            ++n;
          }
        }
      }
      out.at<float>(y, x) = n > 0 ? sum / n : NAN;
    }
  }
  return out;
}

/// Writes the frames the two systems will read. Returns the frame count.
int prepareFrames(const Dataset& d, const Args& a, const std::string& dir) {
  emf::core::SourceOptions options;
  options.depth_scale = d.depth_scale;
  auto src = emf::sources::openSource(d.uri, options);
  const emf::core::Intrinsics k0 = src->intrinsics();
  if (k0.width % a.res.width != 0 || k0.width / a.res.width != k0.height / a.res.height) {
    throw emf::InvalidArgument(d.uri + ": " + std::to_string(k0.width) + "x" +
                               std::to_string(k0.height) + " frames cannot be reduced to " +
                               std::to_string(a.res.width) + "x" + std::to_string(a.res.height) +
                               " by an integer factor");
  }
  const int factor = k0.width / a.res.width;
  const emf::core::Intrinsics k = k0.scaled(a.res.width, a.res.height);
  fs::remove_all(dir);
  emf::io::TumWriterOptions wo;
  wo.readme_about = "slam_bench frames of " + d.uri;
  emf::io::TumWriter writer(dir, k, wo);
  emf::core::Frame f;
  int n = 0;
  while (n < a.frames && src->next(f)) {
    if (!f.T_world_camera_gt) {
      throw emf::IoError(d.uri + ": frame " + std::to_string(f.index) +
                         " has no ground-truth pose (slam_bench needs them for the ATE)");
    }
    if (factor > 1) {
      f.depth = downsampleDepth(f.depth, factor);
      if (!f.color.empty()) {
        cv::resize(f.color, f.color, cv::Size(a.res.width, a.res.height), 0, 0, cv::INTER_AREA);
      }
    }
    f.detections.reset();
    f.T_world_object_gt.clear();
    f.instance_ids.release();
    writer.write(f);
    ++n;
  }
  writer.finish();
  return n;
}

struct ChildResult {
  int exit_code = -1;
  double peak_rss_mb = 0;
  double wall_s = 0;
  double cpu_s = 0;  // user + system time of the child (all its threads)
};

/// Runs argv as a child process (stdout/stderr to `log`), returns its exit code and peak RSS.
ChildResult runChild(const std::vector<std::string>& argv, const std::string& log) {
  std::vector<char*> cargv;
  for (const auto& s : argv) cargv.push_back(const_cast<char*>(s.c_str()));
  cargv.push_back(nullptr);
  std::fflush(stdout);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) throw emf::ResourceError(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    FILE* f = std::freopen(log.c_str(), "w", stdout);
    if (f == nullptr || dup2(fileno(stdout), 2) < 0) _exit(126);
    execv(cargv[0], cargv.data());
    std::fprintf(stderr, "exec %s: %s\n", cargv[0], std::strerror(errno));
    _exit(127);
  }
  int status = 0;
  struct rusage ru {};
  if (wait4(pid, &status, 0, &ru) < 0) {
    throw emf::ResourceError(std::string("wait4 failed: ") + std::strerror(errno));
  }
  ChildResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.peak_rss_mb = ru.ru_maxrss / 1024.0;
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
            1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
  return r;
}

std::string tail(const std::string& path, size_t max_chars = 2000) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string s = ss.str();
  return s.size() > max_chars ? s.substr(s.size() - max_chars) : s;
}

nlohmann::json readJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw emf::IoError(path + ": cannot open");
  return nlohmann::json::parse(in);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double pos = p * (v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - lo) * (v[hi] - v[lo]);
}

struct SystemFigures {
  bool ran = false;
  double ate_cm = NAN, ms = NAN, p90_ms = NAN, rss_mb = NAN;
  size_t poses = 0;
  int lost = 0;
};

/// The estimates against each other (only with the peer): see eval::threeCorneredHat.
struct TruthCheck {
  double emf_vs_peer_ate_cm = NAN;
  double step_deg[3] = {NAN, NAN, NAN};  // own rotation error per frame: gt, emf, peer
};

std::string fmt(double v, int decimals = 2) {
  if (!std::isfinite(v)) return "nan";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

/// How much of the disagreement with the ground truth is the ground truth's own: the two
/// estimates against each other, and the three-cornered hat of the three trajectories' steps
/// (eval::threeCorneredHat) over one frame and over one second. Prints the `truth:` lines. The
/// hat assumes independent errors: an error two trajectories share (the peer's ICP and a ground
/// truth from ICP tracking, say) is given to the third.
TruthCheck truthCheck(const emf::io::Trajectory& gt, const emf::io::Trajectory& est,
                      const emf::io::Trajectory& peer) {
  TruthCheck t;
  try {
    t.emf_vs_peer_ate_cm = emf::eval::computeAte(peer, est).trans_m.rmse * 100;
    std::printf("truth: emf against peer ATE %s cm; RPE rms, rotation deg / translation mm\n",
                fmt(t.emf_vs_peer_ate_cm, 3).c_str());
    std::vector<double> steps;  // the ground truth has a pose per frame (prepareFrames)
    for (size_t k = 1; k < gt.size(); ++k) steps.push_back(gt.stamps[k] - gt.stamps[k - 1]);
    const double frame_s = percentile(steps, 0.5);
    for (const double delta_s : {frame_s, 1.0}) {
      const emf::eval::ThreeCorneredHat h = emf::eval::threeCorneredHat(gt, est, peer, delta_s);
      if (delta_s == frame_s) {
        for (int i = 0; i < 3; ++i) t.step_deg[i] = h.rot_deg[i];
      }
      const auto pair = [](const emf::eval::RpeResult& r) {
        return fmt(r.rot_deg.rmse, 3) + " / " + fmt(r.trans_m.rmse * 1e3);
      };
      const auto own = [&h](int i) {
        return fmt(h.rot_deg[i], 3) + " / " + fmt(h.trans_m[i] * 1e3);
      };
      std::printf(
          "       over %s s (%zu poses common): emf-gt %s, peer-gt %s, emf-peer %s; own share "
          "(three-cornered hat): gt %s, emf %s, peer %s\n",
          fmt(delta_s, 3).c_str(), h.common_poses, pair(h.ab).c_str(), pair(h.ac).c_str(),
          pair(h.bc).c_str(), own(0).c_str(), own(1).c_str(), own(2).c_str());
    }
  } catch (const emf::InvalidArgument& ex) {
    // Too few poses in common (emf lost most frames): the check has nothing to say.
    std::printf("truth: not computed: %s\n", ex.what());
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    Args a = parseArgs(argc, argv);
    if (a.data.empty()) throw emf::bench::UsageError("--data names no dataset");
    // The configuration emf runs with (--config, the resolution's voxel size and volume, then
    // --set): the peer gets the same voxel size, truncation and depth range, and the summary
    // names the voxel size actually used.
    emf::Config defaults = a.config.empty() ? emf::Config() : emf::Config::loadFile(a.config);
    defaults.set("map.background_voxel_m=" + fmt(a.res.voxel_m, 3));
    defaults.set("map.background_resolution=" + std::to_string(a.res.volume_voxels));
    for (const auto& set : a.sets) defaults.set(set);
    defaults.validate();
    a.res.voxel_m = defaults.map.background_voxel_m;
    fs::create_directories(a.out);
    int failed = 0;
    std::vector<std::string> lines;
    bool device_printed = false;  // the device of emf's first run (the peer runs on the CPU)
    std::printf("slam_bench: %dx%d @ %.0f cm, up to %d frames per dataset, peer %s\n", a.res.width,
                a.res.height, a.res.voxel_m * 100, a.frames, a.peer ? "Open3D" : "off");
    for (const std::string& name : a.data) {
      try {
        const Dataset d = resolveDataset(name, a.res);
        const std::string dir = fs::absolute(a.out + "/" + d.name).string();
        const std::string frames_dir = dir + "/frames";
        const int n = prepareFrames(d, a, frames_dir);
        const emf::io::Trajectory gt = emf::io::readTrajectory(frames_dir + "/groundtruth.txt");
        std::printf("\n== %s: %d frames (%s)\n", d.name.c_str(), n, d.uri.c_str());

        // ---- emf ----
        SystemFigures e;
        std::vector<std::string> cmd = {
            a.emf,      "run",
            "--source", "tum:" + frames_dir + "?depth_scale=5000",
            "--out",    dir + "/emf",
            "--force",  "--quiet",
            "--set",    "map.background_voxel_m=" + fmt(a.res.voxel_m, 3),
            "--set",    "map.background_resolution=" + std::to_string(a.res.volume_voxels)};
        if (!a.config.empty()) cmd.insert(cmd.begin() + 2, {"--config", a.config});
        for (const auto& s : a.sets) cmd.insert(cmd.end(), {"--set", s});
        const ChildResult er = runChild(cmd, dir + "/emf.log");
        if (er.exit_code != 0) {
          std::fprintf(stderr, "slam_bench: %s: emf run failed (exit %d); its log %s ends:\n%s\n",
                       d.name.c_str(), er.exit_code, (dir + "/emf.log").c_str(),
                       tail(dir + "/emf.log").c_str());
          ++failed;
          continue;  // no figures for it; the other datasets still run and print theirs
        }
        const nlohmann::json run = readJson(dir + "/emf/run.json");
        const emf::io::Trajectory est = emf::io::readTrajectory(dir + "/emf/camera.txt");
        e.ran = true;
        e.poses = est.size();
        e.lost = run.at("lost_frames").get<int>();
        e.ms = run.at("ms_per_frame").at("total").at("median_ms").get<double>();
        e.p90_ms = run.at("ms_per_frame").at("total").at("p90_ms").get<double>();
        e.rss_mb = er.peak_rss_mb;
        if (est.size() >= emf::eval::kMinAtePairs) {
          e.ate_cm = emf::eval::computeAte(gt, est).trans_m.rmse * 100;
        }
        if (!device_printed && run.at("device").contains("description")) {
          device_printed = true;
          std::printf("device: %s\n",
                      run.at("device").at("description").get<std::string>().c_str());
        }
        const auto& mem = run.at("memory");
        std::printf(
            "emf:   ATE %s cm over %zu poses (%d lost), %s ms/frame median, %s p90, "
            "peak RSS %.0f MB, pool %.0f MB (%lld of %lld slots used), wall %.1f s\n",
            fmt(e.ate_cm, 3).c_str(), e.poses, e.lost, fmt(e.ms).c_str(), fmt(e.p90_ms).c_str(),
            e.rss_mb, mem.at("pool_bytes").get<double>() / (1 << 20),
            mem.at("used_slots").get<long long>(), mem.at("pool_slots").get<long long>(),
            er.wall_s);
        std::printf("       stages (median / p90 ms):");
        for (const auto& [stage, s] : run.at("ms_per_frame").items()) {
          if (stage == "total") continue;
          std::printf(" %s %s / %s", stage.c_str(), fmt(s.at("median_ms").get<double>()).c_str(),
                      fmt(s.at("p90_ms").get<double>()).c_str());
        }
        std::printf("\n");
        // Work per frame: figures the machine's load does not change (and the child's CPU time,
        // which other processes change less than the wall clock; it includes loading the images).
        std::printf("       work (median / p90 per frame):");
        for (const auto& [counter, c] : run.at("work_per_frame").items()) {
          std::printf(" %s %s / %s", counter.c_str(), fmt(c.at("median").get<double>(), 1).c_str(),
                      fmt(c.at("p90").get<double>(), 1).c_str());
        }
        std::printf("; process CPU %s ms/frame\n",
                    fmt(1e3 * er.cpu_s / std::max(1, run.at("frames").get<int>())).c_str());
        for (const auto& l : run.at("lost")) {
          std::printf("       lost frame %lld: %s\n", l.at("index").get<long long>(),
                      l.at("reason").get<std::string>().c_str());
        }

        // ---- peer ----
        SystemFigures p;
        TruthCheck t;
        if (a.peer) {
          const int stride =
              a.peer_source_stride > 0 ? a.peer_source_stride : std::max(1, a.res.width / 160);
          std::vector<std::string> pcmd = {
              a.python,          a.peer_script,
              "--data",          frames_dir,
              "--out",           dir + "/peer",
              "--depth-scale",   "5000",
              "--voxel",         fmt(a.res.voxel_m, 3),
              "--trunc-voxels",  std::to_string(defaults.map.truncation_voxels),
              "--depth-min",     fmt(defaults.preprocess.min_depth_m, 3),
              "--depth-max",     fmt(defaults.preprocess.max_depth_m, 3),
              "--source-stride", std::to_string(stride),
              "--target-stride", std::to_string(std::max(1, stride / 2))};
          const ChildResult pr = runChild(pcmd, dir + "/peer.log");
          if (pr.exit_code != 0) {
            std::fprintf(stderr, "slam_bench: %s: the Open3D peer failed (exit %d); %s ends:\n%s\n",
                         d.name.c_str(), pr.exit_code, (dir + "/peer.log").c_str(),
                         tail(dir + "/peer.log").c_str());
            ++failed;
            continue;
          }
          const nlohmann::json pj = readJson(dir + "/peer/peer.json");
          const emf::io::Trajectory pest = emf::io::readTrajectory(dir + "/peer/camera.txt");
          const auto ms = pj.at("ms_per_frame").get<std::vector<double>>();
          p.ran = true;
          p.poses = pest.size();
          p.ms = percentile(ms, 0.5);
          p.p90_ms = percentile(ms, 0.9);
          p.rss_mb = pr.peak_rss_mb;
          p.ate_cm = emf::eval::computeAte(gt, pest).trans_m.rmse * 100;
          std::printf(
              "peer:  ATE %s cm over %zu poses, %s ms/frame median, %s p90, peak RSS %.0f MB, "
              "wall %.1f s\n       ran: %s\n",
              fmt(p.ate_cm, 3).c_str(), p.poses, fmt(p.ms).c_str(), fmt(p.p90_ms).c_str(), p.rss_mb,
              pr.wall_s, pj.at("ran").get<std::string>().c_str());
          std::printf("ratio: ATE emf/peer %s, speed peer/emf %s, peak RSS emf/peer %s\n",
                      fmt(e.ate_cm / p.ate_cm).c_str(), fmt(p.ms / e.ms).c_str(),
                      fmt(e.rss_mb / p.rss_mb).c_str());
          t = truthCheck(gt, est, pest);
        }
        char line[768];
        std::snprintf(line, sizeof line,
                      "slam_bench data=%s res=%dx%d voxel_m=%.3f emf_ate_cm=%s emf_ms=%s "
                      "emf_p90_ms=%s emf_lost=%d emf_rss_mb=%.0f peer_ate_cm=%s peer_ms=%s "
                      "peer_rss_mb=%s speedup=%s emf_vs_peer_ate_cm=%s gt_step_deg=%s "
                      "emf_step_deg=%s peer_step_deg=%s",
                      d.name.c_str(), a.res.width, a.res.height, a.res.voxel_m,
                      fmt(e.ate_cm, 3).c_str(), fmt(e.ms).c_str(), fmt(e.p90_ms).c_str(), e.lost,
                      e.rss_mb, fmt(p.ate_cm, 3).c_str(), fmt(p.ms).c_str(),
                      fmt(p.rss_mb, 0).c_str(), fmt(p.ms / e.ms).c_str(),
                      fmt(t.emf_vs_peer_ate_cm, 3).c_str(), fmt(t.step_deg[0], 3).c_str(),
                      fmt(t.step_deg[1], 3).c_str(), fmt(t.step_deg[2], 3).c_str());
        lines.push_back(line);
      } catch (const std::exception& ex) {
        // One dataset failing (a broken folder, no ground truth) keeps the others' figures.
        std::fprintf(stderr, "slam_bench: %s: %s\n", name.c_str(), ex.what());
        ++failed;
      }
    }
    std::printf("\n");
    for (const auto& l : lines) std::printf("%s\n", l.c_str());
    if (failed > 0) {
      std::fprintf(stderr, "slam_bench: %d of %zu dataset(s) failed (see above)\n", failed,
                   a.data.size());
      return 1;
    }
    return 0;
  } catch (const emf::bench::UsageError& ex) {
    std::fprintf(stderr, "slam_bench: %s (see --help)\n", ex.what());
    return emf::bench::kExitUsage;
  } catch (const std::exception& ex) {
    std::fprintf(stderr, "slam_bench: %s\n", ex.what());
    return 1;
  }
}
