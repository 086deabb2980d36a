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
//              [--start-at-gt] [--object K] [--fuse-tracked]
//
// Two controls: --prefuse fuses every frame first and then tracks each against the finished
// map (a map that already holds the views ahead of the camera; the frame's own view is in it
// too), and --start-at-gt starts each frame's tracking at its ground truth instead of the
// prediction (a deviation that stays is where the cost has its minimum, not slow convergence).
//
// --object K tracks object K of a synthetic source (--data synth:<preset>?frames=N&...) instead
// of the camera: each frame keeps only the object's rendered pixels (exact instance ids), its
// ground truth is the camera pose in the object's frame, the volume is placed and truncated as
// the pipeline places a new object (from the first frame's points), and the objects' depth
// filter and tracking options apply. With a perfect history and exact association, the per-frame
// error is what the frames themselves allow the object tracker (the floor under emf's object
// ATE); frames where the object covers fewer than objects.invisible_min_px (scaled to the image)
// pixels are neither tracked nor fused.
//
// --fuse-tracked gives up the perfect history: every frame after the first two is fused at its
// tracked pose (the prediction when lost) and predicted from the two previous such poses, as
// the pipeline does; the gap to the default run is what the history's drift costs.
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
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "common/error.h"
#include "core/frame_source.h"
#include "em/object_rules.h"
#include "eval/eval.h"
#include "map/device_image.h"
#include "map/volume.h"
#include "map/voxel_pool.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"
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
  bool prefuse = false;       // fuse every frame first, then track each against the finished map
  bool start_at_gt = false;   // start tracking at the ground truth, not the prediction
  int object = 0;             // > 0: track this object of a synth: source, not the camera
  bool fuse_tracked = false;  // fuse each frame at its tracked pose, predict from those
  double depth_scale = 0.0;   // 0: the source's default
  std::vector<std::string> sets;  // section.key=value overrides of the defaults
};

const char* const kUsage =
    "usage: track_bias --data DIR [--track-data DIR2] [--frames N] [--reverse] [--depth-scale S]\n"
    "                  [--set SECTION.KEY=VALUE]... [--per-frame] [--decompose] [--prefuse]\n"
    "                  [--start-at-gt] [--object K] [--fuse-tracked]\n"
    "  DIR: a TUM folder, or synth:<preset>[?frames=N&seed=S&width=W&height=H] (--object)\n";

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
    } else if (args.is("--fuse-tracked")) {
      a.fuse_tracked = true;
    } else if (args.is("--object")) {
      a.object = static_cast<int>(args.integer(1, 65535));
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
  if (a.fuse_tracked && (a.prefuse || a.start_at_gt)) {
    throw emf::bench::UsageError("--fuse-tracked excludes --prefuse and --start-at-gt");
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

/// --object: `kept` gets only object `id`'s pixels of `f` (NaN elsewhere; no depth at all when
/// fewer than `min_px` have a measurement) and, as its ground truth, the camera pose in the
/// object's frame.
void keepObjectOnly(const emf::core::Frame& f, int id, const std::string& data, int min_px,
                    emf::core::Frame* kept) {
  const auto pose = f.T_world_object_gt.find(id);
  if (f.instance_ids.empty() || pose == f.T_world_object_gt.end()) {
    throw emf::IoError(data + ": frame " + std::to_string(f.index) +
                       " has no ground truth for object " + std::to_string(id) +
                       " (--object needs a synth: source with that object)");
  }
  kept->T_world_camera_gt = pose->second.inverse() * *f.T_world_camera_gt;
  cv::Mat others;
  cv::compare(f.instance_ids, cv::Scalar(id), others, cv::CMP_NE);
  kept->depth.setTo(std::numeric_limits<float>::quiet_NaN(), others);
  cv::Mat measured;
  cv::compare(kept->depth, kept->depth, measured, cv::CMP_EQ);  // false for NaN
  if (cv::countNonZero(measured) < min_px) kept->depth = cv::Mat();
}

/// --object: the volume the pipeline would create for the object from the first frame that
/// shows it (its points in the object's frame, which is the "world" of these frames).
void placeObjectVolume(const std::vector<emf::core::Frame>& frames, const emf::core::Intrinsics& k,
                       const emf::Config& config, emf::map::VolumeSpec* spec,
                       Eigen::Isometry3d* T_world_volume) {
  const auto first = std::find_if(frames.begin(), frames.end(),
                                  [](const emf::core::Frame& f) { return !f.depth.empty(); });
  if (first == frames.end()) throw emf::IoError("--object: the object is in no frame");
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < first->depth.rows; ++v) {
    for (int u = 0; u < first->depth.cols; ++u) {
      const double z = first->depth.at<float>(v, u);
      if (!(z > 0.0)) continue;
      const Eigen::Vector3d p((u - k.cx) / k.fx * z, (v - k.cy) / k.fy * z, z);
      points.push_back(*first->T_world_camera_gt * p);
    }
  }
  const emf::em::VolumePlacement placement = emf::em::placeObject(points, config.objects);
  if (placement.extent_m <= 0.0) throw emf::IoError("--object: fewer than 10 object points");
  const double centre_depth_m = (first->T_world_camera_gt->inverse() * placement.centre_world).z();
  *spec = emf::em::objectVolumeSpec(config.map, config.objects, placement, centre_depth_m / k.fx);
  *T_world_volume = Eigen::Isometry3d::Identity();
  T_world_volume->translation() =
      placement.centre_world - Eigen::Vector3d::Constant(spec->extentM().x() / 2.0);
  std::printf("object volume: %d^3 voxels of %.2f cm, truncation %.2f cm (from frame %lld)\n",
              placement.resolution, placement.voxel_size_m * 100.0, spec->truncation_m * 100.0,
              static_cast<long long>(first->index));
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
    // Set once the first frame's size is known (objects.invisible_min_px is for 640x480).
    int min_object_px = 0;
    const auto load = [&](const std::string& dir, emf::core::Intrinsics* k) {
      const bool is_uri = dir.rfind("synth:", 0) == 0;
      auto source = emf::sources::openSource(is_uri ? dir : "tum:" + dir, config.source);
      *k = source->intrinsics();
      const double scale = k->width / 640.0;
      min_object_px = static_cast<int>(config.objects.invisible_min_px * scale * scale);
      std::vector<emf::core::Frame> frames;
      emf::core::Frame f;
      while ((args.frames <= 0 || static_cast<int>(frames.size()) < args.frames) &&
             source->next(f)) {
        if (!f.T_world_camera_gt) {
          throw emf::IoError(dir + ": frame " + std::to_string(f.index) +
                             " has no ground-truth pose (groundtruth.txt must cover every frame)");
        }
        // Only what the bench reads is kept (300 frames of 640x480 depth: 370 MB).
        emf::core::Frame kept;
        kept.index = f.index;
        kept.timestamp = f.timestamp;
        kept.depth = f.depth.clone();
        kept.T_world_camera_gt = f.T_world_camera_gt;
        if (args.object > 0) keepObjectOnly(f, args.object, dir, min_object_px, &kept);
        frames.push_back(std::move(kept));
      }
      if (frames.size() < 3) throw emf::IoError(dir + ": fewer than 3 frames");
      if (args.reverse) std::reverse(frames.begin(), frames.end());
      return frames;
    };
    emf::core::Intrinsics k;
    const std::vector<emf::core::Frame> frames = load(args.data, &k);
    std::vector<emf::core::Frame> tracked_frames;
    if (!args.track_data.empty()) {
      emf::core::Intrinsics k2;
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
    const std::vector<emf::core::Frame>& track_frames =
        tracked_frames.empty() ? frames : tracked_frames;

    emf::cl::Context ctx{config.cl};
    emf::map::VoxelPool pool(ctx, config.map);
    emf::map::VolumeSpec spec = emf::map::VolumeSpec::background(config.map);
    Eigen::Isometry3d T_wv =
        emf::map::backgroundVolumePose(config.map, spec, *frames.front().T_world_camera_gt);
    if (args.object > 0) placeObjectVolume(frames, k, config, &spec, &T_wv);
    emf::map::Volume volume(pool, spec, T_wv);
    const emf::track::TrackOptions track_options =
        args.object > 0 ? emf::pipeline::objectTrackOptions(config, k.width) : config.track;
    emf::track::Preprocessor pre(
        ctx, args.object > 0 ? emf::pipeline::objectPreprocessOptions(config) : config.preprocess,
        k);
    emf::track::Tracker tracker(ctx, track_options, k.width, k.height);

    Stats stats;
    int lost = 0;
    // The tracked frames' poses and ground truth, for an ATE as `emf eval` computes it.
    emf::io::Trajectory gt_track, est_track;
    // --decompose: per pixel class, the first-order pose shift -H^-1 g_class at the ground truth
    // (H of all pixels), i.e. what each class contributes to the deviation.
    emf::map::DeviceImage q_image(ctx, k.width, k.height);
    std::vector<Stats> class_stats(kClasses);
    // The pose each frame is fused at: its ground truth, or with --fuse-tracked its tracked pose.
    std::vector<Eigen::Isometry3d> fused_at;
    for (const auto& f : frames) fused_at.push_back(*f.T_world_camera_gt);
    const auto fuse = [&](size_t i) {
      if (frames[i].depth.empty()) return;  // --object: not in view
      if (!tracked_frames.empty() || args.prefuse) pre.process(frames[i].depth);
      emf::map::IntegrationInput in;
      in.depth = &pre.inputDepth();
      in.intrinsics = k;
      in.T_world_camera = fused_at[i];
      volume.fuse(in);
    };
    if (args.prefuse) {
      for (size_t i = 0; i < frames.size(); ++i) fuse(i);
    }
    for (size_t i = 0; i < frames.size(); ++i) {
      if (args.fuse_tracked && i >= 2) {  // until tracked: the constant-velocity prediction
        fused_at[i] = fused_at[i - 1] * (fused_at[i - 2].inverse() * fused_at[i - 1]);
      }
      if (track_frames[i].depth.empty()) {  // --object: not in view
        fuse(i);
        continue;
      }
      pre.process(track_frames[i].depth);
      const Eigen::Isometry3d& G = *frames[i].T_world_camera_gt;
      if (i >= 2) {
        const Eigen::Isometry3d& G1 = *frames[i - 1].T_world_camera_gt;
        const Eigen::Isometry3d& G2 = *frames[i - 2].T_world_camera_gt;
        const Eigen::Isometry3d predicted =
            args.start_at_gt
                ? G
                : (args.fuse_tracked ? fused_at[i] : Eigen::Isometry3d(G1 * (G2.inverse() * G1)));
        const emf::track::TrackResult r =
            tracker.track(emf::pipeline::deviceView(volume), pre.vertexMap().get(), nullptr,
                          T_wv.inverse() * predicted);
        if (r.lost) {
          ++lost;
        } else {
          const Eigen::Isometry3d d = G.inverse() * (T_wv * r.T_volume_camera);
          if (args.fuse_tracked) fused_at[i] = T_wv * r.T_volume_camera;
          gt_track.append(static_cast<double>(i), G);
          est_track.append(static_cast<double>(i), T_wv * r.T_volume_camera);
          const Eigen::Isometry3d m = G1.inverse() * G;
          Eigen::Matrix<double, 9, 1> v;
          v << d.translation() * 1000.0, rotationDeg(d.rotation()), m.translation() * 1000.0;
          stats.add(v);
          if (args.decompose) {
            const Eigen::Isometry3d T_gt = T_wv.inverse() * G;
            const cv::Mat classes = classify(frames[i].depth);
            const int stride = tracker.options().pixel_stride;
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
    // The deviation's length, i.e. the camera position's error (with --object: in the object's
    // frame, as `emf eval` scores objects, but without an alignment and with a perfect history).
    const double rms_mm = std::sqrt((stats.sq[0] + stats.sq[1] + stats.sq[2]) / stats.n);
    const double rms_deg = std::sqrt((stats.sq[3] + stats.sq[4] + stats.sq[5]) / stats.n);
    const double ate_mm =
        stats.n >= 3 ? emf::eval::computeAte(gt_track, est_track, 0.5).trans_m.rmse * 1000.0 : NAN;
    std::printf("  per-frame error rms: %.3f mm, %.4f deg; ATE (rigidly aligned) %.3f mm\n", rms_mm,
                rms_deg, ate_mm);
    std::printf(
        "track_bias data=%s frames=%d reverse=%d object=%d bias_mm=%.3f,%.3f,%.3f "
        "bias_deg=%.4f,%.4f,%.4f motion_mm=%.3f,%.3f,%.3f rms_mm=%.3f rms_deg=%.4f ate_mm=%.3f\n",
        args.data.c_str(), static_cast<int>(frames.size()), args.reverse ? 1 : 0, args.object,
        stats.mean(0), stats.mean(1), stats.mean(2), stats.mean(3), stats.mean(4), stats.mean(5),
        stats.mean(6), stats.mean(7), stats.mean(8), rms_mm, rms_deg, ate_mm);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "track_bias: " << e.what() << "\n";
    return 1;
  }
}
