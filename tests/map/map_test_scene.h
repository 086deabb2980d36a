// Analytic test scenes for the map tests: a room (floor, back and side walls) with spheres,
// rendered exactly into z-depth images, and its signed distance.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "core/frame.h"
#include "map/map_math.h"

namespace emf::test {

struct Sphere {
  Eigen::Vector3d centre_w;
  double radius_m;
};

/// Camera frame convention: x right, y down, z forward. World = first camera.
struct Scene {
  double floor_y_m = 0.8;      // plane y = floor_y (below the camera)
  double back_wall_z_m = 3.0;  // plane z = back_wall_z
  double left_wall_x_m = -1.4;
  std::vector<Sphere> spheres = {{Eigen::Vector3d(0.25, 0.15, 1.6), 0.35},
                                 {Eigen::Vector3d(-0.6, 0.45, 2.2), 0.3}};
};

/// Kinect-like intrinsics (fx = fy = 585 at 640x480) at width x height.
core::Intrinsics testIntrinsics(int width, int height);
map::CameraF cameraF(const core::Intrinsics& k);

/// Exact z-depth of the scene (metres; NaN where nothing within 10 m).
cv::Mat renderDepth(const Scene& scene, const core::Intrinsics& k,
                    const Eigen::Isometry3d& T_world_camera);
/// Exact z-depth of only the spheres listed in `which` (NaN elsewhere).
cv::Mat renderSpheres(const Scene& scene, const std::vector<int>& which, const core::Intrinsics& k,
                      const Eigen::Isometry3d& T_world_camera);

/// Detection mask of sphere `which`: 1 where it is the visible surface, 0 elsewhere (CV_32F).
cv::Mat sphereMask(const Scene& scene, int which, const core::Intrinsics& k,
                   const Eigen::Isometry3d& T_world_camera);

/// A camera pose: position in the world, looking at `target` (y down).
Eigen::Isometry3d lookAt(const Eigen::Vector3d& position_w, const Eigen::Vector3d& target_w);

}  // namespace emf::test
