// Renderer: exact depth and instance ids of known geometry (noise off) against analytic
// references computed independently here, the lighting model on a known face, intrinsics.
#include "synth/renderer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"

namespace emf::synth {
namespace {

constexpr double kPi = 3.141592653589793;
/// Rendered vs analytic depth (metres).
constexpr double kDepthToleranceM = 1e-4;

/// Camera at `c` looking along world +y (x right = world +x, y down = world -z), pitched down.
Eigen::Isometry3d lookingAlongY(const Eigen::Vector3d& c, double pitch_down_rad = 0.0) {
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d(1, 0, 0);
  R.col(1) = Eigen::Vector3d(0, 0, -1);
  R.col(2) = Eigen::Vector3d(0, 1, 0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * Eigen::AngleAxisd(-pitch_down_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
  T.translation() = c;
  return T;
}

/// Reference ray-box hit by testing the six face rectangles (box frame B, half extents h).
/// Returns t or +inf; *ambiguous when the hit lies within 1e-6 of a face edge.
double boxReference(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& h,
                    bool* ambiguous) {
  double best = std::numeric_limits<double>::infinity();
  *ambiguous = false;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      if (d[axis] == 0) continue;
      const double t = (sign * h[axis] - o[axis]) / d[axis];
      if (t <= 0) continue;
      const Eigen::Vector3d p = o + t * d;
      bool inside = true, edge = false;
      for (int j = 0; j < 3; ++j) {
        if (j == axis) continue;
        if (std::fabs(p[j]) > h[j] + 1e-6) inside = false;
        if (std::fabs(std::fabs(p[j]) - h[j]) <= 1e-6) edge = true;
      }
      if (inside && t < best) {
        best = t;
        *ambiguous = edge;
      }
    }
  }
  return best;
}

TEST(SynthRenderer, DefaultIntrinsicsAreKinectLikeAndScale) {
  const core::Intrinsics k = defaultIntrinsics(640, 480);
  EXPECT_DOUBLE_EQ(k.fx, 525.0);
  EXPECT_DOUBLE_EQ(k.fy, 525.0);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
  const core::Intrinsics h = defaultIntrinsics(320, 240);
  EXPECT_DOUBLE_EQ(h.fx, 262.5);
  EXPECT_DOUBLE_EQ(h.cx, 159.5);
  EXPECT_EQ(h.width, 320);
}

TEST(SynthRenderer, WallAndRotatedBoxMatchAnalyticDepthAndIds) {
  Scene scene;
  scene.name = "test";
  // Wall y = 3 facing the camera: local z (normal) -> world -y.
  Eigen::Isometry3d T_wall = at(0, 3, 0);
  T_wall.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  scene.statics.push_back(makePlane(T_wall, Material{}));
  SceneObject box;
  box.id = 1;
  box.class_name = "box";
  const Eigen::Vector3d h(0.2, 0.1, 0.15);
  box.parts.push_back(makeBox({h.x(), h.y(), h.z()}, Eigen::Isometry3d::Identity(), Material{}));
  scene.objects.push_back(box);
  const Eigen::Isometry3d T_world_box = at(0.3, 2.0, 0.1, 0.4, 0.2, -0.3);
  const Eigen::Isometry3d T_world_camera = lookingAlongY({0.05, 0.0, 0.2});

  RenderOptions ro;
  ro.width = 160;
  ro.height = 120;
  ro.threads = 1;
  Renderer renderer(ro);
  RenderOutput out;
  renderer.render(scene, T_world_camera, {T_world_box}, &out);
  const core::Intrinsics& K = renderer.intrinsics();

  const Eigen::Isometry3d T_box_camera = T_world_box.inverse() * T_world_camera;
  int box_pixels = 0, wall_pixels = 0, checked = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_c((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);  // z = 1
      const Eigen::Vector3d ray_w = T_world_camera.linear() * ray_c;
      const double t_wall = (3.0 - T_world_camera.translation().y()) / ray_w.y();
      bool ambiguous = false;
      const double t_box =
          boxReference(T_box_camera.translation(), T_box_camera.linear() * ray_c, h, &ambiguous);
      if (ambiguous) continue;
      ++checked;
      const float depth = out.depth.at<float>(v, u);
      const uint16_t id = out.instance_ids.at<uint16_t>(v, u);
      if (t_box < t_wall) {
        ++box_pixels;
        EXPECT_NEAR(depth, t_box, kDepthToleranceM) << u << "," << v;
        EXPECT_EQ(id, 1) << u << "," << v;
      } else {
        ++wall_pixels;
        EXPECT_NEAR(depth, t_wall, kDepthToleranceM) << u << "," << v;
        EXPECT_EQ(id, 0) << u << "," << v;
      }
    }
  }
  EXPECT_GT(checked, 160 * 120 * 95 / 100);
  EXPECT_GT(box_pixels, 500);
  EXPECT_GT(wall_pixels, 5000);
}

TEST(SynthRenderer, FloorSeenFromAPitchedCameraMatchesPlaneDepth) {
  Scene scene;
  scene.name = "floor";
  scene.statics.push_back(makePlane(Eigen::Isometry3d::Identity(), Material{}));
  const Eigen::Isometry3d T_world_camera = lookingAlongY({0.2, -1.0, 1.2}, 0.35);
  RenderOptions ro;
  ro.width = 96;
  ro.height = 72;
  ro.threads = 1;
  Renderer renderer(ro);
  RenderOutput out;
  renderer.render(scene, T_world_camera, {}, &out);
  const core::Intrinsics& K = renderer.intrinsics();
  int hits = 0, misses = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_w =
          T_world_camera.linear() * Eigen::Vector3d((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const float depth = out.depth.at<float>(v, u);
      if (ray_w.z() < -1e-9) {
        ++hits;
        EXPECT_NEAR(depth, -1.2 / ray_w.z(), kDepthToleranceM * (-1.2 / ray_w.z()))
            << u << "," << v;
      } else {
        ++misses;
        EXPECT_TRUE(std::isnan(depth)) << u << "," << v;
        EXPECT_EQ(out.color.at<cv::Vec3b>(v, u), cv::Vec3b(0, 0, 0));
      }
    }
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(misses, 100);  // the horizon is in view
}

TEST(SynthRenderer, FacingSurfaceIsShadedWithTheDocumentedLightModel) {
  Scene scene;
  scene.name = "shade";
  Eigen::Isometry3d T_wall = at(0, 2, 0);
  T_wall.linear() = Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  Material m;
  m.albedo_bgr = {0.2f, 0.5f, 0.8f};
  scene.statics.push_back(makePlane(T_wall, m));
  const Eigen::Isometry3d T_world_camera = lookingAlongY({0, 0, 0});
  RenderOptions ro;
  ro.width = 64;
  ro.height = 48;
  Renderer renderer(ro);
  RenderOutput out;
  renderer.render(scene, T_world_camera, {}, &out);
  // Centre pixel: normal (world -y) faces the camera; key light (0.35, -0.5, 1) normalised.
  const double n_dot_l = 0.5 / Eigen::Vector3d(0.35, -0.5, 1.0).norm();
  const Eigen::Vector3d ray(0.5 / 525.0 * 10, 0.5 / 525.0 * 10, 1.0);  // pixel (32, 24)
  const double c_view = 1.0 / ray.norm();
  const double shade = 0.3 + 0.55 * n_dot_l + 0.25 * c_view;
  const cv::Vec3b bgr = out.color.at<cv::Vec3b>(24, 32);
  EXPECT_NEAR(bgr[0], 255 * 0.2 * shade, 0.51);
  EXPECT_NEAR(bgr[1], 255 * 0.5 * shade, 0.51);
  EXPECT_NEAR(bgr[2], 255 * 0.8 * shade, 0.51);
  EXPECT_NEAR(out.cos_incidence.at<float>(24, 32), c_view, 1e-6);
}

TEST(SynthRenderer, RejectsBadSizesAndPoseCounts) {
  RenderOptions ro;
  ro.width = 0;
  EXPECT_THROW(Renderer{ro}, InvalidArgument);
  ro.width = 32;
  ro.height = 24;
  Renderer renderer(ro);
  Scene scene;
  scene.objects.push_back(SceneObject{});
  RenderOutput out;
  try {
    renderer.render(scene, Eigen::Isometry3d::Identity(), {}, &out);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("1 objects but 0 poses"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace emf::synth
