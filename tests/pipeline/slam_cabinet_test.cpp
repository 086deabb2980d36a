// The static SLAM loop on tum-fr3-cabinet-keyframes (58 real keyframes ~0.67 s apart, up to
// ~15 cm and several degrees between frames): it either tracks, or says which frames it lost
// and why; it never integrates a frame at a wrong pose (ISSUE 5: no silently wrong trajectory).
#include <cmath>

#include "core/frame_source.h"
#include "eval/eval.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

/// ATE RMSE bound of the frames reported as tracked (the target).
constexpr double kTrackedAteToleranceM = 0.05;
/// No integrated frame may be farther than this from the ground truth (both relative to the
/// first frame): a frame integrated farther off would corrupt the map.
constexpr double kIntegratedPoseToleranceM = 0.10;
constexpr double kIntegratedPoseToleranceDeg = 5.0;

TEST(SlamSystem, CabinetKeyframesTrackOrReportLostFrames) {
  Config config;  // defaults: 640x480, 1 cm voxels
  config.source.depth_scale = 5000;
  cl::Context ctx(config.cl);
  auto src =
      sources::openSource("tum:" + test::dataPath("tum-fr3-cabinet-keyframes"), config.source);
  SlamSystem slam(ctx, config, src->intrinsics());
  io::Trajectory gt_tracked, est_tracked;
  std::optional<Eigen::Isometry3d> T_gt0;
  core::Frame f;
  int frames = 0, lost = 0;
  double worst_integrated_m = 0, worst_integrated_deg = 0;
  while (src->next(f)) {
    ASSERT_TRUE(f.T_world_camera_gt.has_value()) << "frame " << f.index;
    if (!T_gt0) T_gt0 = *f.T_world_camera_gt;
    const Eigen::Isometry3d T_gt = T_gt0->inverse() * *f.T_world_camera_gt;  // world = frame 0
    const FrameOutcome o = slam.process(f);
    ++frames;
    {  // per-frame record (what the loss rules saw), printed for diagnosis
      const Eigen::Isometry3d E = T_gt.inverse() * o.T_world_camera;
      const track::TrackResult& t = o.track;
      std::printf(
          "frame %2lld %-5s err %.3f m %5.1f deg  valid %.2f inl %.2f cost/v %.2e "
          "icond %.1e it %3d conv %d motion %.3f m %4.1f deg %s\n",
          static_cast<long long>(o.index), o.lost ? "LOST" : "ok", E.translation().norm(),
          Eigen::AngleAxisd(E.rotation()).angle() * 180.0 / M_PI, t.valid_fraction, t.inlier_ratio,
          t.cost_per_valid, t.inverse_condition, t.iterations, t.converged ? 1 : 0, t.motion_m,
          t.motion_deg, trackLossName(t.loss));
    }
    if (o.lost) {
      ++lost;
      EXPECT_FALSE(o.loss_reason.empty()) << "frame " << o.index << " lost without a reason";
      EXPECT_NE(o.track.loss, track::TrackLoss::kNone) << "frame " << o.index;
      continue;
    }
    // Integrated at o.T_world_camera: it must be close to the truth.
    const Eigen::Isometry3d E = T_gt.inverse() * o.T_world_camera;
    const double err_m = E.translation().norm();
    const double err_deg = Eigen::AngleAxisd(E.rotation()).angle() * 180.0 / M_PI;
    worst_integrated_m = std::max(worst_integrated_m, err_m);
    worst_integrated_deg = std::max(worst_integrated_deg, err_deg);
    EXPECT_LT(err_m, kIntegratedPoseToleranceM) << "frame " << o.index << " integrated off";
    EXPECT_LT(err_deg, kIntegratedPoseToleranceDeg) << "frame " << o.index << " integrated off";
    gt_tracked.append(f.timestamp, T_gt);
    est_tracked.append(f.timestamp, o.T_world_camera);
  }
  EXPECT_EQ(frames, 58);
  EXPECT_EQ(slam.framesLost(), lost);
  // Tracked frames (all of them, or the ones not reported lost) are within the ATE target.
  ASSERT_GE(est_tracked.size(), eval::kMinAtePairs) << lost << " of " << frames << " frames lost";
  const eval::AteResult ate = eval::computeAte(gt_tracked, est_tracked);
  EXPECT_LT(ate.trans_m.rmse, kTrackedAteToleranceM);
  std::printf(
      "cabinet: %d frames, %d lost, ATE of tracked %.4f m, worst integrated %.4f m / "
      "%.2f deg\n",
      frames, lost, ate.trans_m.rmse, worst_integrated_m, worst_integrated_deg);
}

}  // namespace
}  // namespace emf::pipeline
