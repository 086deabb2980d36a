// moving_map_bench: the background that follows the camera (map.follow_camera) on a long walk,
// by default the `apartment` preset (a loop through rooms and doors, exact ground truth). Per
// configuration (image size @ voxel size @ pool MiB) two SLAMs run on the same frames in one
// invocation: the moving map, and the baseline, the same map fixed where it starts
// (map.follow_camera = false). Per run it prints: frames lost, the path length, camera ATE
// (rmse, and as % of the path), the drift per metre travelled (RPE over 1 m of path: rmse of the
// translation error of each 1 m step), the pool occupancy over the run (at each tenth of it and
// its largest), ms per frame (median, p90; for the moving map also on the frames with a move and
// without), the background mesh written (vertices, triangles, binary PLY MiB) and how much of
// the walk's surface it holds: of the ground-truth surface points seen along the walk (every
// 15th frame, a grid of pixels, back-projected with the true pose), the share with a mesh vertex
// within 3 voxels.
//
//   moving_map_bench [--source URI] [--frames N] [--configs 640x480@0.01@256,320x240@0.02@64]
//                    [--set section.key=value]...
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "core/frame_source.h"
#include "eval/eval.h"
#include "eval/surface_coverage.h"
#include "io/ply.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "pipeline/stage_timer.h"
#include "sources/open_source.h"

namespace {

using emf::pipeline::SlamSystem;

struct Setting {
  int width = 640, height = 480;
  double voxel_m = 0.01;
  int memory_mb = 256;
  std::string text;
};

Setting parseSetting(const std::string& text) {
  Setting s;
  s.text = text;
  char x = 0, a1 = 0, a2 = 0;
  std::istringstream in(text);
  if (!(in >> s.width >> x >> s.height >> a1 >> s.voxel_m >> a2 >> s.memory_mb) || x != 'x' ||
      a1 != '@' || a2 != '@' || s.width < 32 || s.height < 24 || s.voxel_m < 0.002 ||
      s.memory_mb < 8) {
    throw emf::bench::UsageError(
        "--configs '" + text + "': expected WIDTHxHEIGHT@VOXEL_M@POOL_MIB, e.g. 640x480@0.01@256");
  }
  return s;
}

/// Counts a mesh and keeps its vertices (world frame) for the coverage test.
struct MeshStats : emf::map::MeshSink {
  std::vector<Eigen::Vector3f> vertices;
  size_t triangles = 0;
  void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f*, size_t n) override {
    vertices.insert(vertices.end(), p, p + n);
  }
  void addTriangles(const Eigen::Vector3i*, size_t n) override { triangles += n; }
};

/// Drift per metre: for each pose i, the first j at least `step_m` of true path further; the
/// translation error of (E_i^-1 E_j)^-1 (G_i^-1 G_j); rmse over the steps, metres.
double driftPerStep(const std::vector<Eigen::Isometry3d>& gt,
                    const std::vector<Eigen::Isometry3d>& est, double step_m) {
  std::vector<double> along(gt.size(), 0.0);
  for (size_t i = 1; i < gt.size(); ++i) {
    along[i] = along[i - 1] + (gt[i].translation() - gt[i - 1].translation()).norm();
  }
  double sum = 0;
  size_t n = 0;
  size_t j = 0;
  for (size_t i = 0; i < gt.size(); ++i) {
    j = std::max(j, i);
    while (j < gt.size() && along[j] - along[i] < step_m) ++j;
    if (j >= gt.size()) break;
    const Eigen::Isometry3d e = (est[i].inverse() * est[j]).inverse() * (gt[i].inverse() * gt[j]);
    sum += e.translation().squaredNorm();
    ++n;
  }
  return n ? std::sqrt(sum / static_cast<double>(n)) : std::nan("");
}

struct Run {
  std::unique_ptr<SlamSystem> slam;
  std::vector<Eigen::Isometry3d> est;
  std::vector<double> ms, ms_move, ms_still;
  std::vector<double> occupancy;
  long lost = 0;
};

void report(const char* label, const Setting& s, Run& r, const std::vector<Eigen::Isometry3d>& gt,
            const std::vector<double>& stamps, const std::vector<Eigen::Vector3f>& surface,
            double path_m) {
  emf::io::Trajectory tg, te;
  for (size_t i = 0; i < gt.size(); ++i) {
    tg.append(stamps[i], gt[i]);
    te.append(stamps[i], r.est[i]);
  }
  const emf::eval::AteResult ate = emf::eval::computeAte(tg, te);
  const double drift = driftPerStep(gt, r.est, 1.0);
  MeshStats mesh;
  const std::string ply = (std::filesystem::temp_directory_path() /
                           ("moving_map_bench_" + std::to_string(::getpid()) + ".ply"))
                              .string();
  {
    emf::io::PlyWriter writer(ply, true);
    struct Tee : emf::map::MeshSink {
      emf::map::MeshSink* a;
      emf::map::MeshSink* b;
      void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f* n, size_t c) override {
        a->addVertices(p, n, c);
        b->addVertices(p, n, c);
      }
      void addTriangles(const Eigen::Vector3i* t, size_t c) override {
        a->addTriangles(t, c);
        b->addTriangles(t, c);
      }
    } tee;
    tee.a = &writer;
    tee.b = &mesh;
    r.slam->extractBackgroundMesh(tee);
    writer.commit();
  }
  const double ply_mib = static_cast<double>(std::filesystem::file_size(ply)) / (1 << 20);
  std::filesystem::remove(ply);
  const double cover = emf::eval::coveredFraction(mesh.vertices, surface, 3.0 * s.voxel_m);
  const auto t = emf::pipeline::summarize(r.ms);
  std::printf(
      "moving_map_bench config=%s map=%s frames=%zu lost=%ld path_m=%.2f ate_cm=%.3f "
      "ate_pct_of_path=%.3f drift_cm_per_m=%.3f ms=%.2f p90_ms=%.2f",
      s.text.c_str(), label, gt.size(), r.lost, path_m, ate.trans_m.rmse * 100.0,
      ate.trans_m.rmse / path_m * 100.0, drift * 100.0, t.median_ms, t.p90_ms);
  if (!r.ms_move.empty()) {
    const auto tm = emf::pipeline::summarize(r.ms_move);
    const auto ts = emf::pipeline::summarize(r.ms_still);
    std::printf(
        " moves=%lld evicted_blocks=%lld ms_move_frames=%.2f p90=%.2f max=%.2f "
        "ms_other_frames=%.2f",
        static_cast<long long>(r.slam->backgroundShifts()),
        static_cast<long long>(r.slam->evictedBlocks()), tm.median_ms, tm.p90_ms,
        *std::max_element(r.ms_move.begin(), r.ms_move.end()), ts.median_ms);
  }
  std::printf(" occupancy_pct=");
  for (size_t k = 1; k <= 10; ++k) {
    const size_t i = std::min(r.occupancy.size() - 1, r.occupancy.size() * k / 10 - 1);
    std::printf("%s%.1f", k > 1 ? "," : "", r.occupancy[i] * 100.0);
  }
  std::printf(
      " occupancy_max_pct=%.1f mesh_vertices=%zu mesh_triangles=%zu ply_mib=%.1f "
      "surface_covered_pct=%.1f\n",
      *std::max_element(r.occupancy.begin(), r.occupancy.end()) * 100.0, mesh.vertices.size(),
      mesh.triangles, ply_mib, cover * 100.0);
  std::fflush(stdout);
}

}  // namespace

constexpr const char* kUsage =
    "usage: moving_map_bench [--source URI] [--frames N] "
    "[--configs 640x480@0.01@256,320x240@0.02@64] [--set section.key=value]...\n";

int main(int argc, char** argv) {
  std::string source = "synth:apartment";
  long frames = 0;  // 0 = the whole sequence
  std::vector<Setting> settings;
  std::vector<std::string> sets;
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (args.is("--source")) {
        source = args.value();
      } else if (args.is("--frames")) {
        frames = args.integer(10, 1000000);
      } else if (args.is("--configs")) {
        std::stringstream ss(args.value());
        std::string item;
        while (std::getline(ss, item, ',')) settings.push_back(parseSetting(item));
      } else if (args.is("--set")) {
        sets.push_back(args.value());
      } else {
        args.unknown();
      }
    }
    if (settings.empty()) {
      settings = {parseSetting("640x480@0.01@256"), parseSetting("320x240@0.02@64")};
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "moving_map_bench: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  try {
    for (const Setting& s : settings) {
      emf::Config config;
      config.map.memory_mb = s.memory_mb;
      config.map.background_voxel_m = s.voxel_m;
      // The same 5.12 m region at every voxel size.
      config.map.background_resolution = static_cast<int>(std::lround(5.12 / s.voxel_m));
      for (const auto& a : sets) config.set(a);
      emf::Config fixed = config;
      config.map.follow_camera = true;
      fixed.map.follow_camera = false;
      emf::cl::Context ctx(config.cl);
      const std::string uri = source + (source.find('?') == std::string::npos ? "?" : "&") +
                              "width=" + std::to_string(s.width) +
                              "&height=" + std::to_string(s.height) +
                              (frames > 0 ? "&frames=" + std::to_string(frames) : "");
      auto src = emf::sources::openSource(uri, config.source);
      Run moving, still;
      moving.slam = std::make_unique<SlamSystem>(ctx, config, src->intrinsics());
      still.slam = std::make_unique<SlamSystem>(ctx, fixed, src->intrinsics());
      std::vector<Eigen::Isometry3d> gt;
      std::vector<double> stamps;
      std::vector<Eigen::Vector3f> surface;
      double path_m = 0;
      const emf::core::Intrinsics k = src->intrinsics();
      emf::core::Frame f;
      while (src->next(f)) {
        if (!f.T_world_camera_gt) throw std::runtime_error(uri + ": no ground truth");
        if (!gt.empty())
          path_m += (f.T_world_camera_gt->translation() - gt.back().translation()).norm();
        gt.push_back(*f.T_world_camera_gt);
        stamps.push_back(f.timestamp);
        if (gt.size() % 15 == 1) {
          const int step = std::max(4, k.width / 40);
          for (int y = step / 2; y < k.height; y += step) {
            for (int x = step / 2; x < k.width; x += step) {
              const float z = f.depth.at<float>(y, x);
              if (!(z > 0.0f) || z > 4.0f) continue;
              const Eigen::Vector3d pc((x - k.cx) / k.fx * z, (y - k.cy) / k.fy * z, z);
              surface.push_back((*f.T_world_camera_gt * pc).cast<float>());
            }
          }
        }
        for (Run* r : {&moving, &still}) {
          const auto t0 = std::chrono::steady_clock::now();
          const emf::pipeline::FrameOutcome o = r->slam->process(f);
          const double ms =
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                  .count();
          r->ms.push_back(ms);
          if (r == &moving) (o.map_shift.isZero() ? r->ms_still : r->ms_move).push_back(ms);
          r->lost += o.lost;
          r->est.push_back(o.T_world_camera);
          r->occupancy.push_back(r->slam->pool().stats().occupancy());
        }
      }
      if (gt.size() < 10) throw std::runtime_error(uri + ": fewer than 10 frames");
      // The first camera of the ground truth is the SLAM's world origin.
      const Eigen::Isometry3d T0 = gt.front();
      for (auto& g : gt) g = T0.inverse() * g;
      for (auto& p : surface) p = (T0.inverse() * p.cast<double>()).cast<float>();
      report("moving", s, moving, gt, stamps, surface, path_m);
      report("fixed", s, still, gt, stamps, surface, path_m);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "moving_map_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
