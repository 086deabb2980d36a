// Occlusion in the running SLAM: a box standing on the floor, detected on frame 0, is covered
// for about a second by an undetected panel that slides past in front of it (outside the box's
// volume), then uncovered. The box must be held (hidden: not tracked, not deleted) while covered
// and tracked again at the same place afterwards. With the hidden rule off (the paper's
// behaviour) the covered box is lost and deleted.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
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
constexpr int kBoxId = 1, kPanelId = 2;
// The panel covers the box fully on frames ~24-54 (eased moves 0.3-0.8 s in, 1.8-2.3 s out).
constexpr int kCoveredFirst = 28, kCoveredLast = 50;
constexpr int kUncoveredFrom = 75;
// Of the fully covered frames, at least this fraction must hold the box (the hidden state
// follows the check of the previous frame, and the edges of the covered span are partial).
constexpr double kMinHeldFraction = 0.9;
// The static box's estimated world position after it is uncovered, against before it was
// covered (10 frames before): measured 0.6-1.6 cm at most over seeds 1-6. On the 2-3 frames on
// which the panel covers part of the box, before it is held, its pose slides towards the
// covered side (the uncovered edge only pins it one way, as at the image border); it recovers
// once uncovered.
constexpr double kPoseDriftToleranceM = 0.025;

synth::Scene coveredBoxScene() {
  using synth::at;
  synth::Scene s = test_scene::boxRoomScene("covered-box", kBoxId, 0, 0.6);
  // A panel 0.6 m wide and 1 m tall, 1.1 m from the camera and 1 m in front of the box: it
  // slides in from the left, stays in front of the box and slides out to the right.
  synth::SceneObject panel;
  panel.id = kPanelId;
  panel.class_name = "panel";
  panel.parts.push_back(synth::makeBox({0.3, 0.025, 0.5}, at(0, 0, 0.5),
                                       test_scene::solidMaterial(0.7f, 0.2f, 0.2f)));
  panel.trajectory.origin_m = Eigen::Vector3d(-1.3, -0.4, 0);
  panel.trajectory.moves.push_back({0.3, 0.8, Eigen::Vector3d(1.3, 0, 0), Eigen::Vector3d::Zero()});
  panel.trajectory.moves.push_back({1.8, 2.3, Eigen::Vector3d(1.3, 0, 0), Eigen::Vector3d::Zero()});
  s.objects.push_back(panel);
  // The camera 2.1 m in front of the box, swaying sideways.
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  s.camera.path.position_terms.push_back({Eigen::Vector3d(0.1, 0, 0.03), 0.4, 0.0});
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.default_frames = kFrames;
  return s;
}

struct BoxRun {
  std::vector<ObjectState> states;  // per frame (kDeleted once; frames after it stay kDeleted)
  std::vector<Eigen::Isometry3d> T_world_box;
  int lost_frames = 0;
  int deleted_frame = -1;
  std::string deleted_reason;
  int covered_frames_seen = 0;  // frames on which the panel covers >= 95 % of the box's pixels
};

BoxRun runScene(double hidden_fraction, uint64_t seed = 1) {
  Config config = test_scene::smallSceneConfig();
  config.objects.hidden_fraction = hidden_fraction;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  so.seed = seed;
  synth::SynthSource src(so, coveredBoxScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  BoxRun run;
  core::Frame f;
  const int box_px0 = [&] {
    synth::SynthSource first(so, coveredBoxScene());
    core::Frame f0;
    EXPECT_TRUE(first.next(f0));
    return cv::countNonZero(f0.instance_ids == kBoxId);
  }();
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    if (f.index == 0) dets.push_back(test_scene::exactDetection(f, kBoxId));
    if (f.index >= kCoveredFirst && f.index <= kCoveredLast &&
        cv::countNonZero(f.instance_ids == kBoxId) < 0.05 * box_px0) {
      ++run.covered_frames_seen;
    }
    const FrameOutcome out = slam.process(f, f.index == 0 ? &dets : nullptr);
    if (out.lost) ++run.lost_frames;
    ObjectState state = ObjectState::kDeleted;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (const ObjectOutcome& o : out.objects) {
      if (o.id != kBoxId) continue;
      // Retired by a rule: dormant (objects.reidentify_frames) counts as deleted here.
      state = o.state == ObjectState::kDormant ? ObjectState::kDeleted : o.state;
      T = o.T_world_object;
      if (state == ObjectState::kDeleted && run.deleted_frame < 0) {
        run.deleted_frame = static_cast<int>(f.index);
        run.deleted_reason = o.deleted_reason;
      }
    }
    run.states.push_back(state);
    run.T_world_box.push_back(T);
  }
  return run;
}

void expectHeldAndTrackedAgain(const BoxRun& run, int max_lost_frames) {
  ASSERT_EQ(run.states.size(), static_cast<size_t>(kFrames));
  EXPECT_LE(run.lost_frames, max_lost_frames);
  // The scene does what it should: the panel hides the box on the covered frames.
  EXPECT_EQ(run.covered_frames_seen, kCoveredLast - kCoveredFirst + 1);
  EXPECT_EQ(run.deleted_frame, -1) << run.deleted_reason;
  int held = 0;
  for (int i = kCoveredFirst; i <= kCoveredLast; ++i) {
    if (run.states[static_cast<size_t>(i)] == ObjectState::kInvisible) ++held;
  }
  EXPECT_GE(held, kMinHeldFraction * (kCoveredLast - kCoveredFirst + 1));
  // A held pose does not move in the world.
  for (int i = 1; i < kFrames; ++i) {
    if (run.states[static_cast<size_t>(i)] != ObjectState::kInvisible ||
        run.states[static_cast<size_t>(i) - 1] != ObjectState::kInvisible) {
      continue;
    }
    EXPECT_TRUE(run.T_world_box[static_cast<size_t>(i)].isApprox(
        run.T_world_box[static_cast<size_t>(i) - 1], 1e-12))
        << "frame " << i;
  }
  const Eigen::Isometry3d& before = run.T_world_box[kCoveredFirst - 10];
  for (int i = kUncoveredFrom; i < kFrames; ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(run.states[static_cast<size_t>(i)], ObjectState::kTracked);
    EXPECT_LT((run.T_world_box[static_cast<size_t>(i)].translation() - before.translation()).norm(),
              kPoseDriftToleranceM);
  }
}

TEST(SlamOcclusion, ACoveredObjectIsHeldAndTrackedAgainWhereItWas) {
  expectHeldAndTrackedAgain(runScene(Config{}.objects.hidden_fraction), 0);
}

// Sensor noise seed 7: as the undetected panel leaves (frames ~56-62) it pulls the camera
// hardest among the noise seeds on which the camera holds. On a few seeds the panel drags
// the camera off and the box cannot be found again, a limit of camera tracking beside an
// undetected mover (docs/benchmarks.md, "Object truncation 3.33 voxels at 64^3"). The box must
// still be held while covered and tracked again where it was. The bound leaves room for other
// builds' rounding (sanitizers): a loss right at the rules' thresholds may take a frame more or
// fewer.
constexpr uint64_t kHardNoiseSeed = 7;
constexpr int kHardSeedMaxLostFrames = 8;

TEST(SlamOcclusion, ACoveredObjectIsHeldAndTrackedAgainOnAnotherNoiseSeed) {
  expectHeldAndTrackedAgain(runScene(Config{}.objects.hidden_fraction, kHardNoiseSeed),
                            kHardSeedMaxLostFrames);
}

TEST(SlamOcclusion, WithoutTheHiddenRuleTheCoveredObjectIsDeleted) {
  const BoxRun run = runScene(0.0);
  EXPECT_GE(run.deleted_frame, kCoveredFirst - 10);
  EXPECT_LE(run.deleted_frame, kUncoveredFrom) << run.deleted_reason;
  for (const ObjectState s : run.states) EXPECT_NE(s, ObjectState::kInvisible);
}

}  // namespace
}  // namespace emf::pipeline
