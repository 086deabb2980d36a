// The leaving rule (objects.leaving_fraction) in the running SLAM: a box slides sideways out of
// the view of a still camera. Once less than half of its projection is inside the image it is
// held instead of tracked; without the rule (0, the paper) the sliver left in view lets its
// pose slide along the image border before it is deleted.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 90;
constexpr int kBoxId = 1;
const Eigen::Vector3d kBoxCentre(0, 0, 0.2);  // in the box's frame (box_room_scene.h)
// The box centre's error while tracked during the slide (from kFirstScoredFrame, once the box
// slides): small with the rule, large without (its last tracked frames slide along the border).
// The frames before are the slow start of a box that stood still: there the still hold's lag
// (objects.still_translation_m, tests/pipeline/slam_still_test.cpp) is what shows, not the
// leaving rule.
constexpr int kFirstScoredFrame = 30;
constexpr double kHeldMaxErrorM = 0.005;
constexpr double kSlidingMinErrorM = 0.01;
// Frames the box is held before it is deleted (its model no longer explains the pixels it
// covers: mean association below 0.1): 14-15 over seeds 1-6.
constexpr int kMinHeldFrames = 8, kMaxHeldFrames = 25;
// The rule costs the frames of the last sliver: 55 tracked with it, 61-70 without.
constexpr int kMinTrackedFrames = 50;

synth::Scene slidingBoxScene() {
  // The camera stands still 2.3 m from the box; between 0.3 s and 3.0 s the box slides 1 m to
  // the left (up to ~2.5 cm per frame) and turns by 0.5 rad, leaving through the left image
  // border on frames ~50-62.
  synth::Scene s = test_scene::boxRoomScene("sliding-box", kBoxId, -0.8, 0.6);
  s.objects.back().trajectory.moves.push_back(
      {0.3, 3.0, Eigen::Vector3d(-1.0, 0, 0), Eigen::Vector3d(0, 0, -0.5)});
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.default_frames = kFrames;
  return s;
}

struct BoxRun {
  int lost_frames = 0;  // camera
  int tracked_frames = 0, held_frames = 0;
  bool held_pose_moved = false;  // a held pose changed in the world between held frames
  int deleted_frame = -1;
  std::string deleted_reason;
  double max_error_m = 0;   // the box centre's error in the world while tracked, from
  double mean_error_m = 0;  // kFirstScoredFrame on
};

BoxRun runScene(double leaving_fraction) {
  Config config = test_scene::smallSceneConfig();
  config.objects.leaving_fraction = leaving_fraction;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, slidingBoxScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  BoxRun run;
  core::Frame f;
  test_scene::PointError centre_error(kBoxId, kBoxCentre);
  Eigen::Isometry3d T_world_held = Eigen::Isometry3d::Identity();
  double error_sum = 0;
  int scored_frames = 0;
  while (src.next(f) && run.deleted_frame < 0) {
    std::vector<core::Detection> dets;
    if (f.index == 0) dets.push_back(test_scene::exactDetection(f, kBoxId));
    const FrameOutcome out = slam.process(f, f.index == 0 ? &dets : nullptr);
    if (out.lost) ++run.lost_frames;
    for (const ObjectOutcome& o : out.objects) {
      if (o.id != kBoxId) continue;
      // Retired by a rule: dormant (objects.reidentify_frames) or deleted.
      if (o.state == ObjectState::kDeleted || o.state == ObjectState::kDormant) {
        run.deleted_frame = static_cast<int>(f.index);
        run.deleted_reason = o.deleted_reason;
      }
      if (o.state == ObjectState::kInvisible) {
        if (run.held_frames++ > 0 && !o.T_world_object.isApprox(T_world_held, 1e-12)) {
          run.held_pose_moved = true;
        }
        T_world_held = o.T_world_object;
      }
      if (o.state != ObjectState::kTracked) continue;
      ++run.tracked_frames;
      if (f.index < kFirstScoredFrame) continue;
      const double e = centre_error(f, o.T_object_camera);
      run.max_error_m = std::max(run.max_error_m, e);
      error_sum += e;
      ++scored_frames;
    }
  }
  if (scored_frames > 0) run.mean_error_m = error_sum / scored_frames;
  return run;
}

TEST(SlamLeaving, AnObjectLeavingTheViewIsHeldInsteadOfSlidingAlongTheBorder) {
  const BoxRun held = runScene(0.5);  // the rule on (off by default, the paper)
  const BoxRun sliding = runScene(0.0);
  for (const auto& [name, r] :
       {std::pair<const char*, const BoxRun&>{"with the rule", held}, {"without", sliding}}) {
    std::printf(
        "%s: tracked %d, held %d, deleted on frame %d (%s); box error max %.2f cm, "
        "mean %.2f cm\n",
        name, r.tracked_frames, r.held_frames, r.deleted_frame, r.deleted_reason.c_str(),
        r.max_error_m * 100, r.mean_error_m * 100);
  }
  EXPECT_EQ(held.lost_frames, 0);
  EXPECT_EQ(sliding.lost_frames, 0);
  EXPECT_GE(held.tracked_frames, kMinTrackedFrames);
  EXPECT_LT(held.max_error_m, kHeldMaxErrorM);
  EXPECT_GT(sliding.max_error_m, kSlidingMinErrorM) << "the scene must show the slide";
  EXPECT_EQ(sliding.held_frames, 0);
  // Held still, then deleted: the model of a mover that left does not stay.
  EXPECT_GE(held.held_frames, kMinHeldFrames);
  EXPECT_LE(held.held_frames, kMaxHeldFrames);
  EXPECT_FALSE(held.held_pose_moved);
  ASSERT_GE(held.deleted_frame, 0) << "the box was never deleted";
  EXPECT_EQ(held.deleted_frame, held.tracked_frames + held.held_frames) << held.deleted_reason;
}

}  // namespace
}  // namespace emf::pipeline
