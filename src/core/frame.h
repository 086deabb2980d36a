// One RGB-D frame as every source delivers it, and the detections that may come with it.
// Frames: camera frame C (x right, y down, z forward, metres); poses are Eigen::Isometry3d
// T_a_b mapping points in b to a (T_world_camera: camera-to-world).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace emf::core {

/// Pinhole intrinsics of the depth image (the colour image is assumed registered to it or is
/// only used for display).
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;

  bool valid() const { return fx > 0 && fy > 0 && width > 0 && height > 0; }
  /// Same camera at another resolution (scales focal lengths and principal point).
  Intrinsics scaled(int new_width, int new_height) const {
    Intrinsics k = *this;
    const double sx = static_cast<double>(new_width) / width;
    const double sy = static_cast<double>(new_height) / height;
    k.fx = fx * sx;
    k.fy = fy * sy;
    // Pixel centres: x_new + 0.5 = (x_old + 0.5) * s.
    k.cx = (cx + 0.5) * sx - 0.5;
    k.cy = (cy + 0.5) * sy - 0.5;
    k.width = new_width;
    k.height = new_height;
    return k;
  }
};

/// Largest image side the SLAM accepts (pixels).
constexpr int kMaxImageSide = 16384;
/// Longest focal length checkedIntrinsics accepts, in image sides (fx / width).
constexpr double kMaxFocalPerSide = 100.0;

/// `k` if it describes a real pinhole depth camera, else throws InvalidArgument naming the bad
/// value and what to do: focal lengths finite, at least a twentieth of the image side (a
/// field of view under ~170 deg) and at most kMaxFocalPerSide sides (over 0.6 deg), principal point
/// finite and at most one image side outside the image, size in [1, kMaxImageSide]. Far-off values
/// would make the map's ray walks unbounded.
Intrinsics checkedIntrinsics(const Intrinsics& k);

/// One instance from a detector (or from a dataset's masks/ folder).
struct Detection {
  int id = 0;              // detection id within the frame (1..n); not an object id
  std::string class_name;  // e.g. "car", "person"
  float score = 0.f;       // [0, 1]
  cv::Rect box;            // pixels, inside the image
  cv::Mat mask;            // CV_32F probability in [0, 1] (binary masks are 0/1), image size
};

struct Frame {
  int64_t index = 0;           // 0-based position in the source
  double timestamp = 0;        // seconds (depth timestamp)
  std::string timestamp_text;  // the depth timestamp exactly as the source wrote it
  double rgb_timestamp = 0;    // seconds
  cv::Mat depth;               // CV_32F metres, NaN = invalid
  cv::Mat color;               // CV_8UC3 BGR (may be empty); same size as depth or not
  std::optional<std::vector<Detection>> detections;    // present on frames the source labels
  std::optional<Eigen::Isometry3d> T_world_camera_gt;  // ground truth when the source has it
  /// Ground-truth object poses (T_world_object) by object id, and the rendered instance ids
  /// (CV_16U, 0 = background), when the source is synthetic.
  std::map<int, Eigen::Isometry3d> T_world_object_gt;
  cv::Mat instance_ids;
};

}  // namespace emf::core
