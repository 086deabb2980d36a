// Writes frames as a TUM RGB-D folder that any TUM tool (and emf's tum: reader) can read:
//   rgb/<t>.png            colour, 8-bit BGR PNG
//   depth/<t>.png          depth, uint16 PNG, depth_scale units per metre (5000), 0 = invalid
//   rgb.txt, depth.txt     "timestamp filename" lists (3 comment lines first, as TUM's)
//   associations.txt       "t_rgb rgb/<t>.png t_depth depth/<t>.png"
//   groundtruth.txt        T_world_camera per frame: "t tx ty tz qx qy qz qw"
//   calibration.txt        "fx fy cx cy width height"
//   objects/gt-object-<k>-world.txt   T_world_object per frame
//   objects/gt-object-<k>-camera.txt  T_object_camera (the camera in the object's frame), only
//                                     frames where the object is visible
//   masks/<t>.png          detections: uint16, pixel = detection id 1..n, 0 = none
//   masks/<t>.txt          one line per detection "det_id class_name score" (spaces in class
//                          names written as '_')
//   README.md              what the folder holds and these formats
// <t> is the depth timestamp text (Frame::timestamp_text). Every file is written atomically.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

#include "core/frame.h"

namespace emf::io {

struct TumWriterOptions {
  /// uint16 depth units per metre (TUM: 5000 -> 0.2 mm steps, 13.1 m maximum).
  double depth_scale = 5000.0;
  /// PNG compression level 0-9 (1: fast, files ~15 % larger than 9).
  int png_compression = 1;
  /// Free text placed at the top of README.md (what the sequence is, how it was made).
  std::string readme_about;
  /// An object counts as visible (-camera.txt line) when its instance id covers at least this
  /// fraction of the image; frames without instance ids count every object as visible.
  double min_visible_fraction = 0.001;
};

/// One TUM line "t tx ty tz qx qy qz qw" for a pose (9 decimals, qw >= 0).
std::string tumPoseLine(const std::string& timestamp_text, const Eigen::Isometry3d& T);

/// Class names as written in masks/<t>.txt: spaces (and tabs) replaced by '_'.
std::string maskClassToken(const std::string& class_name);

class TumWriter {
 public:
  /// Creates `dir` (and parents) and its sub-folders. Throws IoError naming the folder.
  TumWriter(const std::string& dir, const core::Intrinsics& intrinsics,
            const TumWriterOptions& options = {});

  /// Writes the frame's images (and detection masks when frame.detections is set) and
  /// remembers its list lines and poses. Throws IoError naming the frame on bad images
  /// (depth must be CV_32F, colour CV_8UC3 of any size, detection masks of the depth size).
  void write(const core::Frame& frame);

  /// Writes the lists, ground truth, calibration, object trajectories and README.md. Call
  /// once after the last frame; frames written after it are rejected.
  void finish();

  const std::string& dir() const { return dir_; }
  int64_t framesWritten() const { return frames_; }

 private:
  std::string dir_;
  core::Intrinsics intrinsics_;
  TumWriterOptions options_;
  int64_t frames_ = 0;
  bool finished_ = false;
  int64_t unrepresentable_depth_ = 0;
  std::string rgb_list_, depth_list_, associations_, groundtruth_;
  std::map<int, std::string> object_world_, object_camera_;
};

}  // namespace emf::io
