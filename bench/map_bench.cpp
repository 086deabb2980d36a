// map_bench: integration and ray casting speed, memory and mesh accuracy of the map on a real
// sequence with ground-truth poses (default: ../shared/data/redkitchen-0-299).
//
// For each configuration (resolution x voxel size) a fresh pool and background volume fuse every
// frame at its ground-truth pose, then ray cast from the same pose; afterwards the mesh is
// extracted and the ground-truth depth points of every --error-every-th frame (full resolution,
// every 4th pixel, back-projected with the ground-truth pose) are measured against it.
// Prints one table and one machine-readable line per configuration:
//   map_bench res=640x480 voxel_m=0.01 integrate_ms=.. integrate_p90_ms=.. raycast_ms=..
//             raycast_p90_ms=.. blocks=.. bytes_per_voxel=.. pool_mb=.. surface_err_mm=..
// integrate_ms = allocation + integration of one frame (medians unless marked p90; wall time
// with the queue drained); upload of the depth image is reported separately.
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "common/error.h"
#include "common/log.h"
#include "core/frame_source.h"
#include "io/ply.h"
#include "map/device_image.h"
#include "map/mesh.h"
#include "map/mesh_distance.h"
#include "map/raycaster.h"
#include "map/volume.h"
#include "map/volume_host_access.h"
#include "map/voxel_pool.h"
#include "sources/open_source.h"

namespace {

using emf::map::kBlockSize;
using emf::map::kBlockVoxels;
using Clock = std::chrono::steady_clock;

// ---- The sequence, read through sources::openSource("tum:...")
// -----------------------------------
struct BenchFrame {
  double timestamp = 0;
  cv::Mat depth_m;  // CV_32F metres, NaN invalid, full resolution
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
};

struct BenchSequence {
  emf::core::Intrinsics intrinsics;
  std::vector<BenchFrame> frames;
};

/// Frames with ground truth of the TUM folder `dir` (depth scale as given; intrinsics from its
/// calibration.txt), at most `max_frames` (0 = all).
BenchSequence loadTumSequence(const std::string& dir, double depth_scale, int max_frames) {
  emf::core::SourceOptions options;
  options.depth_scale = depth_scale;
  options.max_frames = max_frames > 0 ? max_frames : 0;
  auto source = emf::sources::openSource("tum:" + dir, options);
  BenchSequence seq;
  seq.intrinsics = source->intrinsics();
  emf::core::Frame f;
  while ((max_frames <= 0 || static_cast<int>(seq.frames.size()) < max_frames) && source->next(f)) {
    if (!f.T_world_camera_gt) continue;  // map_bench integrates with ground-truth poses
    BenchFrame b;
    b.timestamp = f.timestamp;
    b.depth_m = f.depth.clone();
    b.T_world_camera = *f.T_world_camera_gt;
    seq.frames.push_back(std::move(b));
  }
  if (seq.frames.empty()) {
    throw emf::IoError(dir + ": no frames with ground-truth poses (map_bench needs them)");
  }
  return seq;
}

/// 2x2 down-sampling of depth: mean of the valid samples within 3 cm of the nearest one, so
/// depth edges are not blended into flying pixels. Pixel centres match Intrinsics::scaled.
cv::Mat halveDepth(const cv::Mat& d) {
  cv::Mat out(d.rows / 2, d.cols / 2, CV_32FC1);
  for (int y = 0; y < out.rows; ++y) {
    for (int x = 0; x < out.cols; ++x) {
      float v[4] = {d.at<float>(2 * y, 2 * x), d.at<float>(2 * y, 2 * x + 1),
                    d.at<float>(2 * y + 1, 2 * x), d.at<float>(2 * y + 1, 2 * x + 1)};
      float lo = std::numeric_limits<float>::infinity();
      for (float s : v) {
        if (!std::isnan(s)) lo = std::min(lo, s);
      }
      float sum = 0;
      int n = 0;
      for (float s : v) {
        if (!std::isnan(s) && s - lo <= 0.03f) {
          sum += s;
          ++n;
        }
      }
      out.at<float>(y, x) =
          n ? sum / static_cast<float>(n) : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return out;
}

struct Config {
  int width, height;
  double voxel_m;
};

struct Result {
  Config config;
  double integrate_ms = 0, integrate_p90_ms = 0, alloc_ms = 0, upload_ms = 0;
  double raycast_ms = 0, raycast_p90_ms = 0;
  double integrate_cpu_ms = 0, raycast_cpu_ms = 0;
  int blocks = 0, frames = 0;
  double bytes_per_voxel = 0, pool_used_mb = 0, pool_mb = 0, index_mb = 0;
  int64_t dropped = 0;
  double surface_err_mm = 0, surface_coverage = 0, mesh_s = 0, mesh_mb = 0;
  double copy_mesh_s = 0, copy_mesh_mb = 0;
  bool mesh_mapped = false;
  size_t mesh_triangles = 0, error_points = 0;
  int raycast_valid_pct = 0;
  int object_blocks = 0;
  double object_bytes_per_voxel = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t i =
      std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

double ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

/// CPU time of the whole process (all PoCL worker threads), ms: on a shared machine this is
/// what the work costs; wall time on an idle 2-core machine is about cpu / 2.
double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

/// A field of /proc/self/status in MiB (VmRSS: resident now; VmHWM: peak since start or since
/// resetPeakRss()), or -1 when it cannot be read.
double procStatusMb(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string key = std::string(field) + ":";
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) == 0) return std::atof(line.c_str() + key.size()) / 1024.0;
  }
  return -1;
}

/// Resets VmHWM to the current RSS (Linux >= 4.0: "5" to /proc/self/clear_refs).
bool resetPeakRss() {
  std::ofstream out("/proc/self/clear_refs");
  out << "5";
  out.flush();
  return static_cast<bool>(out);
}

std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

Result run(emf::cl::Context& ctx, const BenchSequence& seq, const Config& cfg, int memory_mb,
           int error_every, int error_stride, const std::string& ply_dir) {
  Result r;
  r.config = cfg;
  emf::map::MapOptions o;
  o.memory_mb = memory_mb;
  o.background_voxel_m = cfg.voxel_m;
  o.background_resolution = static_cast<int>(std::lround(5.12 / cfg.voxel_m));
  const bool half = cfg.width * 2 == seq.intrinsics.width;
  const emf::core::Intrinsics k =
      half ? seq.intrinsics.scaled(cfg.width, cfg.height) : seq.intrinsics;
  if (k.width != cfg.width || k.height != cfg.height) {
    throw emf::InvalidArgument("map_bench: resolution " + std::to_string(cfg.width) + "x" +
                               std::to_string(cfg.height) + " must be the sequence's or half");
  }
  std::vector<cv::Mat> depth;
  for (const auto& f : seq.frames) depth.push_back(half ? halveDepth(f.depth_m) : f.depth_m);

  const emf::map::VolumeSpec spec = emf::map::VolumeSpec::background(o);
  const Eigen::Isometry3d T_wv =
      emf::map::backgroundVolumePose(o, spec, seq.frames.front().T_world_camera);
  emf::map::DeviceImage image(ctx, k.width, k.height);
  emf::map::RayCaster caster(ctx, o, k.width, k.height);
  emf::map::IntegrationInput in;
  in.depth = &image.buffer();
  in.intrinsics = k;
  {
    // Warm-up on a throwaway volume: PoCL specialises kernels on first launch.
    emf::map::MapOptions wo = o;
    wo.memory_mb = 16;
    emf::map::VoxelPool wpool(ctx, wo);
    emf::map::Volume wvol(wpool, spec, T_wv);
    image.upload(depth.front(), "depth");
    in.T_world_camera = seq.frames.front().T_world_camera;
    wvol.fuse(in);
    caster.render({{&wvol, 0}}, k, in.T_world_camera);
    ctx.finish();
  }
  emf::map::VoxelPool pool(ctx, o);
  emf::map::Volume vol(pool, spec, T_wv);
  std::vector<double> t_int, t_alloc, t_up, t_ray, c_int, c_ray;
  long valid_px = 0;
  cv::Mat rc_depth;
  for (size_t i = 0; i < depth.size(); ++i) {
    in.T_world_camera = seq.frames[i].T_world_camera;
    const auto t0 = Clock::now();
    image.upload(depth[i], "depth");
    ctx.finish();
    const auto t1 = Clock::now();
    const double c1 = cpuMs();
    vol.allocate(in);  // ends with a blocking read of the report
    const auto t2 = Clock::now();
    vol.integrate(in);
    ctx.finish();
    const auto t3 = Clock::now();
    const double c3 = cpuMs();
    caster.render({{&vol, 0}}, k, in.T_world_camera);
    ctx.finish();
    const auto t4 = Clock::now();
    const double c4 = cpuMs();
    c_int.push_back(c3 - c1);
    c_ray.push_back(c4 - c3);
    t_up.push_back(ms(t0, t1));
    t_alloc.push_back(ms(t1, t2));
    t_int.push_back(ms(t1, t3));
    t_ray.push_back(ms(t3, t4));
    if (i + 1 == depth.size()) {
      caster.download(&rc_depth, nullptr, nullptr);
      valid_px = cv::countNonZero(rc_depth == rc_depth);
    }
  }
  r.frames = static_cast<int>(depth.size());
  r.integrate_ms = percentile(t_int, 0.5);
  r.integrate_p90_ms = percentile(t_int, 0.9);
  r.alloc_ms = percentile(t_alloc, 0.5);
  r.upload_ms = percentile(t_up, 0.5);
  r.raycast_ms = percentile(t_ray, 0.5);
  r.raycast_p90_ms = percentile(t_ray, 0.9);
  r.integrate_cpu_ms = percentile(c_int, 0.5);
  r.raycast_cpu_ms = percentile(c_ray, 0.5);
  r.raycast_valid_pct = static_cast<int>(100 * valid_px / std::max(1, k.width * k.height));
  const emf::map::PoolStats ps = pool.stats();
  r.blocks = vol.allocatedBlocks();
  r.dropped = ps.dropped_blocks;
  r.pool_mb = static_cast<double>(ps.pool_bytes) / (1 << 20);
  r.pool_used_mb = static_cast<double>(ps.used_slots) * emf::map::VoxelPool::kSlotBytes / (1 << 20);
  r.index_mb = static_cast<double>(vol.indexBytes()) / (1 << 20);
  r.bytes_per_voxel = r.blocks
                          ? (static_cast<double>(ps.used_slots) * emf::map::VoxelPool::kSlotBytes +
                             static_cast<double>(vol.indexBytes())) /
                                (static_cast<double>(r.blocks) * kBlockVoxels)
                          : 0;

  {
    // An object volume (64^3 voxels, 1.5 m in front of the first camera) fused on every 10th
    // frame with a detection mask of p_fg = 0.5: measures object storage (TSDF + counts).
    emf::map::VolumeSpec ospec =
        emf::map::VolumeSpec::object(o, 64, static_cast<float>(cfg.voxel_m));
    Eigen::Isometry3d T_wo = seq.frames.front().T_world_camera;
    T_wo.translation() =
        T_wo * Eigen::Vector3d(0, 0, 1.5) - T_wo.linear() * ospec.extentM().cast<double>() / 2;
    emf::map::Volume object(pool, ospec, T_wo);
    const cv::Mat half_mask(k.height, k.width, CV_32FC1, cv::Scalar(0.5f));
    emf::map::DeviceImage mask(ctx, k.width, k.height);
    mask.upload(half_mask, "mask");
    emf::map::IntegrationInput oin = in;
    oin.fg_mask = &mask.buffer();
    for (size_t i = 0; i < depth.size(); i += 10) {
      image.upload(depth[i], "depth");
      oin.T_world_camera = seq.frames[i].T_world_camera;
      object.fuse(oin);
    }
    r.object_blocks = object.allocatedBlocks();
    r.object_bytes_per_voxel = r.object_blocks
                                   ? (2.0 * r.object_blocks * emf::map::VoxelPool::kSlotBytes +
                                      static_cast<double>(object.indexBytes())) /
                                         (static_cast<double>(r.object_blocks) * kBlockVoxels)
                                   : 0;
  }

  // The mesh written to a PLY file two ways, one after the other, each measured by its time and
  // the resident memory it adds (peak RSS during it, reset right before, minus the RSS before;
  // freed heap returned to the system in between):
  //  - stream (what emf run and emf_system_save_mesh do): the volume mapped on a CPU
  //    device (downloaded otherwise), the mesh streamed into the file one block layer at a time;
  //  - copy (the reference: emf before streaming): the volume downloaded, the mesh built in
  //    memory, then written. Its mesh is kept for the reconstruction error below.
  char name[128];
  std::snprintf(name, sizeof(name), "/map_bench_%dx%d_%gcm", cfg.width, cfg.height,
                cfg.voxel_m * 100);
  const std::string ply_base = ply_dir + name;
  auto measure = [&](double* seconds, double* mb, const auto& work) {
    malloc_trim(0);
    const bool peak_reset = resetPeakRss();
    const double rss_before_mb = procStatusMb("VmRSS");
    const auto t0 = Clock::now();
    work();
    *seconds = ms(t0, Clock::now()) / 1000;
    *mb = peak_reset && rss_before_mb >= 0 ? procStatusMb("VmHWM") - rss_before_mb : -1;
  };
  size_t streamed_triangles = 0;
  measure(&r.mesh_s, &r.mesh_mb, [&]() {
    const emf::map::VolumeHostAccess access(vol);
    r.mesh_mapped = access.mapped();
    emf::io::PlyWriter ply(ply_base + ".ply", true);
    emf::map::extractMesh(access.view(), access.T_world_volume(), emf::map::MeshOptions(), ply);
    ply.commit();
    streamed_triangles = ply.triangleCount();
  });
  emf::map::Mesh mesh;
  measure(&r.copy_mesh_s, &r.copy_mesh_mb, [&]() {
    const emf::map::VolumeHostAccess access = emf::map::VolumeHostAccess::downloaded(vol);
    mesh = emf::map::extractMesh(access.view(), access.T_world_volume());
    emf::io::writePly(ply_base + "_copy.ply", mesh, true);
  });
  r.mesh_triangles = mesh.triangles.size();
  if (streamed_triangles != mesh.triangles.size()) {
    throw std::runtime_error("streamed mesh has " + std::to_string(streamed_triangles) +
                             " triangles, the in-memory one " +
                             std::to_string(mesh.triangles.size()));
  }
  constexpr float kMaxDistM = 0.1f;
  const emf::map::MeshDistance md(mesh, 0.02f);
  const Eigen::Vector3d ext = spec.extentM().cast<double>();
  double sum = 0;
  size_t found = 0, total = 0;
  const emf::core::Intrinsics& kf = seq.intrinsics;
  for (size_t i = 0; i < seq.frames.size(); i += static_cast<size_t>(error_every)) {
    const BenchFrame& f = seq.frames[i];
    for (int y = error_stride / 2; y < f.depth_m.rows; y += error_stride) {
      for (int x = error_stride / 2; x < f.depth_m.cols; x += error_stride) {
        const float d = f.depth_m.at<float>(y, x);
        if (std::isnan(d)) continue;
        const Eigen::Vector3d pc((x - kf.cx) / kf.fx * d, (y - kf.cy) / kf.fy * d, d);
        const Eigen::Vector3d pw = f.T_world_camera * pc;
        const Eigen::Vector3d pv = T_wv.inverse() * pw;
        if ((pv.array() < 0).any() || (pv.array() > ext.array()).any()) continue;
        ++total;
        const float dist = md.distance(pw.cast<float>(), kMaxDistM);
        if (dist <= kMaxDistM) {
          sum += dist;
          ++found;
        }
      }
    }
  }
  r.error_points = total;
  r.surface_err_mm = found ? 1000.0 * sum / static_cast<double>(found) : 0;
  r.surface_coverage = total ? static_cast<double>(found) / static_cast<double>(total) : 0;
  return r;
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: map_bench [--data DIR] [--frames N] [--configs WxH@VOXEL_M,...]\n"
               "                 [--memory-mb MB] [--error-every K] [--error-stride P]\n"
               "                 [--depth-scale S]\n"
               "                 [--mesh-dir DIR]\n"
               "  --data         TUM-layout folder with associations.txt, groundtruth.txt\n"
               "                 (default ../shared/data/redkitchen-0-299)\n"
               "  --frames       frames to use (default all)\n"
               "  --configs      default 640x480@0.01,640x480@0.02,320x240@0.01,320x240@0.02\n"
               "  --memory-mb    voxel pool budget (default 256)\n"
               "  --error-every  measure mesh error on every K-th frame (default 30)\n"
               "  --error-stride ... on every P-th pixel in x and y (default 4)\n"
               "  --depth-scale  depth PNG units per metre (default 1000, 7-Scenes)\n"
               "  --mesh-dir     also write each mesh as binary PLY there\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::string data = std::string(EMF_SOURCE_DIR) + "/../shared/data/redkitchen-0-299";
  std::string configs = "640x480@0.01,640x480@0.02,320x240@0.01,320x240@0.02";
  std::string mesh_dir;
  int frames = 0, memory_mb = 256, error_every = 30, error_stride = 4;
  double depth_scale = 1000;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw emf::bench::UsageError(a + " needs a value");
        return argv[++i];
      };
      if (a == "--help" || a == "-h") {
        usage(stdout);
        return 0;
      } else if (a == "--data") {
        data = value();
      } else if (a == "--frames") {
        frames = static_cast<int>(emf::bench::parseInteger(a, value(), 0, 1000000));
      } else if (a == "--configs") {
        configs = value();
      } else if (a == "--memory-mb") {
        memory_mb = static_cast<int>(emf::bench::parseInteger(a, value(), 1, 1 << 20));
      } else if (a == "--error-every") {
        error_every = static_cast<int>(emf::bench::parseInteger(a, value(), 1, 1000000));
      } else if (a == "--error-stride") {
        error_stride = static_cast<int>(emf::bench::parseInteger(a, value(), 1, 4096));
      } else if (a == "--depth-scale") {
        depth_scale = emf::bench::parseReal(a, value(), 1e-6, 1e9);
      } else if (a == "--mesh-dir") {
        mesh_dir = value();
      } else {
        std::fprintf(stderr, "map_bench: unknown option '%s'\n", a.c_str());
        usage(stderr);
        return 2;
      }
    }
    std::vector<Config> cfgs;
    std::stringstream cs(configs);
    std::string item;
    while (std::getline(cs, item, ',')) {
      Config c{};
      if (std::sscanf(item.c_str(), "%dx%d@%lf", &c.width, &c.height, &c.voxel_m) != 3 ||
          c.voxel_m <= 0) {
        std::fprintf(stderr, "map_bench: bad configuration '%s' (expected WxH@VOXEL_M)\n",
                     item.c_str());
        return 2;
      }
      cfgs.push_back(c);
    }
    emf::setLogLevel(emf::LogLevel::kWarning);
    const BenchSequence seq = loadTumSequence(data, depth_scale, frames);
    if (seq.frames.empty()) throw emf::IoError(data + ": no frames with ground-truth poses");
    emf::cl::Context ctx{emf::cl::ClOptions{}};
    std::printf("map_bench: %s, %zu frames; device %s; load average before: %s\n", data.c_str(),
                seq.frames.size(), ctx.describe().c_str(), loadAverage().c_str());
    std::vector<Result> results;
    // The PLY files go to --mesh-dir, else to a temporary folder removed at the end.
    const bool temp_ply_dir = mesh_dir.empty();
    const std::string ply_dir = temp_ply_dir
                                    ? (std::filesystem::temp_directory_path() /
                                       ("map_bench-" + std::to_string(static_cast<long>(getpid()))))
                                          .string()
                                    : mesh_dir;
    std::filesystem::create_directories(ply_dir);
    struct RemoveTemp {
      bool active;
      std::string dir;
      ~RemoveTemp() {
        std::error_code ec;
        if (active) std::filesystem::remove_all(dir, ec);
      }
    } remove_temp{temp_ply_dir, ply_dir};
    for (const Config& c : cfgs) {
      results.push_back(run(ctx, seq, c, memory_mb, error_every, error_stride, ply_dir));
    }
    std::printf("load average after: %s\n\n", loadAverage().c_str());
    std::printf(
        "%-9s %6s | %8s %8s %8s %8s %7s | %8s %8s %8s %5s | %7s %7s %7s %6s %6s | %8s %6s %9s "
        "%6s %7s %6s %7s\n",
        "res", "voxel", "integ", "int_p90", "int_cpu", "alloc", "upload", "raycast", "rc_p90",
        "rc_cpu", "rc_px", "blocks", "used_MB", "pool_MB", "idx_MB", "B/vox", "err_mm", "cover",
        "triangles", "mesh_s", "mesh_MB", "copy_s", "copy_MB");
    for (const Result& r : results) {
      char res[32];
      std::snprintf(res, sizeof(res), "%dx%d", r.config.width, r.config.height);
      std::printf(
          "%-9s %5.0fcm | %8.2f %8.2f %8.2f %8.2f %7.2f | %8.2f %8.2f %8.2f %4d%% | %7d %7.1f "
          "%7.0f %6.2f %6.2f | %8.2f %5.1f%% %9zu %6.2f %7.1f %6.2f %7.1f\n",
          res, r.config.voxel_m * 100, r.integrate_ms, r.integrate_p90_ms, r.integrate_cpu_ms,
          r.alloc_ms, r.upload_ms, r.raycast_ms, r.raycast_p90_ms, r.raycast_cpu_ms,
          r.raycast_valid_pct, r.blocks, r.pool_used_mb, r.pool_mb, r.index_mb, r.bytes_per_voxel,
          r.surface_err_mm, 100 * r.surface_coverage, r.mesh_triangles, r.mesh_s, r.mesh_mb,
          r.copy_mesh_s, r.copy_mesh_mb);
      if (r.dropped > 0) {
        std::printf("  ^ pool exhausted: %lld block allocations dropped\n",
                    static_cast<long long>(r.dropped));
      }
    }
    std::printf(
        "\ninteg = allocate + integrate per frame (median wall ms; p90), int_cpu = CPU time of "
        "all threads for it (median ms;\nan idle 2-core machine needs about half of it as wall "
        "time), alloc = its allocation part, upload = depth upload;\nraycast per frame from the "
        "same pose (rc_cpu: CPU time); rc_px = pixels with "
        "a surface (last frame); B/vox = (used slots + index grid) / allocated voxels;\n"
        "err_mm = mean distance of ground-truth depth points (every %d-th frame, every %d-th "
        "pixel) to the mesh, over the cover share within 10 cm;\nmesh_s / mesh_MB = time and "
        "resident memory (peak RSS during it minus RSS before) of writing the mesh as PLY the "
        "way emf does:\nvolume mapped (%s), mesh streamed into the file; copy_s / copy_MB: "
        "the reference, volume downloaded, mesh built\nin memory, then written.\n",
        error_every, error_stride,
        results.empty() || results[0].mesh_mapped ? "CPU device: no copy"
                                                  : "not a CPU device: downloaded");
    for (const Result& r : results) {
      std::printf(
          "object volume %dx%d @ %gcm: %d blocks, %.2f bytes per voxel (TSDF + Fg/Bg "
          "counts + index)\n",
          r.config.width, r.config.height, r.config.voxel_m * 100, r.object_blocks,
          r.object_bytes_per_voxel);
    }
    std::printf("\n");
    for (const Result& r : results) {
      std::printf(
          "map_bench res=%dx%d voxel_m=%g integrate_ms=%.2f integrate_p90_ms=%.2f "
          "raycast_ms=%.2f raycast_p90_ms=%.2f blocks=%d bytes_per_voxel=%.2f pool_mb=%.1f "
          "surface_err_mm=%.2f mesh_s=%.2f mesh_mb=%.1f copy_mesh_s=%.2f copy_mesh_mb=%.1f\n",
          r.config.width, r.config.height, r.config.voxel_m, r.integrate_ms, r.integrate_p90_ms,
          r.raycast_ms, r.raycast_p90_ms, r.blocks, r.bytes_per_voxel, r.pool_used_mb,
          r.surface_err_mm, r.mesh_s, r.mesh_mb, r.copy_mesh_s, r.copy_mesh_mb);
    }
    return 0;
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "map_bench: %s\n", e.what());
    usage(stderr);
    return emf::bench::kExitUsage;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "map_bench: %s\n", e.what());
    return 1;
  }
}
