// track_bias: the camera tracker's systematic error against a map built at ground-truth poses.
//
// Every frame of a TUM folder with ground truth is first tracked against the background volume,
// starting from the constant-velocity prediction of the two previous ground-truth poses, and
// then integrated at its ground-truth pose (so the map never carries a tracking error). The
// tracked pose's deviation from the ground truth, in the camera frame, is a per-frame tracking
// error with a perfect history; its mean over the frames is the tracker's bias on this data.
// --reverse plays the frames backwards (the camera moves the other way through the same
// views): a bias that flips sign with it follows the motion, not the scene. --track-data tracks
// the frames of a second folder with the same poses (e.g. the same `emf synth` preset with
// --no-noise) against the map fused from --data: noise in the map and in the frames apart.
//
//   track_bias --data DIR [--track-data DIR2] [--frames N] [--reverse] [--depth-scale S]
//              [--set SECTION.KEY=VALUE]... [--per-frame] [--decompose] [--prefuse]
//              [--start-at-gt]
//
// Two controls: --prefuse fuses every frame first and then tracks each against the finished
// map (a map that already holds the views ahead of the camera; the frame's own view is in it
// too), and --start-at-gt starts each frame's tracking at its ground truth instead of the
// prediction (a deviation that stays is where the cost has its minimum, not slow convergence).
//
// --set overrides a configuration default (e.g. preprocess.hole_margin_px=1). --decompose adds,
// per pixel class (next to a hole on the background or foreground side of an edge, or inside a
// surface; all others; see classify), the first-order pose shift -H^-1 g_class at the ground
// truth: which pixels pull the pose.
// Prints the mean and standard deviation of the deviation (mm, degrees about the camera's
// axes), the mean ground-truth motion per frame, and one line
//   track_bias data=.. frames=.. reverse=0|1 bias_mm=x,y,z bias_deg=x,y,z motion_mm=x,y,z
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "common/config.h"
#include "common/error.h"
#include "io/frame_source.h"
#include "map/device_image.h"
#include "map/volume.h"
#include "map/voxel_pool.h"
#include "pipeline/slam_system.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace {

struct Args {
  std::string data;
  std::string track_data;  // optional: the frames to track come from here (same poses)
  int frames = 0;
  bool reverse = false;
  bool per_frame = false;
  bool decompose = false;
  bool prefuse = false;      // fuse every frame first, then track each against the finished map
  bool start_at_gt = false;  // start tracking at the ground truth, not the prediction
  double depth_scale = 0.0;  // 0: the source's default
  std::vector<std::string> sets;  // section.key=value overrides of the defaults
};

const char* const kUsage =
    "usage: track_bias --data DIR [--track-data DIR2] [--frames N] [--reverse] [--depth-scale S]\n"
    "                  [--set SECTION.KEY=VALUE]... [--per-frame] [--decompose] [--prefuse]\n"
    "                  [--start-at-gt]\n";

Args parse(int argc, char** argv) {
  Args a;
  emf::bench::ArgWalker args(argc, argv);
  while (args.next()) {
    if (args.is("--help") || args.is("-h")) {
      std::printf("%s", kUsage);
      std::exit(0);
    } else if (args.is("--reverse")) {
      a.reverse = true;
    } else if (args.is("--per-frame")) {
      a.per_frame = true;
    } else if (args.is("--decompose")) {
      a.decompose = true;
    } else if (args.is("--prefuse")) {
      a.prefuse = true;
    } else if (args.is("--start-at-gt")) {
      a.start_at_gt = true;
    } else if (args.is("--data")) {
      a.data = args.value();
    } else if (args.is("--track-data")) {
      a.track_data = args.value();
    } else if (args.is("--frames")) {
      a.frames = static_cast<int>(args.integer(0, 10000000));
    } else if (args.is("--depth-scale")) {
      a.depth_scale = args.real(0.0, 1e9);
    } else if (args.is("--set")) {
      a.sets.push_back(args.value());
    } else {
      args.unknown();
    }
  }
  if (a.data.empty()) {
    throw emf::bench::UsageError("--data DIR is required (a TUM folder with groundtruth.txt)");
  }
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

/// Pixel classes of --decompose, from a depth image. A pixel within 1 px (8-neighbourhood) of a
/// pixel without depth is "next to a hole"; of those, class 0 has a valid pixel more than 5 %
/// nearer within 3 px (the background side of an edge), class 1 one more than 5 % farther (the
/// foreground side), class 2 neither (dropouts inside a surface). Class 3: every other pixel.
constexpr int kClasses = 4;
const char* const kClassNames[kClasses] = {"hole, background side", "hole, foreground side",
                                           "hole, no jump near", "other"};

cv::Mat classify(const cv::Mat& depth) {
  cv::Mat hole(depth.size(), CV_8U, cv::Scalar(0));
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      if (!(depth.at<float>(v, u) > 0.0f)) hole.at<uint8_t>(v, u) = 255;
    }
  }
  cv::Mat near_hole;
  cv::dilate(hole, near_hole, cv::Mat::ones(3, 3, CV_8U));
  cv::Mat classes(depth.size(), CV_8U, cv::Scalar(3));
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (!near_hole.at<uint8_t>(v, u) || !(z > 0.0f)) continue;
      bool nearer = false, farther = false;
      for (int vv = std::max(0, v - 3); vv <= std::min(depth.rows - 1, v + 3); ++vv) {
        for (int uu = std::max(0, u - 3); uu <= std::min(depth.cols - 1, u + 3); ++uu) {
          const float zn = depth.at<float>(vv, uu);
          if (!(zn > 0.0f)) continue;
          nearer = nearer || zn < 0.95f * z;
          farther = farther || zn > 1.05f * z;
        }
      }
      classes.at<uint8_t>(v, u) = nearer ? 0 : (farther ? 1 : 2);
    }
  }
  return classes;
}

}  // namespace

int main(int argc, char** argv) {
  Args parsed;
  try {
    parsed = parse(argc, argv);
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "track_bias: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  const Args& args = parsed;
  try {
    emf::Config config;
    if (args.depth_scale > 0) config.source.depth_scale = args.depth_scale;
    for (const auto& assignment : args.sets) config.set(assignment);
    const auto load = [&](const std::string& dir, emf::io::Intrinsics* k) {
      auto source = emf::io::openSource("tum:" + dir, config.source);
      *k = source->intrinsics();
      std::vector<emf::io::Frame> frames;
      emf::io::Frame f;
      while ((args.frames <= 0 || static_cast<int>(frames.size()) < args.frames) &&
             source->next(f)) {
        if (!f.T_world_camera_gt) {
          throw emf::IoError(dir + ": frame " + std::to_string(f.index) +
                             " has no ground-truth pose (groundtruth.txt must cover every frame)");
        }
        // Only what the bench reads is kept (300 frames of 640x480 depth: 370 MB).
        emf::io::Frame kept;
        kept.index = f.index;
        kept.timestamp = f.timestamp;
        kept.depth = f.depth.clone();
        kept.T_world_camera_gt = f.T_world_camera_gt;
        frames.push_back(std::move(kept));
      }
      if (frames.size() < 3) throw emf::IoError(dir + ": fewer than 3 frames");
      if (args.reverse) std::reverse(frames.begin(), frames.end());
      return frames;
    };
    emf::io::Intrinsics k;
    const std::vector<emf::io::Frame> frames = load(args.data, &k);
    std::vector<emf::io::Frame> tracked_frames;
    if (!args.track_data.empty()) {
      emf::io::Intrinsics k2;
      tracked_frames = load(args.track_data, &k2);
      if (k2.width != k.width || k2.height != k.height || tracked_frames.size() != frames.size()) {
        throw emf::IoError(args.track_data + ": not the same frame count and size as " + args.data);
      }
      for (size_t i = 0; i < frames.size(); ++i) {
        if (std::abs(tracked_frames[i].timestamp - frames[i].timestamp) > 1e-3) {
          throw emf::IoError(args.track_data + ": frame " + std::to_string(i) +
                             " has another timestamp than in " + args.data);
        }
      }
    }
    const std::vector<emf::io::Frame>& track_frames =
        tracked_frames.empty() ? frames : tracked_frames;

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
    // --decompose: per pixel class, the first-order pose shift -H^-1 g_class at the ground truth
    // (H of all pixels), i.e. what each class contributes to the deviation.
    emf::map::DeviceImage q_image(ctx, k.width, k.height);
    std::vector<Stats> class_stats(kClasses);
    const auto fuse = [&](size_t i) {
      if (!tracked_frames.empty() || args.prefuse) pre.process(frames[i].depth);
      emf::map::IntegrationInput in;
      in.depth = &pre.inputDepth();
      in.intrinsics = k;
      in.T_world_camera = *frames[i].T_world_camera_gt;
      volume.fuse(in);
    };
    if (args.prefuse) {
      for (size_t i = 0; i < frames.size(); ++i) fuse(i);
    }
    for (size_t i = 0; i < frames.size(); ++i) {
      pre.process(track_frames[i].depth);
      const Eigen::Isometry3d& G = *frames[i].T_world_camera_gt;
      if (i >= 2) {
        const Eigen::Isometry3d& G1 = *frames[i - 1].T_world_camera_gt;
        const Eigen::Isometry3d& G2 = *frames[i - 2].T_world_camera_gt;
        const Eigen::Isometry3d predicted =
            args.start_at_gt ? G : Eigen::Isometry3d(G1 * (G2.inverse() * G1));
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
          if (args.decompose) {
            const Eigen::Isometry3d T_gt = T_wv.inverse() * G;
            const cv::Mat classes = classify(frames[i].depth);
            const int stride = config.track.pixel_stride;
            const emf::track::NormalEquations all = tracker.evaluate(
                emf::pipeline::deviceView(volume), pre.vertexMap().get(), nullptr, T_gt, stride);
            for (int c = 0; c < kClasses; ++c) {
              cv::Mat q;
              cv::compare(classes, c, q, cv::CMP_EQ);
              q.convertTo(q, CV_32F, 1.0 / 255.0);
              q_image.upload(q, "class mask");
              const emf::track::NormalEquations part =
                  tracker.evaluate(emf::pipeline::deviceView(volume), pre.vertexMap().get(),
                                   q_image.buffer().get(), T_gt, stride);
              // Increment (v, w) of the volume-frame pose, left-multiplied: T = exp(x) T_gt.
              const emf::track::Vector6d x = -all.H.ldlt().solve(part.g);
              Eigen::Isometry3d inc = Eigen::Isometry3d::Identity();
              inc.linear() = Eigen::AngleAxisd(x.tail<3>().norm(), x.tail<3>().norm() > 0
                                                                       ? x.tail<3>().normalized()
                                                                       : Eigen::Vector3d::UnitX())
                                 .toRotationMatrix();
              inc.translation() = x.head<3>();
              const Eigen::Isometry3d shift = T_gt.inverse() * inc * T_gt;
              Eigen::Matrix<double, 9, 1> cv_;
              cv_ << shift.translation() * 1000.0, rotationDeg(shift.rotation()),
                  Eigen::Vector3d(part.valid, 0, 0);
              class_stats[static_cast<size_t>(c)].add(cv_);
            }
          }
          if (args.per_frame) {
            std::printf("frame %zu dev_mm %+.3f %+.3f %+.3f dev_deg %+.4f %+.4f %+.4f\n", i, v[0],
                        v[1], v[2], v[3], v[4], v[5]);
          }
        }
      }
      if (!args.prefuse) fuse(i);
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
    if (args.decompose) {
      for (int c = 0; c < kClasses; ++c) {
        const Stats& cs = class_stats[static_cast<size_t>(c)];
        std::printf(
            "  first-order shift from %-20s (%6.0f px): %+7.3f %+7.3f %+7.3f mm  %+.4f %+.4f %+.4f "
            "deg\n",
            kClassNames[c], cs.mean(6), cs.mean(0), cs.mean(1), cs.mean(2), cs.mean(3), cs.mean(4),
            cs.mean(5));
      }
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
