#pragma once
// The scene's up direction from one depth frame: the normal shared by its upward-facing
// horizontal surfaces (floor, table tops, seats). emf has no gravity sensor input; the
// re-identification turns a returning object about this axis (object_reid.cpp).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>

namespace emf::pipeline {

/// The unit up direction in the camera frame (x right, y down, z forward) of the vertex map
/// `vertex` (CV_32FC4, metres, w = 0 where the depth is missing), or nothing when too few
/// surfaces face up within kMaxUpTiltDeg of the image's up (-y): the mode of the sampled
/// surface normals in that cone, refined to the mean of those within kUpClusterDeg of it.
std::optional<Eigen::Vector3d> upInCamera(const cv::Mat& vertex);

/// Surfaces farther than this from the image's up (-y) are not candidates (walls are 90 deg
/// from the up, so the camera may pitch by up to 90 - kMaxUpTiltDeg deg).
constexpr double kMaxUpTiltDeg = 45.0;
/// Normals within this angle of the mode count as its surface.
constexpr double kUpClusterDeg = 10.0;
/// The mode's surface must hold this share of the sampled normals.
constexpr double kMinUpSupport = 0.05;

}  // namespace emf::pipeline
