// track_bias: the camera tracker's systematic error against a map built at ground-truth poses.
//
// Every frame of a TUM folder with ground truth is first tracked against the background volume,
// starting from the constant-velocity prediction of the two previous ground-truth poses, and
// then integrated at its ground-truth pose (so the map never carries a tracking error). The
// tracked pose's deviation from the ground truth, in the camera frame, is a per-frame tracking
// error with a perfect history; its mean over the frames is the tracker's bias on this data.
// --reverse plays the frames backwards (the camera moves the other way through the same
// views): a bias that flips sign with it follows the motion, not the scene.
//
//   track_bias --data DIR [--frames N] [--reverse] [--depth-scale S] [--truncation-voxels T]
//              [--huber F] [--per-frame]
//
// Prints the mean and standard deviation of the deviation (mm, degrees about the camera's
// axes), the mean ground-truth motion per frame, and one line
//   track_bias data=.. frames=.. reverse=0|1 bias_mm=x,y,z bias_deg=x,y,z motion_mm=x,y,z
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "cl/context.h"
#include "common/config.h"
#include "common/error.h"
#include "io/frame_source.h"
#include "map/volume.h"
#include "map/voxel_pool.h"
#include "pipeline/slam_system.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace {

struct Args {
  std::string data;
  int frames = 0;
  bool reverse = false;
  bool per_frame = false;
  double depth_scale = 0.0;  // 0: the source's default
  int truncation_voxels = 0;
  double huber = 0.0;
};

[[noreturn]] void usage(const std::string& message) {
  std::cerr << "track_bias: " << message
            << "\nusage: track_bias --data DIR [--frames N] [--reverse] [--depth-scale S] "
               "[--truncation-voxels T] [--huber F] [--per-frame]\n";
  std::exit(2);
}

double number(const std::string& option, const char* text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || v < 0) {
    usage(option + " " + text + ": expected a non-negative number");
  }
  return v;
}

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string o = argv[i];
    const bool has_value = i + 1 < argc;
    if (o == "--reverse") {
      a.reverse = true;
    } else if (o == "--per-frame") {
      a.per_frame = true;
    } else if (o == "--data" && has_value) {
      a.data = argv[++i];
    } else if (o == "--frames" && has_value) {
      a.frames = static_cast<int>(number(o, argv[++i]));
    } else if (o == "--depth-scale" && has_value) {
      a.depth_scale = number(o, argv[++i]);
    } else if (o == "--truncation-voxels" && has_value) {
      a.truncation_voxels = static_cast<int>(number(o, argv[++i]));
    } else if (o == "--huber" && has_value) {
      a.huber = number(o, argv[++i]);
    } else if (o == "--help" || o == "-h") {
      usage("help");
    } else {
      usage("unknown argument or missing value: '" + o + "'");
    }
  }
  if (a.data.empty()) usage("--data DIR is required (a TUM folder with groundtruth.txt)");
  return a;
}

/// Rotation vector of R in degrees.
Eigen::Vector3d rotationDeg(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis() * 180.0 / M_PI;
}

struct Stats {
  Eigen::Matrix<double, 9, 1> sum = Eigen::Matrix<double, 9, 1>::Zero();
  Eigen::Matrix<double, 9, 1> sq = Eigen::Matrix<double, 9, 1>::Zero();
  int n = 0;
  void add(const Eigen::Matrix<double, 9, 1>& v) {
    sum += v;
    sq += v.cwiseProduct(v);
    ++n;
  }
  double mean(int k) const { return sum[k] / n; }
  double sd(int k) const { return std::sqrt(std::max(0.0, sq[k] / n - mean(k) * mean(k))); }
};

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  try {
    emf::Config config;
    if (args.depth_scale > 0) config.source.depth_scale = args.depth_scale;
    if (args.truncation_voxels > 0) config.map.truncation_voxels = args.truncation_voxels;
    if (args.huber > 0) config.track.huber_truncation_factor = args.huber;
    auto source = emf::io::openSource("tum:" + args.data, config.source);
    const emf::io::Intrinsics k = source->intrinsics();
    std::vector<emf::io::Frame> frames;
    emf::io::Frame f;
    while ((args.frames <= 0 || static_cast<int>(frames.size()) < args.frames) && source->next(f)) {
      if (!f.T_world_camera_gt) {
        throw emf::IoError(args.data + ": frame " + std::to_string(f.index) +
                           " has no ground-truth pose (groundtruth.txt must cover every frame)");
      }
      frames.push_back(f);
      frames.back().depth = f.depth.clone();
    }
    if (frames.size() < 3) throw emf::IoError(args.data + ": fewer than 3 frames");
    if (args.reverse) std::reverse(frames.begin(), frames.end());

    emf::cl::Context ctx{config.cl};
    emf::map::VoxelPool pool(ctx, config.map);
    const emf::map::VolumeSpec spec = emf::map::VolumeSpec::background(config.map);
    const Eigen::Isometry3d T_wv =
        emf::map::backgroundVolumePose(config.map, spec, *frames.front().T_world_camera_gt);
    emf::map::Volume volume(pool, spec, T_wv);
    emf::track::Preprocessor pre(ctx, config.preprocess, k);
    emf::track::Tracker tracker(ctx, config.track, k.width, k.height);

    Stats stats;
    int lost = 0;
    for (size_t i = 0; i < frames.size(); ++i) {
      pre.process(frames[i].depth);
      const Eigen::Isometry3d& G = *frames[i].T_world_camera_gt;
      if (i >= 2) {
        const Eigen::Isometry3d& G1 = *frames[i - 1].T_world_camera_gt;
        const Eigen::Isometry3d& G2 = *frames[i - 2].T_world_camera_gt;
        const Eigen::Isometry3d predicted = G1 * (G2.inverse() * G1);
        const emf::track::TrackResult r =
            tracker.track(emf::pipeline::deviceView(volume), pre.vertexMap().get(), nullptr,
                          T_wv.inverse() * predicted);
        if (r.lost) {
          ++lost;
        } else {
          const Eigen::Isometry3d d = G.inverse() * (T_wv * r.T_volume_camera);
          const Eigen::Isometry3d m = G1.inverse() * G;
          Eigen::Matrix<double, 9, 1> v;
          v << d.translation() * 1000.0, rotationDeg(d.rotation()), m.translation() * 1000.0;
          stats.add(v);
          if (args.per_frame) {
            std::printf("frame %zu dev_mm %+.3f %+.3f %+.3f dev_deg %+.4f %+.4f %+.4f\n", i, v[0],
                        v[1], v[2], v[3], v[4], v[5]);
          }
        }
      }
      emf::map::IntegrationInput in;
      in.depth = &pre.inputDepth();
      in.intrinsics = k;
      in.T_world_camera = G;
      volume.fuse(in);
    }
    if (stats.n == 0) throw emf::IoError("track_bias: every frame was lost");
    std::printf("%s, %d frames%s (%d tracked, %d lost), %dx%d\n", args.data.c_str(),
                static_cast<int>(frames.size()), args.reverse ? " reversed" : "", stats.n, lost,
                k.width, k.height);
    const char* names[6] = {"x mm", "y mm", "z mm", "about x deg", "about y deg", "about z deg"};
    for (int c = 0; c < 6; ++c) {
      std::printf("  deviation %-12s mean %+8.4f  sd %7.4f\n", names[c], stats.mean(c),
                  stats.sd(c));
    }
    std::printf("  ground-truth motion per frame (mm, camera frame): %+.3f %+.3f %+.3f\n",
                stats.mean(6), stats.mean(7), stats.mean(8));
    std::printf(
        "track_bias data=%s frames=%d reverse=%d bias_mm=%.3f,%.3f,%.3f bias_deg=%.4f,%.4f,%.4f "
        "motion_mm=%.3f,%.3f,%.3f\n",
        args.data.c_str(), static_cast<int>(frames.size()), args.reverse ? 1 : 0, stats.mean(0),
        stats.mean(1), stats.mean(2), stats.mean(3), stats.mean(4), stats.mean(5), stats.mean(6),
        stats.mean(7), stats.mean(8));
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "track_bias: " << e.what() << "\n";
    return 1;
  }
}
