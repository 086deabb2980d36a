#include "pipeline/frame_counters.h"
#include "pipeline/object_settings.h"
#include "pipeline/progress.h"
#include "pipeline/slam_system.h"
#include "pipeline/stage_timer.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

TEST(StageTimer, MedianP90AndTotal) {
  StageTimer t({"track", "integrate"}, 16);
  for (int i = 1; i <= 10; ++i) {
    t.add("track", i);
    t.add("integrate", 2 * i);
    t.add("integrate", 1);  // accumulates within a frame
    t.endFrame();
  }
  const auto s = t.summary();
  EXPECT_DOUBLE_EQ(s.at("track").median_ms, 5.5);
  EXPECT_DOUBLE_EQ(s.at("track").p90_ms, 9.0);   // nearest rank: ceil(0.9 * 10) = 9th
  EXPECT_DOUBLE_EQ(s.at("track").p99_ms, 10.0);  // ceil(0.99 * 10) = 10th
  EXPECT_DOUBLE_EQ(s.at("track").max_ms, 10.0);
  EXPECT_DOUBLE_EQ(s.at("integrate").mean_ms, 12.0);
  EXPECT_DOUBLE_EQ(s.at("total").median_ms, 3 * 5.5 + 1);
  EXPECT_EQ(s.at("total").count, 10);
  EXPECT_THROW(t.add("nope", 1), InvalidArgument);
}

TEST(StageTimer, SummaryOfOddAndEmpty) {
  EXPECT_DOUBLE_EQ(summarize({3, 1, 2}).median_ms, 2.0);
  EXPECT_EQ(summarize({}).count, 0);
}

TEST(FrameCounters, SumsPerFrameAndSummarises) {
  FrameCounters c({"iterations", "blocks"}, 4);
  for (int i = 1; i <= 10; ++i) {
    c.add("iterations", i);
    c.add("iterations", 1);  // accumulates within a frame
    if (i % 2 == 0) c.add("blocks", 100 * i);
    c.endFrame();
  }
  const auto s = c.summary();
  EXPECT_DOUBLE_EQ(s.at("iterations").median, 6.5);
  EXPECT_DOUBLE_EQ(s.at("iterations").p90, 10.0);
  EXPECT_DOUBLE_EQ(s.at("iterations").max, 11.0);
  EXPECT_DOUBLE_EQ(s.at("blocks").mean, 300.0);  // untouched frames count as 0
  EXPECT_EQ(s.at("blocks").count, 10);
  EXPECT_EQ(c.samples("blocks")[0], 0.0);
  EXPECT_EQ(c.samples("blocks")[1], 200.0);
  EXPECT_THROW(c.add("nope", 1), InvalidArgument);
  EXPECT_THROW(c.samples("nope"), InvalidArgument);
}

TEST(ProgressLine, FormatsRateAndEta) {
  EXPECT_EQ(Progress::format(50, 300, 10.0, ""), "frame 50/300  5.0 frames/s  ETA 00:50");
  EXPECT_EQ(Progress::format(30, -1, 2.0, "lost 1"), "frame 30  15.0 frames/s  lost 1");
}

TEST(ObjectTrackOptions, ObjectsKeepTheirOwnHuberDeltaAndRules) {
  Config config;
  config.track.huber_truncation_factor = 0.05;
  config.objects.huber_truncation_factor = 0.2;
  config.track.pixel_stride = 2;
  const track::TrackOptions o = objectTrackOptions(config, 640);
  EXPECT_DOUBLE_EQ(o.huber_truncation_factor, 0.2);
  EXPECT_DOUBLE_EQ(o.inlier_truncation_factor, config.track.inlier_truncation_factor);
  EXPECT_EQ(o.pixel_stride, 1);
  EXPECT_EQ(o.step_acceptance, track::StepAcceptance::kFixedWeights);
  EXPECT_DOUBLE_EQ(o.min_valid_fraction, 0.0);
  // No recovery bound on the motion beyond every call's: a lost object may have moved on.
  EXPECT_DOUBLE_EQ(o.recovery_max_motion_m, config.track.max_motion_m);
  EXPECT_DOUBLE_EQ(o.recovery_max_motion_deg, config.track.max_motion_deg);
  EXPECT_LT(config.track.recovery_max_motion_deg, config.track.max_motion_deg);  // the camera's
  // The defaults: the camera's tight delta, the objects' the paper's.
  EXPECT_LT(Config{}.track.huber_truncation_factor,
            objectTrackOptions(Config{}, 640).huber_truncation_factor);
}

TEST(ObjectTrackOptions, RotationPriorScalesWithTheImageArea) {
  Config config;
  config.objects.motion_prior_rotation = 3.0;
  EXPECT_DOUBLE_EQ(objectTrackOptions(config, 640).prior_rotation_weight, 3.0);
  EXPECT_DOUBLE_EQ(objectTrackOptions(config, 320).prior_rotation_weight, 0.75);
  EXPECT_DOUBLE_EQ(objectTrackOptions(config, 1280).prior_rotation_weight, 12.0);
  EXPECT_DOUBLE_EQ(objectTrackOptions(config, 640).prior_translation_weight, 0.0);
  // The camera has no prior.
  EXPECT_DOUBLE_EQ(config.track.prior_rotation_weight, 0.0);
  config.objects.motion_prior_rotation = 0.0;
  EXPECT_DOUBLE_EQ(objectTrackOptions(config, 640).prior_rotation_weight, 0.0);
}

TEST(ObjectSettings, EverythingTheObjectsDeriveComesFromOnePlace) {
  Config config;
  config.objects.min_detection_px = 40;
  config.objects.invisible_min_px = 1600;
  config.objects.visibility_border_px = 20;
  config.objects.visibility_width = 160;
  config.track.rotation_centre = track::RotationCentre::kCamera;
  core::Intrinsics k;
  k.width = 320;
  k.height = 240;
  k.fx = k.fy = 262.5;
  k.cx = 159.5;
  k.cy = 119.5;
  const ObjectSettings s = deriveObjectSettings(config, k);
  // Pixel thresholds given for 640 px: lengths with the width, areas with its square.
  EXPECT_EQ(s.rules.min_detection_px, 20);
  EXPECT_EQ(s.rules.visibility_border_px, 10);
  EXPECT_EQ(s.rules.invisible_min_px, 400);
  EXPECT_EQ(s.visibility_rules.visibility_border_px, 5);
  EXPECT_EQ(s.visibility_rules.invisible_min_px, 100);
  // The visibility cast at objects.visibility_width, the frame's aspect kept.
  EXPECT_EQ(s.visibility_k.width, 160);
  EXPECT_EQ(s.visibility_k.height, 120);
  EXPECT_DOUBLE_EQ(s.visibility_k.fx, k.fx / 2);
  // The leaving test: the frame at half size in the middle of a frame-sized cast.
  EXPECT_EQ(s.wide_frame, cv::Rect(80, 60, 160, 120));
  EXPECT_EQ(s.wide_k.width, 320);
  EXPECT_EQ(s.wide_k.height, 240);
  EXPECT_DOUBLE_EQ(s.wide_k.fx, k.fx / 2);
  // Tracking: the camera's keys with the objects' own, whatever track.* says.
  EXPECT_EQ(s.track.rotation_centre, track::RotationCentre::kStiffness);
  EXPECT_EQ(s.track.step_acceptance, track::StepAcceptance::kFixedWeights);
  EXPECT_DOUBLE_EQ(s.track.max_motion_m, config.track.max_motion_m);
  EXPECT_DOUBLE_EQ(s.reid_track.max_motion_m, 100.0);
  EXPECT_DOUBLE_EQ(s.reid_track.prior_rotation_weight, 0.0);
  EXPECT_EQ(s.reid_track.rotation_centre, track::RotationCentre::kStiffness);
  // A visibility width above the frame's is the frame's.
  config.objects.visibility_width = 1280;
  EXPECT_EQ(deriveObjectSettings(config, k).visibility_k.width, 320);
}

}  // namespace
}  // namespace emf::pipeline
