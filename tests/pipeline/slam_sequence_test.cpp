// The static SLAM loop on a 40-frame synthetic room: camera ATE against the exact ground truth.
#include "core/frame_source.h"
#include "eval/eval.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr double kSynthRoomAteToleranceM = 0.01;  // ATE at 2 cm voxels, 320x240 (bench: 1 cm)

Config smallConfig() {
  Config c;
  c.map.memory_mb = 64;
  c.map.background_voxel_m = 0.02;
  c.map.background_resolution = 256;
  return c;
}

TEST(SlamSystem, TracksTheSyntheticRoom) {
  const Config config = smallConfig();
  cl::Context ctx(config.cl);
  auto src = sources::openSource("synth:room?frames=40&width=320&height=240&seed=3", config.source);
  SlamSystem slam(ctx, config, src->intrinsics());
  io::Trajectory gt, est;
  core::Frame f;
  while (src->next(f)) {
    const FrameOutcome o = slam.process(f);
    ASSERT_FALSE(o.lost) << "frame " << o.index << ": " << o.loss_reason;
    ASSERT_TRUE(f.T_world_camera_gt.has_value());
    gt.append(f.timestamp, *f.T_world_camera_gt);
    est.append(f.timestamp, o.T_world_camera);
  }
  EXPECT_EQ(slam.framesProcessed(), 40);
  EXPECT_EQ(slam.framesLost(), 0);
  const eval::AteResult ate = eval::computeAte(gt, est);
  EXPECT_LT(ate.trans_m.rmse, kSynthRoomAteToleranceM);
  EXPECT_GT(slam.pool().stats().used_slots, 0);
  EXPECT_EQ(slam.pool().stats().dropped_blocks, 0);
  const auto t = slam.timer().summary();
  EXPECT_EQ(t.at("total").count, 40);
}

}  // namespace
}  // namespace emf::pipeline
