// Tracking benchmark: prints ms per call and LM iterations of the tracker variants side by side
// (paper settings, device vs host final reduction, early exit, coarse-to-fine), with their pose
// errors, on synthetic frames with known motion and on the real TUM fr1/xyz pairs; plus the
// preprocessing kernel and one accumulation pass. Figures only, never pass/fail.
//
// Usage: track_bench [--data DIR] [--trials N] [--quick] [--kernels-only] [--sequences]
//   --sequences: only the frame-to-frame statistics on redkitchen and fr3-cabinet-keyframes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <map>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bench_args.h"
#include "track/preprocess.h"
#include "track/tracker.h"
#include "track_test_support.h"

namespace {

using emf::track::TrackOptions;
using emf::track::TrackResult;
using Clock = std::chrono::steady_clock;
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// CPU time of the whole process (all PoCL threads), ms: the work done, independent of how much
// of the 2 shared cores the other processes on the machine leave us.
double cpuMs() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Variant {
  std::string name;
  TrackOptions options;
};

std::vector<Variant> variants() {
  std::vector<Variant> out;
  // The paper's settings (docs/method.md#tracking): tau 1e3, eps 1e-8, 100 iterations, all
  // pixels, plain LM.
  TrackOptions paper;
  paper.coarse_levels = 0;
  paper.early_exit_step = 0.0;
  paper.max_step_scale = 1.0;
  out.push_back({"paper-host", paper});
  TrackOptions dev = paper;
  dev.final_reduction = emf::track::FinalReduction::kDevice;
  out.push_back({"paper-device", dev});
  TrackOptions early = paper;
  early.early_exit_step = 1e-5;
  out.push_back({"paper+exit", early});
  TrackOptions c2f = early;
  c2f.coarse_levels = 2;
  out.push_back({"paper+exit+c2f", c2f});
  out.push_back({"default", TrackOptions{}});  // c2f + early exit + step extrapolation
  TrackOptions stride2;
  stride2.pixel_stride = 2;
  stride2.coarse_levels = 1;
  out.push_back({"default-stride2", stride2});
  TrackOptions stride4;
  stride4.pixel_stride = 4;
  stride4.coarse_levels = 1;
  out.push_back({"default-stride4", stride4});
  return out;
}

Eigen::Isometry3d perturb(const Eigen::Isometry3d& T, std::mt19937& rng, double t_m,
                          double angle_rad) {
  Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
  P.linear() = emf::track::expSo3(emf::test::randomUnit(rng) * angle_rad);
  P.translation() = emf::test::randomUnit(rng) * t_m;
  return T * P;
}

struct Stats {
  std::vector<double> ms, cpu_ms, iterations;
  double max_t_mm = 0, max_r_deg = 0;
  int lost = 0, runs = 0;
  void add(double t_ms, double t_cpu_ms, const TrackResult& r, const Eigen::Isometry3d& T_gt) {
    ms.push_back(t_ms);
    cpu_ms.push_back(t_cpu_ms);
    iterations.push_back(r.iterations);
    const Eigen::Isometry3d e = T_gt.inverse() * r.T_volume_camera;
    max_t_mm = std::max(max_t_mm, e.translation().norm() * 1000.0);
    max_r_deg = std::max(max_r_deg, emf::track::rotationAngle(e) / kDeg);
    lost += r.lost ? 1 : 0;
    ++runs;
  }
  void print(const std::string& scene, const std::string& variant) const {
    double mean_it = 0;
    for (double i : iterations) mean_it += i;
    mean_it /= std::max<size_t>(1, iterations.size());
    std::printf("  %-16s %9.1f %9.1f %9.1f %8.1f %11.3f %11.4f %5d/%d\n", variant.c_str(),
                median(ms), *std::min_element(ms.begin(), ms.end()), median(cpu_ms), mean_it,
                max_t_mm, max_r_deg, lost, runs);
    std::printf(
        "track_bench scene=%s variant=%s ms=%.2f cpu_ms=%.2f iters=%.1f t_err_mm=%.3f "
        "r_err_deg=%.4f lost=%d\n",
        scene.c_str(), variant.c_str(), median(ms), median(cpu_ms), mean_it, max_t_mm, max_r_deg,
        lost);
  }
};

void header() {
  std::printf("  %-16s %9s %9s %9s %8s %11s %11s %7s\n", "variant", "ms(med)", "ms(min)", "cpu ms",
              "iters", "max t(mm)", "max r(deg)", "lost");
}

// Synthetic room: tracks `trials` perturbed starts with every variant.
void syntheticScene(emf::cl::Context& ctx, const std::string& name, float voxel_m, int width,
                    double t_m, double r_deg, int trials) {
  const emf::test::AnalyticScene scene = emf::test::roomCornerScene();
  const int blocks = static_cast<int>(std::lround(2.56 / voxel_m / 8));
  const emf::test::HostVolume host =
      emf::test::volumeFromSdf([&](const Eigen::Vector3f& x) { return scene.sdf(x); },
                               Eigen::Vector3i::Constant(blocks), voxel_m, 10 * voxel_m, 10.0f);
  const emf::test::DeviceVolume vol = emf::test::upload(ctx, host);
  emf::core::Intrinsics k = emf::test::smallCamera();
  k = k.scaled(width, width * 3 / 4);
  const Eigen::Isometry3d T_gt = emf::test::roomCornerCamera();
  const cv::Mat depth = scene.render(k, T_gt);
  emf::track::Preprocessor pre(ctx, emf::track::PreprocessOptions{}, k);
  pre.process(depth);
  std::printf(
      "\n%s: room corner + boxes, %dx%d, voxel %.0f mm, truncation %.0f mm, %d blocks, "
      "starts %.0f mm / %.1f deg off (%d trials)\n",
      name.c_str(), k.width, k.height, voxel_m * 1000, voxel_m * 10000, host.allocatedBlocks(),
      t_m * 1000, r_deg, trials);
  header();
  for (const Variant& v : variants()) {
    emf::track::Tracker tracker(ctx, v.options, k.width, k.height);
    tracker.track(vol.view, pre.vertexMap().get(), nullptr, T_gt);  // warm-up (kernel build)
    std::mt19937 rng(100);
    Stats s;
    for (int i = 0; i < trials; ++i) {
      const Eigen::Isometry3d init = perturb(T_gt, rng, t_m, r_deg * kDeg);
      const auto t0 = Clock::now();
      const double c0 = cpuMs();
      const TrackResult r = tracker.track(vol.view, pre.vertexMap().get(), nullptr, init);
      s.add(msSince(t0), cpuMs() - c0, r, T_gt);
    }
    s.print(name, v.name);
  }
}

void realPairs(emf::cl::Context& ctx, const std::string& data, int repeats) {
  emf::core::Intrinsics k;
  k.fx = k.fy = 525.0;
  k.cx = 319.5;
  k.cy = 239.5;
  k.width = 640;
  k.height = 480;
  for (const char* c : {"case_1", "case_2"}) {
    const std::string dir = data + "/tum-fr1-xyz-pairs/" + c;
    const cv::Mat prev = emf::test::readDepthPng(dir + "/dep_prev.png", 5000.0);
    const cv::Mat curr = emf::test::readDepthPng(dir + "/dep_curr.png", 5000.0);
    const Eigen::Isometry3d gt = emf::test::readPoseTxt(dir + "/pose_prev.txt").inverse() *
                                 emf::test::readPoseTxt(dir + "/pose_curr.txt");
    emf::test::HostVolume host(Eigen::Vector3i(64, 64, 64), 0.01f, 0.1f);
    Eigen::Isometry3d T_vp = Eigen::Isometry3d::Identity();
    T_vp.translation() << 2.56, 2.56, 0.0;
    emf::test::fuseDepth(&host, prev, k, T_vp, 64.0f);
    const emf::test::DeviceVolume vol = emf::test::upload(ctx, host);
    emf::track::Preprocessor pre(ctx, emf::track::PreprocessOptions{}, k);
    pre.process(curr);
    std::printf(
        "\nreal %s: TUM fr1/xyz pair, 640x480, voxel 10 mm, volume of the first frame, "
        "start at identity (true motion %.1f mm / %.2f deg); error vs mocap\n",
        c, gt.translation().norm() * 1000, emf::track::rotationAngle(gt) / kDeg);
    header();
    for (const Variant& v : variants()) {
      emf::track::Tracker tracker(ctx, v.options, k.width, k.height);
      tracker.track(vol.view, pre.vertexMap().get(), nullptr, T_vp);  // warm-up
      Stats s;
      for (int i = 0; i < repeats; ++i) {
        const auto t0 = Clock::now();
        const double c0 = cpuMs();
        const TrackResult r = tracker.track(vol.view, pre.vertexMap().get(), nullptr, T_vp);
        s.add(msSince(t0), cpuMs() - c0, r, T_vp * gt);
      }
      s.print(std::string("fr1-") + c, v.name);
    }
  }
}

// One accumulation pass with each final reduction, and the preprocessing kernel: median wall
// and CPU ms.
void kernels(emf::cl::Context& ctx, const std::string& data, int repeats) {
  const emf::test::AnalyticScene scene = emf::test::roomCornerScene();
  const emf::test::HostVolume host =
      emf::test::volumeFromSdf([&](const Eigen::Vector3f& x) { return scene.sdf(x); },
                               Eigen::Vector3i::Constant(32), 0.01f, 0.1f, 10.0f);
  const emf::test::DeviceVolume vol = emf::test::upload(ctx, host);
  const cv::Mat real =
      emf::test::readDepthPng(data + "/tum-fr1-xyz-pairs/case_1/dep_prev.png", 5000.0);
  auto timeIt = [&](const std::function<void()>& f, double* wall, double* cpu) {
    f();  // warm-up
    std::vector<double> w, c;
    for (int i = 0; i < repeats; ++i) {
      const auto t0 = Clock::now();
      const double c0 = cpuMs();
      f();
      c.push_back(cpuMs() - c0);
      w.push_back(msSince(t0));
    }
    *wall = median(w);
    *cpu = median(c);
  };
  std::printf("\nkernels (median of %d runs; wall ms / process CPU ms)\n", repeats);
  std::printf("  %-9s %15s %15s %15s %15s %15s %7s\n", "size", "preprocess", "eval:host-sum",
              "eval:device-sum", "eval:stride2", "eval:stride8", "groups");
  for (int width : {640, 320}) {
    emf::core::Intrinsics k = emf::test::smallCamera().scaled(width, width * 3 / 4);
    const cv::Mat depth = scene.render(k, emf::test::roomCornerCamera());
    emf::track::Preprocessor pre(ctx, emf::track::PreprocessOptions{}, k);
    cv::Mat real_scaled;
    cv::resize(real, real_scaled, cv::Size(k.width, k.height), 0, 0, cv::INTER_NEAREST);
    double w[5], c[5];
    timeIt(
        [&] {
          pre.process(real_scaled);
          ctx.finish();
        },
        &w[0], &c[0]);
    pre.process(depth);
    int groups = 0;
    // Modes: host sum, device sum, stride 2, stride 8 (few pixels: mostly the fixed cost of one
    // evaluation, i.e. launch, partial read-back and host sum).
    for (int mode = 0; mode < 4; ++mode) {
      TrackOptions o;
      o.final_reduction =
          mode == 1 ? emf::track::FinalReduction::kDevice : emf::track::FinalReduction::kHost;
      const int stride = mode == 2 ? 2 : (mode == 3 ? 8 : 1);
      emf::track::Tracker tracker(ctx, o, k.width, k.height);
      groups = tracker.numGroups(1);
      timeIt(
          [&] {
            tracker.evaluate(vol.view, pre.vertexMap().get(), nullptr,
                             emf::test::roomCornerCamera(), stride);
          },
          &w[mode + 1], &c[mode + 1]);
    }
    {
      const emf::track::PreprocessedFrame f =
          emf::track::preprocessReference(real_scaled, k, emf::track::PreprocessOptions{});
      const emf::track::PreprocessedFrame g =
          emf::track::preprocessReference(depth, k, emf::track::PreprocessOptions{});
      double rw, rc, aw, ac;
      timeIt([&] { emf::track::preprocessReference(real_scaled, k, {}); }, &rw, &rc);
      timeIt(
          [&] {
            emf::track::accumulateReference(host.view(), g.vertex, cv::Mat(), 1,
                                            emf::test::roomCornerCamera(), 0.02);
          },
          &aw, &ac);
      std::printf("  CPU reference (1 thread): preprocess %.2f ms, accumulate %.2f ms\n", rc, ac);
    }
    std::printf("  %4dx%-4d %7.2f/%7.2f %7.2f/%7.2f %7.2f/%7.2f %7.2f/%7.2f %7.2f/%7.2f %7d\n",
                k.width, k.height, w[0], c[0], w[1], c[1], w[2], c[2], w[3], c[3], w[4], c[4],
                groups);
    std::printf(
        "track_bench kernels=%dx%d preprocess_ms=%.2f preprocess_cpu_ms=%.2f "
        "eval_host_ms=%.2f eval_host_cpu_ms=%.2f eval_device_ms=%.2f "
        "eval_device_cpu_ms=%.2f eval_stride2_ms=%.2f eval_stride2_cpu_ms=%.2f "
        "eval_stride8_ms=%.2f eval_stride8_cpu_ms=%.2f\n",
        k.width, k.height, w[0], c[0], w[1], c[1], w[2], c[2], w[3], c[3], w[4], c[4]);
  }
}

// Frame-to-frame statistics over real sequences: fuses frame i into a fresh volume (CPU
// reference fusion, 1 cm), tracks frame i + gap from identity with the default options, and
// prints the errors against the ground truth and the loss-rule figures (for the thresholds).
struct SequenceFrame {
  std::string depth_path;
  Eigen::Isometry3d T_world_camera;
};

std::vector<SequenceFrame> readSequence(const std::string& dir) {
  std::vector<SequenceFrame> frames;
  std::ifstream assoc(dir + "/associations.txt"), gt(dir + "/groundtruth.txt");
  std::map<std::string, Eigen::Isometry3d> poses;
  std::string line;
  while (std::getline(gt, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string ts;
    double tx, ty, tz, qx, qy, qz, qw;
    in >> ts >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
    T.translation() << tx, ty, tz;
    poses[ts] = T;
  }
  while (std::getline(assoc, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string t_rgb, rgb, t_depth, depth;
    in >> t_rgb >> rgb >> t_depth >> depth;
    const auto it = poses.find(t_depth);
    if (it != poses.end()) frames.push_back({dir + "/" + depth, it->second});
  }
  return frames;
}

void sequence(emf::cl::Context& ctx, const std::string& name, const std::string& dir,
              double depth_scale, const emf::core::Intrinsics& k, int gap, int step) {
  const std::vector<SequenceFrame> frames = readSequence(dir);
  std::printf(
      "\nsequence %s: %zu frames, pairs (i, i+%d) every %d frames, single-frame volume "
      "(1 cm), start at identity, default options\n",
      name.c_str(), frames.size(), gap, step);
  std::printf("  %5s %9s %9s %9s %9s %6s %6s %7s %6s %9s %s\n", "pair", "gt mm", "gt deg", "err mm",
              "err deg", "valid", "inl", "invcond", "iters", "ms", "lost");
  emf::track::Preprocessor pre(ctx, emf::track::PreprocessOptions{}, k);
  emf::track::Tracker tracker(ctx, TrackOptions{}, k.width, k.height);
  std::vector<double> ms, valid, inl, cond;
  int lost = 0, silent_bad = 0, pairs = 0;
  for (size_t i = 0; i + gap < frames.size(); i += step) {
    const cv::Mat prev = emf::test::readDepthPng(frames[i].depth_path, depth_scale);
    const cv::Mat curr = emf::test::readDepthPng(frames[i + gap].depth_path, depth_scale);
    const Eigen::Isometry3d gt =
        frames[i].T_world_camera.inverse() * frames[i + gap].T_world_camera;
    emf::test::HostVolume host(Eigen::Vector3i(64, 64, 64), 0.01f, 0.1f);
    Eigen::Isometry3d T_vp = Eigen::Isometry3d::Identity();
    T_vp.translation() << 2.56, 2.56, 0.0;
    emf::test::fuseDepth(&host, prev, k, T_vp, 64.0f);
    const emf::test::DeviceVolume vol = emf::test::upload(ctx, host);
    pre.process(curr);
    const auto t0 = Clock::now();
    const TrackResult r = tracker.track(vol.view, pre.vertexMap().get(), nullptr, T_vp);
    ms.push_back(msSince(t0));
    const Eigen::Isometry3d e = gt.inverse() * (T_vp.inverse() * r.T_volume_camera);
    const double e_mm = e.translation().norm() * 1000, e_deg = emf::track::rotationAngle(e) / kDeg;
    valid.push_back(r.valid_fraction);
    inl.push_back(r.inlier_ratio);
    cond.push_back(r.inverse_condition);
    lost += r.lost ? 1 : 0;
    // A wrong pose that is not flagged: more than 2 cm / 2 deg off the ground truth.
    if (!r.lost && (e_mm > 20.0 || e_deg > 2.0)) ++silent_bad;
    ++pairs;
    std::printf("  %5zu %9.1f %9.2f %9.1f %9.2f %6.3f %6.3f %7.4f %6d %9.1f %s\n", i,
                gt.translation().norm() * 1000, emf::track::rotationAngle(gt) / kDeg, e_mm, e_deg,
                r.valid_fraction, r.inlier_ratio, r.inverse_condition, r.iterations, ms.back(),
                r.lost ? emf::track::trackLossName(r.loss) : "");
  }
  auto mn = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  std::printf(
      "  %s: %d pairs, %d lost, %d wrong (>2 cm / 2 deg) but not flagged; min/median "
      "valid %.3f/%.3f inliers %.3f/%.3f invcond %.4f/%.4f; ms median %.1f\n",
      name.c_str(), pairs, lost, silent_bad, mn(valid), median(valid), mn(inl), median(inl),
      mn(cond), median(cond), median(ms));
  std::printf("track_bench sequence=%s pairs=%d lost=%d silent_wrong=%d ms=%.1f\n", name.c_str(),
              pairs, lost, silent_bad, median(ms));
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(EMF_SOURCE_DIR) + "/../shared/data";
  int trials = 6;
  bool quick = false;
  bool kernels_only = false;
  bool sequences_only = false;
  const char* usage =
      "usage: track_bench [--data DIR] [--trials N] [--quick] [--kernels-only] [--sequences]\n";
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::printf("%s", usage);
        return 0;
      } else if (args.is("--data")) {
        data = args.value();
      } else if (args.is("--trials")) {
        trials = static_cast<int>(args.integer(1, 100000));
      } else if (args.is("--quick")) {
        quick = true;
      } else if (args.is("--kernels-only")) {
        kernels_only = true;
      } else if (args.is("--sequences")) {
        sequences_only = true;
      } else {
        args.unknown();
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "track_bench: %s\n%s", e.what(), usage);
    return emf::bench::kExitUsage;
  }
  try {
    emf::cl::Context ctx(emf::cl::ClOptions{});
    std::printf("track_bench on %s\n", ctx.describe().c_str());
    if (sequences_only) {
      emf::core::Intrinsics kitchen{585, 585, 320, 240, 640, 480};
      sequence(ctx, "redkitchen", data + "/redkitchen-0-299", 1000.0, kitchen, 5, 15);
      emf::core::Intrinsics fr3{535.4, 539.2, 320.1, 247.6, 640, 480};
      sequence(ctx, "fr3-cabinet-keyframes", data + "/tum-fr3-cabinet-keyframes", 5000.0, fr3, 1,
               1);
      return 0;
    }
    kernels(ctx, data, quick ? 5 : 30);
    if (kernels_only) return 0;
    syntheticScene(ctx, "room-320-2cm", 0.02f, 320, 0.05, 5.0, trials);
    syntheticScene(ctx, "room-640-1cm", 0.01f, 640, 0.02, 2.0, trials);
    if (!quick) syntheticScene(ctx, "room-640-1cm-5cm5deg", 0.01f, 640, 0.05, 5.0, trials);
    realPairs(ctx, data, quick ? 1 : 3);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "track_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
