// A held object that moves on: a box slides half behind a static panel, is held there as hidden,
// and slides back out, past where it was. Its held pose stays half behind the panel; the part of
// it in front of the panel then shows the wall behind (em::movedOn), so the box is no longer held
// but lost, and tracked again where it is (by itself, or from the next detection), as one object
// with its id. Without the rule it stays held 0.5 m from the box until the detection.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 110;
constexpr int kBoxId = 1;
constexpr int kDetectionFrame = 90;  // the only detection after frame 0
// The box's moves (s): right into the panel's shadow, then back out of it and on, 0.5 m in all:
// its held pose's part in front of the panel then shows the wall behind.
constexpr double kInStart = 0.5, kInEnd = 1.5, kOutStart = 2.0, kOutEnd = 2.8;
constexpr double kOutM = 0.5;
constexpr int kFps = 30;
// After the detection, the bound on the error of the box's centre (seen from the camera)
// against the truth: tracked where it is, not at its held pose 0.5 m away.
constexpr double kMaxErrorAfterM = 0.03;

synth::Scene slideBackScene() {
  using synth::at;
  synth::Scene s = test_scene::boxRoomScene("slide-back", kBoxId, -0.3, 0.6);
  // A panel 0.6 m wide and 1 m tall, 0.6 m in front of the box's path: its shadow on the box's
  // plane starts at x ~ 0.14 m.
  s.statics.push_back(synth::makeBox({0.3, 0.025, 0.5}, at(0.4, 0.0, 0.5),
                                     test_scene::solidMaterial(0.7f, 0.2f, 0.2f)));
  synth::SceneObject& box = s.objects.front();
  box.trajectory.moves.push_back(
      {kInStart, kInEnd, Eigen::Vector3d(0.5, 0, 0), Eigen::Vector3d::Zero()});
  box.trajectory.moves.push_back(
      {kOutStart, kOutEnd, Eigen::Vector3d(-kOutM, 0, 0), Eigen::Vector3d::Zero()});
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  s.camera.path.position_terms.push_back({Eigen::Vector3d(0.05, 0, 0.02), 0.4, 0.0});
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.default_frames = kFrames;
  return s;
}

struct BoxRun {
  std::vector<ObjectState> states;  // the box's state per frame (kDeleted when absent)
  std::vector<double> error_m;      // its position error per frame (NaN before it is known)
  std::vector<int> other_ids;       // ids of any other object
};

BoxRun runScene() {
  Config config = test_scene::smallSceneConfig();
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, slideBackScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  BoxRun run;
  core::Frame f;
  // The box's centre (its frame), seen from the camera, estimated against true; the estimate's
  // frame is mapped onto the true one on frame 10 (tracked, still).
  test_scene::PointError point_error(kBoxId, Eigen::Vector3d(0, 0, 0.2));
  bool mapped = false;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    const bool detect = f.index == 0 || f.index == kDetectionFrame;
    if (detect) dets.push_back(test_scene::exactDetection(f, kBoxId));
    const FrameOutcome out = slam.process(f, detect ? &dets : nullptr);
    ObjectState state = ObjectState::kDeleted;
    double error = std::nan("");
    for (const ObjectOutcome& o : out.objects) {
      if (o.id != kBoxId) {
        if (o.state != ObjectState::kDeleted) run.other_ids.push_back(o.id);
        continue;
      }
      state = o.state;
      if (f.index == 10 && state == ObjectState::kTracked) mapped = true;
      if (mapped) error = point_error(f, o.T_object_camera);
    }
    run.states.push_back(state);
    run.error_m.push_back(error);
  }
  return run;
}

TEST(SlamMovedOn, AHeldObjectThatMovesOnIsReleasedAndTrackedAgainWhereItIs) {
  const BoxRun run = runScene();
  ASSERT_EQ(run.states.size(), static_cast<size_t>(kFrames));
  EXPECT_TRUE(run.other_ids.empty()) << "another object, id " << run.other_ids.front();
  // Held as hidden while it stands half behind the panel.
  const auto standing = static_cast<size_t>((kInEnd + kOutStart) / 2 * kFps);
  EXPECT_EQ(run.states[standing], ObjectState::kInvisible);
  // Released once it has slid out: lost on some frame before the detection (then tracked again
  // by itself, or re-identified by the detection).
  bool released = false;
  for (auto i = standing; i < static_cast<size_t>(kDetectionFrame); ++i) {
    released = released || run.states[i] == ObjectState::kLost;
  }
  EXPECT_TRUE(released);
  // From the detection on (at the latest), tracked where it is.
  for (size_t i = kDetectionFrame + 1; i < run.states.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(run.states[i], ObjectState::kTracked);
    EXPECT_LT(run.error_m[i], kMaxErrorAfterM);
  }
}

}  // namespace
}  // namespace emf::pipeline
