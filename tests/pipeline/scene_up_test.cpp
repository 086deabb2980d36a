// upInCamera on rendered vertex maps of a floor and a wall, seen by a pitched, rolled camera.
#include "pipeline/scene_up.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace emf::pipeline {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kUpToleranceDeg = 0.5;  // the refined mean of the floor's normals
constexpr int kWidth = 320, kHeight = 240;
constexpr double kF = 260.0;

double deg(double rad) { return rad * 180.0 / kPi; }

// The camera at 1.5 m above the floor (world z up, floor z = 0), looking along world +x, pitched
// down by `pitch_deg` and rolled by `roll_deg`; T_world_camera with x right, y down, z forward.
Eigen::Isometry3d camera(double pitch_deg, double roll_deg) {
  Eigen::Matrix3d base;
  base.col(0) = -Eigen::Vector3d::UnitY();  // image right
  base.col(1) = -Eigen::Vector3d::UnitZ();  // image down
  base.col(2) = Eigen::Vector3d::UnitX();   // forward
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = base * Eigen::AngleAxisd(-pitch_deg * kPi / 180.0, Eigen::Vector3d::UnitX()) *
               Eigen::AngleAxisd(roll_deg * kPi / 180.0, Eigen::Vector3d::UnitZ());
  T.translation() = Eigen::Vector3d(0.0, 0.0, 1.5);
  return T;
}

// The vertex map (camera frame) of the planes n.x = d (world) the rays hit first; `ripple_m`
// adds a deterministic depth ripple of that amplitude.
cv::Mat render(const Eigen::Isometry3d& T_world_camera, bool floor, bool wall, double ripple_m) {
  cv::Mat vertex(kHeight, kWidth, CV_32FC4, cv::Scalar(0, 0, 0, 0));
  struct Plane {
    Eigen::Vector3d n;
    double d;
  };
  std::vector<Plane> planes;
  if (floor) planes.push_back({Eigen::Vector3d::UnitZ(), 0.0});
  if (wall) planes.push_back({Eigen::Vector3d::UnitX(), 3.0});
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      const Eigen::Vector3d ray_c((u - kWidth / 2.0) / kF, (v - kHeight / 2.0) / kF, 1.0);
      const Eigen::Vector3d ray_w = T_world_camera.linear() * ray_c;
      const Eigen::Vector3d o = T_world_camera.translation();
      double t_best = std::numeric_limits<double>::infinity();
      for (const Plane& p : planes) {
        const double denom = p.n.dot(ray_w);
        if (std::abs(denom) < 1e-9) continue;
        const double t = (p.d - p.n.dot(o)) / denom;
        if (t > 0.0 && t < t_best) t_best = t;
      }
      if (!std::isfinite(t_best) || t_best > 8.0) continue;
      const double z = t_best + ripple_m * std::sin(0.37 * u + 0.73 * v);  // t is the depth
      const Eigen::Vector3d p = ray_c * z;
      vertex.at<cv::Vec4f>(v, u) = cv::Vec4f(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                             static_cast<float>(p.z()), 1.0f);
    }
  }
  return vertex;
}

double errorDeg(const Eigen::Isometry3d& T_world_camera, const Eigen::Vector3d& up_camera) {
  const Eigen::Vector3d truth = T_world_camera.linear().transpose() * Eigen::Vector3d::UnitZ();
  return deg(std::acos(std::clamp(truth.dot(up_camera), -1.0, 1.0)));
}

TEST(SceneUp, FloorAndWallFromAPitchedRolledCamera) {
  for (const double pitch : {10.0, 30.0, 40.0}) {
    const Eigen::Isometry3d T = camera(pitch, 5.0);
    const std::optional<Eigen::Vector3d> up = upInCamera(render(T, true, true, 0.0));
    ASSERT_TRUE(up.has_value()) << "pitch " << pitch;
    EXPECT_LT(errorDeg(T, *up), kUpToleranceDeg) << "pitch " << pitch;
  }
}

TEST(SceneUp, NoisyFloor) {
  const Eigen::Isometry3d T = camera(25.0, -8.0);
  const std::optional<Eigen::Vector3d> up = upInCamera(render(T, true, true, 0.002));
  ASSERT_TRUE(up.has_value());
  EXPECT_LT(errorDeg(T, *up), kUpToleranceDeg);
}

TEST(SceneUp, AWallAloneGivesNothing) {
  // A level camera facing a wall: no surface faces up, so no up is claimed (the wall's normal is
  // 90 deg from the image's up, outside kMaxUpTiltDeg).
  EXPECT_FALSE(upInCamera(render(camera(0.0, 0.0), false, true, 0.0)).has_value());
  EXPECT_FALSE(upInCamera(cv::Mat(kHeight, kWidth, CV_32FC4, cv::Scalar(0, 0, 0, 0))).has_value());
}

}  // namespace
}  // namespace emf::pipeline
