// Volume growth from masks that spill: a 40 cm box stands on the floor, detected on frame 0 with
// its exact silhouette and then every 10 frames with a mask that spills over its top onto the
// floor far behind it (a detector's spill). Each matched detection's robust extent grows the
// volume towards the floor behind, but blocks are allocated (and integrated every frame) only
// near the region the object claims in the E-step (objects.claim_region: the depth-continuous
// part of its masks): the floor's blocks in the grown volume would never hold the object's
// surface. With the whole volume claimed (the paper) they are allocated.
#include <gtest/gtest.h>

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
constexpr int kFrames = 61;
constexpr int kBoxId = 1;
constexpr int kDetectEvery = 10;
constexpr int kSpillPx = 20;  // the spilled masks reach this far above the box, px at 320 px
// The volume grows to metres either way (kGrownSideM); the blocks it allocates with the claim
// region stay below kMaxBlocksShare of those allocated with the whole volume claimed.
constexpr double kGrownSideM = 2.0;
constexpr double kMaxBlocksShare = 0.6;

struct GrowthRun {
  double side_m = 0;  // the box volume's largest side after the last detection
  int blocks = 0;     // its allocated blocks then
  int objects = 0;    // objects created
  ObjectState last_state = ObjectState::kDeleted;
};

GrowthRun runScene(bool claim_region) {
  Config config = test_scene::smallSceneConfig();
  config.objects.claim_region = claim_region;
  cl::Context ctx(config.cl);
  synth::SynthOptions so;
  so.width = kWidth;
  so.height = kHeight;
  synth::SynthSource src(so, test_scene::standingBoxScene("standing-box", kBoxId, kFrames));
  SlamSystem slam(ctx, config, src.intrinsics());
  GrowthRun run;
  core::Frame f;
  int box = 0;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    const bool detect = f.index % kDetectEvery == 0;
    if (detect) {
      core::Detection d = test_scene::exactDetection(f, kBoxId);
      if (f.index > 0) {  // the mask and its copy kSpillPx higher
        cv::Mat up = cv::Mat::zeros(d.mask.size(), d.mask.type());
        d.mask.rowRange(kSpillPx, d.mask.rows).copyTo(up.rowRange(0, d.mask.rows - kSpillPx));
        d.mask = cv::max(d.mask, up);
        d.box = cv::boundingRect(d.mask > 0.5f);
      }
      dets.push_back(d);
    }
    const FrameOutcome out = slam.process(f, detect ? &dets : nullptr);
    for (const ObjectOutcome& o : out.objects) {
      if (o.first_frame == f.index) ++run.objects;
      if (box == 0 && o.first_frame == 0) box = o.id;
      if (o.id == box) run.last_state = o.state;
    }
  }
  const map::Volume* v = box != 0 ? slam.volume(box) : nullptr;
  if (v != nullptr) {
    run.side_m = v->spec().extentM().maxCoeff();
    run.blocks = v->allocatedBlocks();
  }
  std::printf("claim_region %d: box volume %.3f m, %d blocks allocated; %d objects\n",
              claim_region ? 1 : 0, run.side_m, run.blocks, run.objects);
  return run;
}

TEST(SlamGrowth, AVolumeGrownBySpilledMasksAllocatesOnlyNearItsClaimRegion) {
  const GrowthRun with = runScene(true);
  EXPECT_EQ(with.objects, 1);
  EXPECT_EQ(with.last_state, ObjectState::kTracked);
  EXPECT_GT(with.side_m, kGrownSideM);
  const GrowthRun without = runScene(false);
  EXPECT_GT(without.side_m, kGrownSideM);
  EXPECT_GT(with.blocks, 0);
  EXPECT_LT(with.blocks, kMaxBlocksShare * without.blocks);
}

}  // namespace
}  // namespace emf::pipeline
