#include "map_test_scene.h"

#include <cmath>
#include <limits>

namespace emf::test {

core::Intrinsics testIntrinsics(int width, int height) {
  core::Intrinsics k;
  k.fx = k.fy = 585.0;
  k.cx = 320.0;
  k.cy = 240.0;
  k.width = 640;
  k.height = 480;
  return (width == 640 && height == 480) ? k : k.scaled(width, height);
}

map::CameraF cameraF(const core::Intrinsics& k) {
  map::CameraF c;
  c.fx = static_cast<float>(k.fx);
  c.fy = static_cast<float>(k.fy);
  c.cx = static_cast<float>(k.cx);
  c.cy = static_cast<float>(k.cy);
  c.width = k.width;
  c.height = k.height;
  return c;
}

namespace {

constexpr double kMaxRange = 10.0;

double hitPlane(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int axis, double value) {
  if (std::abs(d[axis]) < 1e-12) return kMaxRange + 1;
  const double t = (value - o[axis]) / d[axis];
  return t > 1e-6 ? t : kMaxRange + 1;
}

double hitSphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Sphere& s) {
  const Eigen::Vector3d oc = o - s.centre_w;
  const double a = d.squaredNorm(), b = 2 * oc.dot(d),
               c = oc.squaredNorm() - s.radius_m * s.radius_m;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return kMaxRange + 1;
  const double t = (-b - std::sqrt(disc)) / (2 * a);
  return t > 1e-6 ? t : kMaxRange + 1;
}

cv::Mat render(const Scene& scene, bool walls, const std::vector<int>& which,
               const core::Intrinsics& k, const Eigen::Isometry3d& T_world_camera) {
  cv::Mat depth(k.height, k.width, CV_32FC1);
  const Eigen::Matrix3d R = T_world_camera.rotation();
  const Eigen::Vector3d o = T_world_camera.translation();
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const Eigen::Vector3d ray_c((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);  // z = 1
      const Eigen::Vector3d d = R * ray_c;
      double t = kMaxRange + 1;
      if (walls) {
        t = std::min(t, hitPlane(o, d, 1, scene.floor_y_m));
        t = std::min(t, hitPlane(o, d, 2, scene.back_wall_z_m));
        t = std::min(t, hitPlane(o, d, 0, scene.left_wall_x_m));
      }
      for (int i : which) t = std::min(t, hitSphere(o, d, scene.spheres[static_cast<size_t>(i)]));
      depth.at<float>(y, x) =
          t <= kMaxRange ? static_cast<float>(t) : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return depth;
}

}  // namespace

cv::Mat renderDepth(const Scene& scene, const core::Intrinsics& k,
                    const Eigen::Isometry3d& T_world_camera) {
  std::vector<int> all;
  for (size_t i = 0; i < scene.spheres.size(); ++i) all.push_back(static_cast<int>(i));
  return render(scene, true, all, k, T_world_camera);
}

cv::Mat renderSpheres(const Scene& scene, const std::vector<int>& which, const core::Intrinsics& k,
                      const Eigen::Isometry3d& T_world_camera) {
  return render(scene, false, which, k, T_world_camera);
}

cv::Mat sphereMask(const Scene& scene, int which, const core::Intrinsics& k,
                   const Eigen::Isometry3d& T_world_camera) {
  const cv::Mat depth = renderDepth(scene, k, T_world_camera);
  const cv::Mat sphere_only = renderSpheres(scene, {which}, k, T_world_camera);
  cv::Mat mask(k.height, k.width, CV_32FC1);
  for (int y = 0; y < k.height; ++y) {
    for (int x = 0; x < k.width; ++x) {
      const float ds = sphere_only.at<float>(y, x);
      mask.at<float>(y, x) =
          !std::isnan(ds) && std::abs(ds - depth.at<float>(y, x)) < 1e-4f ? 1.0f : 0.0f;
    }
  }
  return mask;
}

Eigen::Isometry3d lookAt(const Eigen::Vector3d& position_w, const Eigen::Vector3d& target_w) {
  const Eigen::Vector3d z = (target_w - position_w).normalized();
  Eigen::Vector3d x = Eigen::Vector3d(0, 1, 0).cross(z);  // y down: x = down x forward
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = position_w;
  return T;
}

}  // namespace emf::test
