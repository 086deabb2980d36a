// The kernels' lane width (cl.lanes: 16, 8 or 4 pixels per work item) changes a result only by
// rounding: the SLAM with a moving object gives the same camera and object poses at every width
// within a fraction of a voxel. Every per-lane operation is the same at every width and the sums
// keep one order (track_reduce.cl, estep.cl); clang fuses multiply-adds differently per vector
// width (docs/opencl.md), which is all that may differ.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "box_room_scene.h"
#include "pipeline/slam_system.h"
#include "synth/synth_source.h"

namespace emf::pipeline {
namespace {

constexpr int kFrames = 24;
constexpr int kBoxId = 1;
// Largest pose difference from the 16-lane run over the frames, as fractions of the background
// voxel (test_scene::smallSceneConfig): rounding differences of the float kernels grow through
// the frames of tracking, but stay far inside a voxel; the box, tracked against its own young
// model, is allowed more than the camera.
const double kVoxelM = test_scene::smallSceneConfig().map.background_voxel_m;
const double kMaxCameraDiffM = kVoxelM / 20;
const double kMaxBoxDiffM = kVoxelM / 4;
constexpr double kMaxDiffRad = 0.002;

struct Poses {
  std::vector<Eigen::Isometry3d> camera;
  std::vector<Eigen::Isometry3d> box;  // T_object_camera of the tracked box, per frame
};

Poses run(const std::string& lanes) {
  synth::Scene scene = test_scene::boxRoomScene("lanes", kBoxId, 0.1, 0.6);
  scene.objects.back().trajectory.R0 = test_scene::yawed(test_scene::kBoxYawRad);
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

struct Diff {
  double translation_m = 0, rotation_rad = 0;
};

Diff maxDiff(const std::vector<Eigen::Isometry3d>& a, const std::vector<Eigen::Isometry3d>& b) {
  Diff d;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    const Eigen::Isometry3d e = a[i].inverse() * b[i];
    d.translation_m = std::max(d.translation_m, e.translation().norm());
    d.rotation_rad = std::max(d.rotation_rad, Eigen::AngleAxisd(e.rotation()).angle());
  }
  return d;
}

TEST(SlamLanes, PosesAgreeAtEveryLaneWidth) {
  const Poses p16 = run("16");
  ASSERT_EQ(p16.camera.size(), static_cast<size_t>(kFrames));
  ASSERT_GE(p16.box.size(), static_cast<size_t>(kFrames - 2)) << "the box must be tracked";
  for (const char* lanes : {"8", "4"}) {
    const Poses p = run(lanes);
    ASSERT_EQ(p.camera.size(), p16.camera.size()) << lanes << " lanes";
    ASSERT_EQ(p.box.size(), p16.box.size()) << lanes << " lanes";
    const Diff camera = maxDiff(p.camera, p16.camera), box = maxDiff(p.box, p16.box);
    std::printf("%s lanes against 16: camera %.3g m %.3g rad, box %.3g m %.3g rad\n", lanes,
                camera.translation_m, camera.rotation_rad, box.translation_m, box.rotation_rad);
    EXPECT_LT(camera.translation_m, kMaxCameraDiffM) << lanes << " lanes";
    EXPECT_LT(camera.rotation_rad, kMaxDiffRad) << lanes << " lanes";
    EXPECT_LT(box.translation_m, kMaxBoxDiffM) << lanes << " lanes";
    EXPECT_LT(box.rotation_rad, kMaxDiffRad) << lanes << " lanes";
  }
}

}  // namespace
}  // namespace emf::pipeline
