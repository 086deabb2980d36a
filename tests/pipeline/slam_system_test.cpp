// The static SLAM loop end to end on the synthetic room: camera ATE against the exact ground
// truth, and tracking loss handled (not integrated, last good pose kept).
#include "pipeline/slam_system.h"

#include <cmath>
#include <vector>

#include "core/frame_source.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr double kRecoveredToleranceM = 0.03;  // absolute drift after 11 frames, no alignment

Config smallConfig() {
  Config c;
  c.map.memory_mb = 64;
  c.map.background_voxel_m = 0.02;
  c.map.background_resolution = 256;
  return c;
}

TEST(SlamSystem, LostFrameIsNotIntegratedAndPoseIsKept) {
  const Config config = smallConfig();
  cl::Context ctx(config.cl);
  auto src = sources::openSource("synth:room?frames=12&width=320&height=240&seed=5", config.source);
  SlamSystem slam(ctx, config, src->intrinsics());
  core::Frame f;
  Eigen::Isometry3d T_gtworld_first = Eigen::Isometry3d::Identity();
  std::vector<FrameOutcome> tracked;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(src->next(f));
    if (i == 0) T_gtworld_first = *f.T_world_camera_gt;
    tracked.push_back(slam.process(f));
    ASSERT_FALSE(tracked.back().lost);
  }
  // The work counters hold one sample per frame: the camera's LM iterations (none on the
  // first frame, which is placed) and the blocks integrated (the background's listed blocks).
  const auto& iterations = slam.counters().samples("track_iterations");
  const auto& blocks = slam.counters().samples("integrated_blocks");
  ASSERT_EQ(iterations.size(), 10u);
  ASSERT_EQ(blocks.size(), 10u);
  EXPECT_EQ(iterations[0], 0.0);
  for (size_t i = 0; i < tracked.size(); ++i) {
    if (i > 0) {
      EXPECT_EQ(iterations[i], tracked[i].track.iterations) << "frame " << i;
    }
    EXPECT_GT(blocks[i], 0.0) << "frame " << i;
    EXPECT_EQ(blocks[i], tracked[i].allocation.listed_blocks) << "frame " << i;
  }
  EXPECT_EQ(slam.counters().samples("object_track_iterations"), std::vector<double>(10, 0.0));
  const Eigen::Isometry3d before = slam.T_world_camera();
  const int used_before = slam.pool().stats().used_slots;
  // A frame of nothing but invalid depth: no evidence at all.
  core::Frame blank = f;
  blank.depth.setTo(std::nanf(""));
  const FrameOutcome lost = slam.process(blank);
  EXPECT_TRUE(lost.lost);
  EXPECT_FALSE(lost.loss_reason.empty());
  EXPECT_TRUE(lost.T_world_camera.isApprox(before, 1e-12));
  EXPECT_EQ(slam.pool().stats().used_slots, used_before);
  EXPECT_EQ(slam.framesLost(), 1);
  // The lost frame tracked (its iterations count) but integrated nothing.
  EXPECT_EQ(slam.counters().samples("track_iterations").back(), lost.track.iterations);
  EXPECT_EQ(slam.counters().samples("integrated_blocks").back(), 0.0);
  // The next real frame tracks again.
  ASSERT_TRUE(src->next(f));
  const FrameOutcome back = slam.process(f);
  EXPECT_FALSE(back.lost) << back.loss_reason;
  // The SLAM world is the first camera's frame.
  const Eigen::Isometry3d T_first_camera_gt = T_gtworld_first.inverse() * *f.T_world_camera_gt;
  EXPECT_LT((back.T_world_camera.translation() - T_first_camera_gt.translation()).norm(),
            kRecoveredToleranceM);
}

TEST(SlamSystem, WrongFrameSizeNamesTheFrame) {
  const Config config = smallConfig();
  cl::Context ctx(config.cl);
  core::Intrinsics k;
  k.fx = k.fy = 262.5;
  k.cx = 159.5;
  k.cy = 119.5;
  k.width = 320;
  k.height = 240;
  SlamSystem slam(ctx, config, k);
  core::Frame f;
  f.index = 7;
  f.depth = cv::Mat(480, 640, CV_32F, cv::Scalar(1.0f));
  try {
    slam.process(f);
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 7"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace emf::pipeline
