// The kernels' lane width (cl.lanes: 4, 8 or 16 pixels per work item, chosen per device) does not
// change a result: the SLAM with a moving object gives the same camera and object poses, to the
// bit, at every width. Every per-lane operation is the same at every width (no floating-point
// contraction: kernels_cl/common.clh) and the sums keep one order (track_reduce.cl, estep.cl).
#include <gtest/gtest.h>

#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"

namespace emf::pipeline {
namespace {

constexpr int kFrames = 24;
constexpr int kBoxId = 1;

struct Poses {
  std::vector<Eigen::Isometry3d> camera;
  std::vector<Eigen::Isometry3d> box;  // T_object_camera of the tracked box, per frame
};

Poses run(const std::string& lanes) {
  synth::Scene scene = test_scene::boxRoomScene("lanes", kBoxId, 0.1, 0.6);
  // The box slides and turns while the camera sweeps.
  scene.objects.back().trajectory.moves.push_back(
      {0.1, 0.8, Eigen::Vector3d(-0.15, 0.05, 0), Eigen::Vector3d(0, 0, 0.2)});
  scene.camera.path.origin_m = Eigen::Vector3d(0, -1.5, 1.2);
  scene.camera.path.position_terms = {{Eigen::Vector3d(0.15, 0, 0), 0.2, 0.0}};
  scene.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.3);
  scene.default_frames = kFrames;
  Config config = test_scene::smallSceneConfig();
  config.cl.lanes = lanes;
  cl::Context ctx(config.cl);
  EXPECT_EQ(ctx.lanes(), std::stoi(lanes));
  synth::SynthOptions so;
  so.width = 320;
  so.height = 240;
  synth::SynthSource src(so, scene);
  SlamSystem slam(ctx, config, src.intrinsics());
  Poses poses;
  core::Frame f;
  while (src.next(f)) {
    std::vector<core::Detection> dets;
    if (f.index == 0) dets.push_back(test_scene::exactDetection(f, kBoxId));
    const FrameOutcome out = slam.process(f, f.index == 0 ? &dets : nullptr);
    poses.camera.push_back(out.T_world_camera);
    for (const ObjectOutcome& o : out.objects) {
      if (o.state == ObjectState::kTracked) poses.box.push_back(o.T_object_camera);
    }
  }
  return poses;
}

bool sameBits(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), sizeof(double) * 16) == 0;
}

TEST(SlamLanes, PosesAreTheSameToTheBitAtEveryLaneWidth) {
  const Poses p16 = run("16");
  ASSERT_EQ(p16.camera.size(), static_cast<size_t>(kFrames));
  ASSERT_GE(p16.box.size(), static_cast<size_t>(kFrames - 2)) << "the box must be tracked";
  for (const char* lanes : {"8", "4"}) {
    const Poses p = run(lanes);
    ASSERT_EQ(p.camera.size(), p16.camera.size()) << lanes << " lanes";
    ASSERT_EQ(p.box.size(), p16.box.size()) << lanes << " lanes";
    for (size_t i = 0; i < p.camera.size(); ++i) {
      ASSERT_TRUE(sameBits(p.camera[i], p16.camera[i]))
          << "camera pose of frame " << i << " at " << lanes << " lanes:\n"
          << p.camera[i].matrix() << "\nat 16 lanes:\n"
          << p16.camera[i].matrix();
    }
    for (size_t i = 0; i < p.box.size(); ++i) {
      ASSERT_TRUE(sameBits(p.box[i], p16.box[i]))
          << "box pose " << i << " at " << lanes << " lanes:\n"
          << p.box[i].matrix() << "\nat 16 lanes:\n"
          << p16.box[i].matrix();
    }
  }
}

}  // namespace
}  // namespace emf::pipeline
