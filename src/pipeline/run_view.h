// The picture of one processed frame, as `emf run --view / --video / --frames-png` show it
// (one BGR image, 1.5 W x 1.5 H for a W x H depth image):
//
//   +---------------------------+-------------+
//   | colour, each object's     | top view of |
//   | rendered mask over it in  | trajectories|
//   | objectColor(id), labelled +-------------+
//   | "id class [state]";       | depth       |
//   | status line at the bottom | (false col.)|
//   +-------------+-------------+-------------+
//   | q_0 (back-  | q_i of the  | objects:    |
//   | ground)     | objects, in | id class    |
//   |             | their colour| state       |
//   +-------------+-------------+-------------+
//
// The top view looks down the world's y axis (x right, z up in the picture), the world being
// the first camera's frame; it keeps the camera's path and every object's (the point seen at
// the centre of its rendered mask, at the median measured depth there) so far.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pipeline/object_outputs.h"
#include "pipeline/slam_system.h"

namespace emf::pipeline {

/// What one frame's picture is made from (copies: the viewer may draw on another thread).
struct ViewFrame {
  int64_t index = 0;
  double timestamp = 0;                       // seconds
  cv::Mat color;                              // CV_8UC3 BGR (may be empty: black)
  cv::Mat depth;                              // CV_32F metres, NaN = none
  cv::Mat object_ids;                         // CV_32S, the rendered volume ids (<= 0: none)
  std::vector<AssociationImage> association;  // q per volume (id 0 = background), depth size
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  core::Intrinsics intrinsics;         // of the depth image (places objects in the top view)
  std::vector<ObjectOutcome> objects;  // FrameOutcome::objects
  bool lost = false;                   // camera tracking failed
  double ms = 0;                       // the SLAM's time for this frame
  double pool_occupancy = 0;           // [0, 1]
  int64_t dropped_frames = 0;          // by the source so far
};

/// Metres of depth mapped onto the false-colour scale (JET: blue near, red far).
constexpr double kViewDepthRangeM = 5.0;

class RunView {
 public:
  /// The picture of `frame` (BGR, 1.5 W x 1.5 H for a W x H depth image; W, H even), and the
  /// frame's poses added to the top view's paths. Throws InvalidArgument for images of the
  /// wrong type or size.
  cv::Mat compose(const ViewFrame& frame);

  /// The overlay tile alone (colour + masks + labels + status line), W x H.
  static cv::Mat overlayTile(const ViewFrame& frame);
  /// sum_i q_i * objectColor(i) over the objects (background black), clamped.
  static cv::Mat objectAssociationTile(const std::vector<AssociationImage>& association,
                                       cv::Size size);

 private:
  cv::Mat topView(cv::Size size) const;

  std::vector<Eigen::Vector3d> camera_path_;
  std::map<int, std::vector<Eigen::Vector3d>> object_paths_;
  Eigen::Vector3d camera_position_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d camera_forward_ = Eigen::Vector3d::UnitZ();
};

}  // namespace emf::pipeline
