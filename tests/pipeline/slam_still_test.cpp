// Still objects (objects.still_translation_m, still_release_cost) in the running SLAM: a box
// stands on the floor for 2 s, then is pushed 40 cm in 1 s and stands again. Held, its pose does
// not change while it stands; the push releases it and it is tracked to its new place.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 120;         // 4 s at 30 Hz
constexpr int kPushFirstFrame = 60;  // the push: 2.0-3.0 s
constexpr int kPushLastFrame = 90;
constexpr int kBoxId = 1;
const Eigen::Vector3d kBoxCentre(0, 0, 0.2);  // in the box's frame (box_room_scene.h)

constexpr double kStillBoundM = 0.02;  // objects.still_translation_m under test
constexpr double kReleaseCost = 0.2;   // objects.still_release_cost under test
// Held on every still frame before the push once the first still_frames (15) have been tracked
// to judge it (44 frames: 16-59), less two for a window that ends a frame or two later: a noise
// excursion beyond the bounds does not fit the depth enough better to release it
// (objects.still_release_cost; this near box's excursions stay within the bounds anyway).
constexpr int kMinHeldBeforePush = kPushFirstFrame - 15 - 3;
// The box centre's error (m) on the last frame, after the push: tracked to its new place
// (measured: docs/benchmarks.md, "A box seen square-on").
constexpr double kMaxFinalErrorM = 0.01;
// What holding costs during the push, over the same run without still objects: the frames it
// takes to release the box (its pose lags) and the model fused at the held pose meanwhile
// (measured: docs/benchmarks.md, still objects).
constexpr double kMaxReleaseLagM = 0.005;

synth::Scene pushedBoxScene() {
  synth::Scene s = test_scene::boxRoomScene("pushed-box", kBoxId, 0.2, 0.6);
  // Turned by kBoxYawRad so that the camera sees two of its sides (test_scene::kBoxYawRad).
  s.objects.back().trajectory.R0 = test_scene::yawed(test_scene::kBoxYawRad);
  s.objects.back().trajectory.moves.push_back(
      {2.0, 3.0, Eigen::Vector3d(-0.4, 0, 0), Eigen::Vector3d(0, 0, 0.3)});
  // The camera stands still 2.3 m from the box.
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.default_frames = kFrames;
  return s;
}

struct BoxRun {
  int tracked_frames = 0;
  int held_before_push = 0;      // tracked frames before the push with the last frame's pose
  int held_during_push = 0;      // ... during the push
  double final_error_m = -1.0;   // the box centre's error on the last frame
  double max_still_error_m = 0;  // ... largest before the push
  double max_push_error_m = 0;   // ... largest during the push
};

BoxRun runScene(double still_translation_m, double still_release_cost) {
  Config config = test_scene::smallSceneConfig();
  config.objects.still_translation_m = still_translation_m;
  config.objects.still_release_cost = still_release_cost;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, pushedBoxScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  BoxRun run;
  core::Frame f;
  test_scene::PointError centre_error(kBoxId, kBoxCentre);
  Eigen::Isometry3d T_world_last = Eigen::Isometry3d::Identity();
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    if (f.index == 0) dets.push_back(test_scene::exactDetection(f, kBoxId));
    const FrameOutcome out = slam.process(f, f.index == 0 ? &dets : nullptr);
    EXPECT_FALSE(out.lost) << "frame " << f.index;
    for (const ObjectOutcome& o : out.objects) {
      if (o.id != kBoxId || o.state != ObjectState::kTracked) continue;
      const double e = centre_error(f, o.T_object_camera);
      const bool held = run.tracked_frames > 0 && o.T_world_object.isApprox(T_world_last, 1e-12);
      if (f.index < kPushFirstFrame) {
        run.max_still_error_m = std::max(run.max_still_error_m, e);
        run.held_before_push += held;
      } else if (f.index <= kPushLastFrame) {
        run.held_during_push += held;
        run.max_push_error_m = std::max(run.max_push_error_m, e);
      }
      run.final_error_m = e;
      T_world_last = o.T_world_object;
      ++run.tracked_frames;
    }
  }
  return run;
}

TEST(SlamStill, AStandingBoxIsHeldAndAPushReleasesIt) {
  const BoxRun held = runScene(kStillBoundM, kReleaseCost);
  const BoxRun tracked = runScene(0.0, 0.0);  // off (the paper)
  for (const auto& [name, r] :
       {std::pair<const char*, const BoxRun&>{"still objects", held}, {"off", tracked}}) {
    std::printf(
        "%s: tracked %d, held %d before the push and %d during it; box error max %.2f cm "
        "before the push, %.2f cm during it, %.2f cm at the end\n",
        name, r.tracked_frames, r.held_before_push, r.held_during_push, r.max_still_error_m * 100,
        r.max_push_error_m * 100, r.final_error_m * 100);
  }
  EXPECT_EQ(held.tracked_frames, kFrames);
  EXPECT_EQ(tracked.tracked_frames, kFrames);
  EXPECT_GE(held.held_before_push, kMinHeldBeforePush);
  EXPECT_EQ(tracked.held_before_push, 0) << "off: every tracked pose is taken";
  // The push moves it about 1.3 cm per frame: held on fewer frames than it moves.
  EXPECT_LT(held.held_during_push, (kPushLastFrame - kPushFirstFrame) / 2);
  EXPECT_LT(held.max_push_error_m, tracked.max_push_error_m + kMaxReleaseLagM);
  EXPECT_LT(held.final_error_m, kMaxFinalErrorM);
  EXPECT_LT(held.max_still_error_m, kStillBoundM);
}

}  // namespace
}  // namespace emf::pipeline
