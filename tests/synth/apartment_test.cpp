// The apartment preset: a static flat walked through on one long closed loop by a hand-held
// camera. The walk is long enough, hand-held in pace and turn rate, keeps clear of every wall and
// piece of furniture (doorways included), ends at its start pose, and views spread over the loop
// have surfaces within depth-sensor range facing in several directions (what a depth-only
// tracker needs).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "synth/presets.h"
#include "synth/renderer.h"
#include "synth/scene_check.h"

namespace emf::synth {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

constexpr double kMinPathLengthM = 32.0;
// Walking pace over the whole loop, and at rest over its first and last frame.
constexpr double kMinMeanSpeedMps = 0.25, kMaxMeanSpeedMps = 0.4;
constexpr double kRestSpeedMps = 0.05;
// Hand-held limits per frame (finite differences at 30 fps): walking, and the TUM hand-held
// sequences' rotation rates.
constexpr double kMaxSpeedMps = 0.5;
constexpr double kMaxRateDegPerS = 30.0;
// Eye height, and how far the optical axis points below the horizontal.
constexpr double kMinEyeHeightM = 1.4, kMaxEyeHeightM = 1.6;
constexpr double kMinLookDownDeg = 5.0, kMaxLookDownDeg = 25.0;
// Camera centre to any static surface; last pose against the first.
constexpr double kMinClearanceM = 0.3;
constexpr double kClosureM = 0.01, kClosureDeg = 1.0;
// Of the pixels of every checked view, at least kMinNearFraction within kNearDepthM.
constexpr double kNearDepthM = 4.0;
constexpr double kMinNearFraction = 0.6;
// The spread of the surface normals in view (scene_check.h) that the generated scenes require
// of every frame (random_scene.cpp kMinNormalSpread): all three directions are pinned down.
constexpr double kMinNormalSpread = 0.004;
constexpr int kViewsChecked = 16;

double rotationDegBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * kRadToDeg;
}

std::vector<Eigen::Isometry3d> cameraPoses(const Scene& s) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < s.default_frames; ++i) poses.push_back(s.camera.pose(s.timeOf(i)));
  return poses;
}

TEST(SynthApartment, IsAStaticPresetWalkedOnALongClosedLoop) {
  const auto names = presetNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "apartment"), names.end());
  const Scene s = makePreset("apartment");
  EXPECT_EQ(s.name, "apartment");
  EXPECT_TRUE(s.objects.empty());
  EXPECT_GT(s.statics.size(), 200u);
  const auto poses = cameraPoses(s);
  ASSERT_GT(poses.size(), 2u);
  double length = 0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].translation() - poses[i - 1].translation()).norm();
  }
  EXPECT_GE(length, kMinPathLengthM);
  // About 100 s at hand-held walking pace, all of it needed for the loop.
  const double seconds = (s.default_frames - 1) / s.fps;
  EXPECT_GT(length / seconds, kMinMeanSpeedMps) << length << " m in " << seconds << " s";
  EXPECT_LT(length / seconds, kMaxMeanSpeedMps) << length << " m in " << seconds << " s";
  EXPECT_LT((poses.back().translation() - poses.front().translation()).norm(), kClosureM);
  EXPECT_LT(rotationDegBetween(poses.back(), poses.front()), kClosureDeg);
  // It starts from rest and comes to rest.
  EXPECT_LT((poses[1].translation() - poses[0].translation()).norm() * s.fps, kRestSpeedMps);
  EXPECT_LT((poses.back().translation() - poses[poses.size() - 2].translation()).norm() * s.fps,
            kRestSpeedMps);
}

TEST(SynthApartment, CameraIsHandHeldAtEyeHeightLookingAheadAndDown) {
  const Scene s = makePreset("apartment");
  const auto poses = cameraPoses(s);
  double max_speed = 0, max_rate = 0;
  for (size_t i = 1; i < poses.size(); ++i) {
    max_speed =
        std::max(max_speed, (poses[i].translation() - poses[i - 1].translation()).norm() * s.fps);
    max_rate = std::max(max_rate, rotationDegBetween(poses[i - 1], poses[i]) * s.fps);
  }
  EXPECT_LE(max_speed, kMaxSpeedMps);
  EXPECT_LE(max_rate, kMaxRateDegPerS);
  for (size_t i = 0; i < poses.size(); ++i) {
    const double z = poses[i].translation().z();
    ASSERT_GE(z, kMinEyeHeightM) << "frame " << i;
    ASSERT_LE(z, kMaxEyeHeightM) << "frame " << i;
    // Looking ahead and down: the optical axis (camera z) below the horizontal.
    const double down_deg = -std::asin(poses[i].linear()(2, 2)) * kRadToDeg;
    ASSERT_GT(down_deg, kMinLookDownDeg) << "frame " << i;
    ASSERT_LT(down_deg, kMaxLookDownDeg) << "frame " << i;
  }
}

TEST(SynthApartment, CameraKeepsClearOfEveryWallAndPiece) {
  const Scene s = makePreset("apartment");
  double nearest = std::numeric_limits<double>::infinity();
  int nearest_frame = -1;
  size_t nearest_static = 0;
  for (int i = 0; i < s.default_frames; ++i) {
    const Eigen::Vector3d c = s.camera.pose(s.timeOf(i)).translation();
    for (size_t k = 0; k < s.statics.size(); ++k) {
      const Eigen::Vector3d p = s.statics[k].T_parent_primitive.inverse() * c;
      const double d = signedDistance(s.statics[k].geometry, {p.x(), p.y(), p.z()});
      if (d < nearest) {
        nearest = d;
        nearest_frame = i;
        nearest_static = k;
      }
    }
  }
  EXPECT_GE(nearest, kMinClearanceM)
      << "frame " << nearest_frame << ", static " << nearest_static << " at "
      << s.statics[nearest_static].T_parent_primitive.translation().transpose();
}

TEST(SynthApartment, ViewsAlongTheLoopHaveStructureWithinRange) {
  const Scene s = makePreset("apartment");
  RenderOptions ro;
  ro.width = 160;
  ro.height = 120;
  const Renderer renderer(ro);
  for (int v = 0; v < kViewsChecked; ++v) {
    const int frame = v * (s.default_frames - 1) / kViewsChecked;
    RenderOutput r;
    renderer.render(s, s.camera.pose(s.timeOf(frame)), {}, &r);
    const int near = cv::countNonZero(r.depth <= kNearDepthM);  // NaN compares false
    EXPECT_GE(static_cast<double>(near) / r.depth.total(), kMinNearFraction) << "frame " << frame;
    EXPECT_GE(random_gen::normalSpread(r.depth, r.instance_ids, renderer.intrinsics()),
              kMinNormalSpread)
        << "frame " << frame;
  }
}

}  // namespace
}  // namespace emf::synth
