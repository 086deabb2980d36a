// The TUM RGB-D dataset folder reader (`tum:<dir>`):
//   rgb.txt, depth.txt        `timestamp file` lists ('#' comments)
//   associations.txt          optional, `t_rgb rgb_file t_depth depth_file` (the depth-first
//                             order `t_depth depth_file t_rgb rgb_file` is recognised too);
//                             without it depth and rgb are associated like associate.py
//                             within SourceOptions::max_time_diff_s
//   groundtruth.txt           optional, `t tx ty tz qx qy qz qw` (T_world_camera), interpolated
//                             to each depth timestamp within 0.02 s
//   calibration.txt           optional, `fx fy cx cy [width height]` (depth camera)
//   masks/                    optional detections (see detections_io.h)
// Depth is uint16 PNG in units of 1/depth_scale m (TUM 5000, 7-Scenes 1000), 0 = invalid.
#pragma once

#include <string>
#include <vector>

#include "core/frame_source.h"
#include "io/trajectory.h"

namespace emf::io {

/// One frame of the folder's listing, before its images are read.
struct TumEntry {
  double depth_stamp = 0;
  std::string depth_stamp_text;  // exactly as written in depth.txt (detections key on it)
  std::string depth_file;        // relative to the folder
  double rgb_stamp = 0;
  std::string rgb_file;      // empty: no colour for this frame
  std::string origin;        // "<list file>:<line>" the entry came from (for errors)
  std::string color_origin;  // the same for the colour image ("" = origin: associations.txt)
};

class TumSource : public core::FrameSource {
 public:
  /// Indexes the folder: reads the lists, the ground truth, the intrinsics and the first depth
  /// image (for the image size). Throws IoError naming file and line for anything missing or
  /// inconsistent, and when no intrinsics are available (neither options/query nor
  /// calibration.txt: TUM camera defaults are deliberately not guessed).
  TumSource(const std::string& dir, const core::SourceOptions& options);

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  bool next(core::Frame& frame) override;
  int64_t size() const override { return static_cast<int64_t>(entries_.size()); }
  std::string describe() const override;

  const std::vector<TumEntry>& entries() const { return entries_; }
  /// The ground truth read from groundtruth.txt (empty when the folder has none).
  const Trajectory& groundTruth() const { return ground_truth_; }
  /// Reads frame `index` (0-based) without moving the cursor of next().
  core::Frame readFrame(size_t index) const;
  /// What opening the folder warned about (also logged): a depth scale that looks wrong for the
  /// first depth image (see depthScaleWarning), detection lists in masks/ that match no frame.
  const std::vector<std::string>& openWarnings() const { return open_warnings_; }

 private:
  void warn(const std::string& text);
  void checkMasksMatchFrames();

  std::string dir_;
  core::SourceOptions options_;
  std::vector<TumEntry> entries_;
  Trajectory ground_truth_;
  core::Intrinsics intrinsics_;
  std::string masks_dir_;  // empty when the folder has no masks/
  cv::Size depth_size_;
  std::string first_depth_file_;
  size_t cursor_ = 0;
  std::vector<std::string> open_warnings_;
  mutable cv::Size color_size_;  // first colour image's size (0x0 until read)
  mutable std::string first_color_file_;
  mutable int64_t bad_masks_ = 0;  // frames whose masks/ files could not be read
};

/// The tum-fr1-xyz-pairs layout: a case folder with img_prev.png, img_curr.png, dep_prev.png,
/// dep_curr.png (uint16, `depth_scale` units per metre) and pose_prev.txt / pose_curr.txt
/// (`tx ty tz qx qy qz qw`, camera-to-world), plus a 3x3 intrinsic matrix file.
struct TumPairCase {
  core::Frame prev, curr;  // depth, colour and T_world_camera_gt filled; timestamps 0 and 1
  core::Intrinsics intrinsics;
  /// Ground-truth pose of the current camera in the previous camera's frame.
  Eigen::Isometry3d T_prev_curr() const;
};

/// Loads one case folder. Throws IoError naming the file (and line) on any problem.
TumPairCase loadTumPairCase(const std::string& case_dir, const std::string& intrinsics_path,
                            double depth_scale = 5000.0);

/// Reads a 3x3 intrinsic matrix (`fx 0 cx / 0 fy cy / 0 0 1`, spaces or tabs); width and height
/// are left 0. Throws IoError naming file and line.
core::Intrinsics readIntrinsicMatrix(const std::string& path);

/// Reads calibration.txt: `fx fy cx cy [width height]` on one line (width/height 0 when
/// absent). Throws IoError naming file and line.
core::Intrinsics readCalibrationFile(const std::string& path);

/// Intrinsics for a source with image size `size`: from `options` (fx, fy, cx, cy all set) if
/// given, else from `calibration_path` if it exists (its width/height must match `size`), else
/// IoError telling the user to pass fx/fy/cx/cy. `what` names the source in messages.
core::Intrinsics resolveIntrinsics(const core::SourceOptions& options,
                                   const std::string& calibration_path, cv::Size size,
                                   const std::string& what);

}  // namespace emf::io
