// A detection whose mask spills far over its object (objects.match_spilled): a 40 cm box stands
// on the floor, detected on frame 0 with its exact silhouette and then every 10 frames with a
// mask three times as wide and high as its silhouette, spilling onto the floor and the wall
// (IoU with the box's mask about 0.1, below objects.match_iou). Such a mask shows the box: it
// is matched to the box and makes no second object. With the rule off (the paper), the first
// spilled mask makes a new object of the floor and wall around the box.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kWidth = 320, kHeight = 240;
constexpr int kFrames = 41;
constexpr int kBoxId = 1;
constexpr int kDetectEvery = 10;

/// The box's silhouette, or on later frames its bounding box grown by its own size on every
/// side (clipped to the image) as a spilled mask.
core::Detection boxDetection(const core::Frame& f) {
  core::Detection d = test_scene::exactDetection(f, kBoxId);
  if (f.index == 0) return d;
  const cv::Rect r = d.box;
  const cv::Rect spill = cv::Rect(r.x - r.width, r.y - r.height, 3 * r.width, 3 * r.height) &
                         cv::Rect(0, 0, kWidth, kHeight);
  d.mask.setTo(0.0f);
  d.mask(spill).setTo(1.0f);
  d.box = spill;
  return d;
}

struct SpillRun {
  int objects = 0;         // objects created
  int spills_matched = 0;  // spilled masks matched to the box
  double max_spill_iou = 0;
  ObjectState last_state = ObjectState::kDeleted;
};

SpillRun runScene(double match_spilled) {
  Config config = test_scene::smallSceneConfig();
  config.objects.match_spilled = match_spilled;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, test_scene::standingBoxScene("spilled-box", kBoxId, kFrames));
  SlamSystem slam(ctx, config, src.intrinsics());
  SpillRun run;
  core::Frame f;
  int box = 0;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    const bool detect = f.index % kDetectEvery == 0;
    if (detect) dets.push_back(boxDetection(f));
    const FrameOutcome out = slam.process(f, detect ? &dets : nullptr);
    for (const ObjectOutcome& o : out.objects) {
      if (o.first_frame == f.index) ++run.objects;
      if (box == 0 && o.first_frame == 0) box = o.id;
      if (o.id == box) run.last_state = o.state;
    }
    if (detect && f.index > 0 && out.matches.size() == 1) {
      if (out.matches[0].object_id == box) ++run.spills_matched;
      if (out.matches[0].best_object == box) {
        run.max_spill_iou = std::max(run.max_spill_iou, out.matches[0].best_iou);
      }
    }
  }
  std::printf(
      "match_spilled %.1f: %d objects, %d of %d spilled masks matched to the box (IoU at "
      "most %.3f)\n",
      match_spilled, run.objects, run.spills_matched, (kFrames - 1) / kDetectEvery,
      run.max_spill_iou);
  return run;
}

TEST(SlamSpill, AMaskSpilledFarOverAnObjectIsMatchedToItAndMakesNoNewObject) {
  const SpillRun ours = runScene(0.7);
  // The spilled masks are far below a match by IoU.
  EXPECT_GT(ours.max_spill_iou, 0.0);
  EXPECT_LT(ours.max_spill_iou, Config().objects.match_iou);
  EXPECT_EQ(ours.objects, 1);
  EXPECT_EQ(ours.spills_matched, (kFrames - 1) / kDetectEvery);
  EXPECT_EQ(ours.last_state, ObjectState::kTracked);
  const SpillRun paper = runScene(0.0);
  EXPECT_GT(paper.objects, 1);
  EXPECT_EQ(paper.spills_matched, 0);
}

}  // namespace
}  // namespace emf::pipeline
