// Presets: every preset renders; camera motion is hand-held-like (speed and rotation per frame
// bounded); objects are visible for long stretches; each preset's documented events happen.
#include "synth/presets.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "common/error.h"
#include "synth/synth_source.h"

namespace emf::synth {
namespace {

constexpr double kRadToDeg = 57.29577951308232;

/// Per frame, the pixel count of every object id (64x48, exact depth, no detections).
std::vector<std::vector<int>> pixelCounts(const std::string& preset, int* min_pixels) {
  SynthOptions o;
  o.preset = preset;
  o.width = 64;
  o.height = 48;
  o.noise = false;
  o.detector.every_n_frames = 0;
  SynthSource src(o);
  *min_pixels = minVisiblePixels(64, 48);
  std::vector<std::vector<int>> counts;
  core::Frame f;
  while (src.next(f)) {
    std::vector<int> c = instancePixelCounts(f.instance_ids);
    c.resize(src.scene().objects.size() + 1, 0);
    counts.push_back(c);
  }
  return counts;
}

int longestVisibleRun(const std::vector<std::vector<int>>& counts, int id, int min_pixels) {
  int best = 0, run = 0;
  for (const auto& c : counts) {
    run = c[static_cast<size_t>(id)] >= min_pixels ? run + 1 : 0;
    best = std::max(best, run);
  }
  return best;
}

double translationBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}
double rotationDegBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * kRadToDeg;
}

TEST(SynthPresets, UnknownPresetListsValidOnes) {
  try {
    makePreset("garden");
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown preset 'garden': valid presets are room, cars, "
                                         "occlusion, enter, apartment"),
              std::string::npos)
        << e.what();
  }
}

TEST(SynthPresets, CameraMovesLikeAHandHeldSensor) {
  for (const auto& name : presetNames()) {
    const Scene s = makePreset(name);
    double max_speed = 0, sum_speed = 0, max_rot_deg = 0;
    for (int i = 1; i < s.default_frames; ++i) {
      const auto a = s.camera.pose(s.timeOf(i - 1)), b = s.camera.pose(s.timeOf(i));
      const double speed = translationBetween(a, b) * s.fps;
      max_speed = std::max(max_speed, speed);
      sum_speed += speed;
      max_rot_deg = std::max(max_rot_deg, rotationDegBetween(a, b));
    }
    const double mean_speed = sum_speed / (s.default_frames - 1);
    EXPECT_LT(max_speed, 0.5) << name;
    EXPECT_GT(mean_speed, 0.15) << name;
    EXPECT_LT(max_rot_deg, 1.5) << name;
    EXPECT_GT(max_rot_deg, 0.1) << name;
  }
}

TEST(SynthPresets, RoomIsStatic) {
  const Scene s = makePreset("room");
  EXPECT_TRUE(s.objects.empty());
  EXPECT_GT(s.statics.size(), 20u);
  SynthOptions o;
  o.preset = "room";
  o.width = 64;
  o.height = 48;
  o.noise = false;
  SynthSource src(o);
  EXPECT_EQ(src.size(), 300);
  for (int64_t i = 0; i < 300; i += 10) {
    core::Frame f;
    src.renderFrame(i, &f);
    EXPECT_EQ(cv::countNonZero(f.instance_ids), 0) << i;  // every pixel is static scene
    EXPECT_TRUE(f.T_world_object_gt.empty());
    EXPECT_TRUE(f.detections.has_value() == (i % 30 == 0));
    for (const auto& d : f.detections.value_or(std::vector<core::Detection>{})) {
      EXPECT_LE(d.score, 0.75f);  // nothing to detect: only false positives
    }
  }
}

TEST(SynthPresets, CarsDriveAndStayInView) {
  const Scene s = makePreset("cars");
  ASSERT_EQ(s.objects.size(), 2u);
  for (const auto& car : s.objects) {
    EXPECT_EQ(car.class_name, "car");
    for (int i = 1; i < s.default_frames; ++i) {
      const auto a = car.trajectory.pose(s.timeOf(i - 1)), b = car.trajectory.pose(s.timeOf(i));
      EXPECT_GT(translationBetween(a, b) * s.fps, 0.1) << "car " << car.id << " frame " << i;
      EXPECT_LT(translationBetween(a, b) * s.fps, 0.45) << "car " << car.id << " frame " << i;
      // On the floor, pointing where it drives.
      EXPECT_NEAR(b.translation().z(), 0.0, 0.004);
      const Eigen::Vector3d v = b.translation() - a.translation();
      const Eigen::Vector3d forward = b.linear().col(0);
      EXPECT_GT(forward.head<2>().normalized().dot(v.head<2>().normalized()), 0.98);
    }
  }
  int min_pixels = 0;
  const auto counts = pixelCounts("cars", &min_pixels);
  EXPECT_GE(longestVisibleRun(counts, 1, min_pixels), 60);
  EXPECT_GE(longestVisibleRun(counts, 2, min_pixels), 60);
}

TEST(SynthPresets, OcclusionEventsHappenAsDocumented) {
  const Scene s = makePreset("occlusion");
  ASSERT_EQ(s.objects.size(), 3u);
  const auto& bear = s.objects[0];
  const auto& bag = s.objects[1];
  const auto& chair = s.objects[2];
  EXPECT_EQ(bear.class_name, "teddy bear");
  EXPECT_EQ(bag.class_name, "suitcase");
  EXPECT_EQ(chair.class_name, "chair");
  auto moved = [&](const SceneObject& o, int f0, int f1) {
    const auto a = o.trajectory.pose(s.timeOf(f0)), b = o.trajectory.pose(s.timeOf(f1));
    return translationBetween(a, b) + rotationDegBetween(a, b) / kRadToDeg;
  };
  EXPECT_GT(moved(bear, 0, 30), 0.05);     // flies from the start
  EXPECT_EQ(moved(bag, 0, 59), 0.0);       // still before 2 s
  EXPECT_GT(moved(bag, 60, 150), 1.0);     // slides in
  EXPECT_EQ(moved(bag, 150, 270), 0.0);    // waits in front of the chair
  EXPECT_GT(moved(bag, 270, 360), 1.0);    // slides out
  EXPECT_EQ(moved(chair, 0, 390), 0.0);    // still until 13 s
  EXPECT_GT(moved(chair, 390, 450), 0.1);  // then moves
  EXPECT_GT(moved(chair, 450, 599), 0.1);

  int min_pixels = 0;
  const auto counts = pixelCounts("occlusion", &min_pixels);
  for (int id : {1, 2, 3}) EXPECT_GE(longestVisibleRun(counts, id, min_pixels), 60) << id;
  // The suitcase hides most of the chair while it stands in front of it (6-8.5 s) compared
  // with before it arrives (0-1.5 s).
  int before = 1 << 30, during = 1 << 30;
  for (int i = 0; i < 45; ++i) before = std::min(before, counts[static_cast<size_t>(i)][3]);
  for (int i = 180; i < 255; ++i) during = std::min(during, counts[static_cast<size_t>(i)][3]);
  EXPECT_GT(before, 4 * min_pixels);
  EXPECT_LT(during, before / 2) << "before " << before << " during " << during;
}

TEST(SynthPresets, EnterBringsALargeObjectInThroughTheBorder) {
  const Scene s = makePreset("enter");
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].class_name, "couch");
  SynthOptions o;
  o.preset = "enter";
  o.width = 64;
  o.height = 48;
  o.noise = false;
  o.detector.every_n_frames = 0;
  SynthSource src(o);
  const int min_pixels = minVisiblePixels(64, 48);
  core::Frame f;
  int first_visible = -1, run = 0, best_run = 0, max_pixels = 0;
  while (src.next(f)) {
    const auto c = instancePixelCounts(f.instance_ids);
    const int n = c.size() > 1 ? c[1] : 0;
    max_pixels = std::max(max_pixels, n);
    run = n >= min_pixels ? run + 1 : 0;
    best_run = std::max(best_run, run);
    if (n > 0 && first_visible < 0) {
      first_visible = static_cast<int>(f.index);
      // It appears at the right image border.
      EXPECT_GT(cv::countNonZero(f.instance_ids.col(63) == 1), 0);
      EXPECT_EQ(cv::countNonZero(f.instance_ids.colRange(0, 32) == 1), 0);
    }
  }
  EXPECT_GT(first_visible, 30);  // out of view at the start
  EXPECT_GE(best_run, 60);
  EXPECT_GT(max_pixels, 64 * 48 / 5);  // large: over a fifth of the image
}

}  // namespace
}  // namespace emf::synth
