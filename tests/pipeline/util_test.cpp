#include "pipeline/frame_counters.h"
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
  EXPECT_DOUBLE_EQ(s.at("track").p90_ms, 9.0);  // nearest rank: ceil(0.9 * 10) = 9th
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
  EXPECT_EQ(o.step_acceptance, "fixed_weights");
  EXPECT_DOUBLE_EQ(o.min_valid_fraction, 0.0);
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

}  // namespace
}  // namespace emf::pipeline
