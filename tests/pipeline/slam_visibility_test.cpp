// The visibility rule in the running SLAM: a box standing on the floor leaves the image as the
// camera turns away, and is deleted as invisible on the frame its silhouette inside the image
// border falls below objects.invisible_min_px. The rule's ray cast runs at a reduced width
// (objects.visibility_width) with its thresholds scaled; this checks that it deletes on the same
// frame as the full-size cast (the paper's) and as the ground-truth silhouette says.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "box_room_scene.h"
#include "em/object_rules.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 60;
constexpr int kObjectId = 1;
// The deletion frame of the full-size cast against the ground-truth silhouette: measured 0-2
// frames late over seeds 1-6 (as the box leaves, the sliver left in view lets its tracking
// slide along the border, up to 15 cm on its last frames, and the model lingers).
constexpr int kGroundTruthFrameTolerance = 3;
// The reduced casts against the full-size one: a pixel of the cast at half the frame's width
// covers 4 of the frame's (the default objects.visibility_width at 320x240), at a quarter 16
// (the default at 640x480). Measured: the same frame at half width on seeds 1-6, and at both
// widths on this scene's seed.
constexpr int kReducedFrameTolerance = 1;

synth::Scene leavingBoxScene() {
  synth::Scene s = test_scene::boxRoomScene("leaving-box", kObjectId, -0.3, 0.6);
  // The camera stands 2 m in front of the box and turns right by about 45 deg between 0.2 s
  // and 1.6 s: the box leaves through the left image border.
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  s.camera.target.moves.push_back({0.2, 1.6, Eigen::Vector3d(2.2, 0, 0), Eigen::Vector3d::Zero()});
  s.default_frames = kFrames;
  return s;
}

struct Deletion {
  int64_t frame = -1;
  std::string reason;
};

// Runs the scene with the box detected (its exact silhouette) on frame 0; the frame and reason
// of the box's deletion, if it was deleted.
Deletion runScene(int visibility_width, int* lost_frames) {
  Config config = test_scene::smallSceneConfig();
  config.objects.visibility_width = visibility_width;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, leavingBoxScene());
  SlamSystem slam(ctx, config, src.intrinsics());
  Deletion d;
  *lost_frames = 0;
  core::Frame f;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    if (f.index == 0) dets.push_back(test_scene::exactDetection(f, kObjectId));
    const FrameOutcome out = slam.process(f, f.index == 0 ? &dets : nullptr);
    if (out.lost) ++*lost_frames;
    for (const ObjectOutcome& o : out.objects) {
      // Retired by the rule: dormant (objects.reidentify_frames) or deleted.
      if (o.id == kObjectId &&
          (o.state == ObjectState::kDeleted || o.state == ObjectState::kDormant)) {
        d = {f.index, o.deleted_reason};
      }
    }
    if (d.frame >= 0) break;
  }
  return d;
}

TEST(SlamVisibility, ALeavingObjectIsDeletedWhenItsSilhouetteIsTooSmall) {
  // Ground truth: the first frame whose box silhouette inside the border is below the
  // threshold (both scaled to 320x240, as the SLAM does).
  Config config;
  em::ObjectOptions opt = config.objects;
  const double scale = kWidth / 640.0;
  opt.visibility_border_px = static_cast<int>(std::lround(opt.visibility_border_px * scale));
  opt.invisible_min_px = static_cast<int>(std::lround(opt.invisible_min_px * scale * scale));
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource truth(so, leavingBoxScene());
  int64_t gt_frame = -1;
  int first_px = 0;
  for (int64_t i = 0; i < kFrames && gt_frame < 0; ++i) {
    core::Frame f;
    truth.renderFrame(i, &f);
    cv::Mat ids;
    f.instance_ids.convertTo(ids, CV_32S);
    if (i == 0) first_px = em::visiblePixels(ids, kObjectId, opt);
    if (em::isInvisible(ids, kObjectId, opt)) gt_frame = i;
  }
  std::printf("box: %d px inside the border on frame 0; ground truth below %d px on frame %lld\n",
              first_px, opt.invisible_min_px, static_cast<long long>(gt_frame));
  ASSERT_GT(first_px, 4 * opt.invisible_min_px) << "the scene must start with the box well seen";
  ASSERT_GT(gt_frame, 20) << "the box must stay in view long enough to be tracked";

  int lost_full = 0, lost_reduced = 0, lost_quarter = 0;
  const Deletion full = runScene(0, &lost_full);
  const Deletion reduced = runScene(kWidth / 2, &lost_reduced);
  const Deletion quarter = runScene(kWidth / 4, &lost_quarter);
  std::printf(
      "deleted on frame %lld (full-size cast: %s), %lld (%dx%d cast: %s), %lld (%dx%d "
      "cast: %s)\n",
      static_cast<long long>(full.frame), full.reason.c_str(),
      static_cast<long long>(reduced.frame), kWidth / 2, kHeight / 2, reduced.reason.c_str(),
      static_cast<long long>(quarter.frame), kWidth / 4, kHeight / 4, quarter.reason.c_str());
  EXPECT_EQ(lost_full, 0);
  EXPECT_EQ(lost_reduced, 0);
  EXPECT_EQ(lost_quarter, 0);
  ASSERT_GE(full.frame, 0) << "the box was never deleted";
  ASSERT_GE(reduced.frame, 0) << "the box was never deleted with the reduced cast";
  // The visibility rule deletes the box, or, on the frame it leaves, the association rule:
  // the sliver left in view lets the model slide (seed 1: on frame 29 the full-size cast sees
  // 0 px of it without the range guard, and with it the slide, 12 cm, drops the mean
  // association to 0.065 first; seeds 2-6 delete as invisible either way). Both casts must
  // agree on which rule it was.
  const auto rule = [](const std::string& reason) {
    return reason.rfind("invisible", 0) == 0          ? std::string("invisible")
           : reason.rfind("mean association", 0) == 0 ? std::string("mean association")
                                                      : reason;
  };
  EXPECT_TRUE(rule(full.reason) == "invisible" || rule(full.reason) == "mean association")
      << full.reason;
  EXPECT_EQ(rule(reduced.reason), rule(full.reason)) << reduced.reason;
  EXPECT_NE(reduced.reason.find("(ray cast at 160x120)"), std::string::npos) << reduced.reason;
  ASSERT_GE(quarter.frame, 0) << "the box was never deleted with the quarter-width cast";
  EXPECT_EQ(rule(quarter.reason), rule(full.reason)) << quarter.reason;
  EXPECT_NE(quarter.reason.find("(ray cast at 80x60)"), std::string::npos) << quarter.reason;
  EXPECT_LE(std::abs(full.frame - gt_frame), kGroundTruthFrameTolerance);
  EXPECT_LE(std::abs(reduced.frame - full.frame), kReducedFrameTolerance);
  EXPECT_LE(std::abs(quarter.frame - full.frame), kReducedFrameTolerance);
}

}  // namespace
}  // namespace emf::pipeline
