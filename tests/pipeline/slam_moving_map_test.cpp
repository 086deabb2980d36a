// The background following the camera (map.follow_camera) on a walk longer than its grid: the
// first 25 s of the `apartment` preset (the living room into the kitchen and round its island)
// at 160x120 with a 5.12 m grid of 4 cm voxels. The camera stays tracked, the grid moves and
// frees what it leaves, and the background mesh holds the surface of the whole walk, not only
// of the grid's last place.
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/frame_source.h"
#include "eval/eval.h"
#include "eval/surface_coverage.h"
#include "io/ply.h"
#include "map/volume_host_access.h"
#include "pipeline/run_outputs.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

constexpr int kFrames = 750;                // 25 s, about 8 m of walking
constexpr double kAteToleranceM = 0.04;     // one voxel
constexpr double kCoverNearM = 0.12;        // a surface point is in the mesh: a vertex this near
constexpr double kMinWalkCoverage = 0.9;    // of the walk's surface points, in the mesh
constexpr double kMaxWindowCoverage = 0.8;  // the grid's own mesh alone holds less

Config movingConfig() {
  Config c;
  c.map.memory_mb = 16;
  c.map.background_voxel_m = 0.04;
  c.map.background_resolution = 128;
  c.map.follow_camera = true;
  c.map.follow_trigger_m = 0.5;
  return c;
}

struct Collect : map::MeshSink {
  std::vector<Eigen::Vector3f> vertices;
  size_t triangles = 0;
  void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f*, size_t n) override {
    vertices.insert(vertices.end(), p, p + n);
  }
  void addTriangles(const Eigen::Vector3i*, size_t n) override { triangles += n; }
};

TEST(SlamMovingMap, AWalkOutOfTheGridStaysTrackedAndItsMeshHoldsTheWholeWalk) {
  const Config config = movingConfig();
  cl::Context ctx(config.cl);
  auto src = sources::openSource(
      "synth:apartment?frames=" + std::to_string(kFrames) + "&width=160&height=120&seed=2",
      config.source);
  SlamSystem slam(ctx, config, src->intrinsics());
  slam.setEvictedSurfaceFolder(test::tempDir("moving_map"));
  const core::Intrinsics k = src->intrinsics();
  io::Trajectory gt, est;
  std::vector<Eigen::Vector3f> surface;  // true surface points along the walk, first camera frame
  std::optional<Eigen::Isometry3d> T0;
  core::Frame f;
  int moved_frames = 0;
  double path_m = 0;
  while (src->next(f)) {
    const FrameOutcome o = slam.process(f);
    ASSERT_FALSE(o.lost) << "frame " << o.index << ": " << o.loss_reason;
    ASSERT_TRUE(f.T_world_camera_gt.has_value());
    if (!T0) T0 = *f.T_world_camera_gt;
    const Eigen::Isometry3d T_gt = T0->inverse() * *f.T_world_camera_gt;
    if (!gt.empty()) path_m += (T_gt.translation() - gt.poses.back().translation()).norm();
    gt.append(f.timestamp, T_gt);
    est.append(f.timestamp, o.T_world_camera);
    moved_frames += !o.map_shift.isZero();
    if (o.index % 25 == 0) {
      for (int y = 2; y < k.height; y += 4) {
        for (int x = 2; x < k.width; x += 4) {
          const float z = f.depth.at<float>(y, x);
          if (!(z > 0.0f) || z > 3.0f) continue;
          const Eigen::Vector3d pc((x - k.cx) / k.fx * z, (y - k.cy) / k.fy * z, z);
          surface.push_back((T_gt * pc).cast<float>());
        }
      }
    }
  }
  EXPECT_EQ(slam.framesLost(), 0);
  EXPECT_GT(path_m, 5.0);
  const eval::AteResult ate = eval::computeAte(gt, est);
  EXPECT_LT(ate.trans_m.rmse, kAteToleranceM);
  // The grid moved, in small steps, and gave back what it left.
  EXPECT_GE(slam.backgroundShifts(), 10);
  EXPECT_EQ(slam.backgroundShifts(), moved_frames);
  EXPECT_GT(slam.evictedBlocks(), 100);
  EXPECT_EQ(slam.pool().stats().used_slots, slam.background().allocatedBlocks());
  EXPECT_EQ(slam.pool().stats().dropped_blocks, 0);

  Collect walk;
  slam.extractBackgroundMesh(walk);
  Collect window;
  {
    const map::VolumeHostAccess access(slam.background());
    map::extractMesh(access.view(), access.T_world_volume(), map::MeshOptions(), window);
  }
  const double walk_cover = eval::coveredFraction(walk.vertices, surface, kCoverNearM);
  const double window_cover = eval::coveredFraction(window.vertices, surface, kCoverNearM);
  EXPECT_GT(walk_cover, kMinWalkCoverage);
  EXPECT_LT(window_cover, kMaxWindowCoverage);
  // background.ply, as `emf run` writes it, is that whole mesh.
  const std::string dir = test::tempDir("moving_map_out");
  writeBackgroundMesh(dir, slam, true);
  const map::Mesh written = io::readPly(dir + "/background.ply");
  EXPECT_EQ(written.vertices.size(), walk.vertices.size());
  EXPECT_EQ(written.triangles.size(), walk.triangles);
  RecordProperty("walk_coverage", std::to_string(walk_cover));
  RecordProperty("window_coverage", std::to_string(window_cover));
  std::printf(
      "path %.2f m, ATE %.2f cm, moves %lld, evicted %lld, coverage walk %.3f window %.3f\n",
      path_m, ate.trans_m.rmse * 100, static_cast<long long>(slam.backgroundShifts()),
      static_cast<long long>(slam.evictedBlocks()), walk_cover, window_cover);
}

}  // namespace
}  // namespace emf::pipeline
