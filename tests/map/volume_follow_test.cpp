// A background that follows the camera (map/volume_follow.h): the move rule, Volume::shift on
// the device (staying blocks keep their voxels, leaving ones return their slots) and the mesh of
// what leaves, which with the mesh of what stays gives back the mesh of the grid before the move.
#include "map/volume_follow.h"

#include <cmath>

#include "common/error.h"
#include "eval/surface_coverage.h"
#include "map/volume_host_access.h"
#include "map_fixture.h"

namespace emf::test {
namespace {

/// Vertex positions of two meshes of the same surface agree to float rounding of the world
/// transform (metres).
constexpr double kSameVertexM = 1e-5;

class VolumeFollowTest : public MapTest {};

/// Centroids of a mesh's triangles, world frame.
std::vector<Eigen::Vector3f> centroids(const map::Mesh& m) {
  std::vector<Eigen::Vector3f> c;
  for (const Eigen::Vector3i& t : m.triangles) {
    c.push_back((m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.0f);
  }
  return c;
}

TEST(FollowShift, MovesByTheExcessOverTheTriggerInWholeBlocks) {
  map::MapOptions o;  // 512 voxels of 1 cm: blocks of 8 cm, focus 2.56 m ahead
  o.follow_trigger_m = 1.0;
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  const Eigen::Isometry3d T_wv = map::backgroundVolumePose(o, spec, Eigen::Isometry3d::Identity());
  const map::FollowRule rule = map::followRule(o, spec);
  EXPECT_NEAR(rule.focus_m, 2.56, 1e-6);  // the extent is a float
  // The first camera looks at the centre.
  EXPECT_EQ(map::followShift(spec, T_wv, Eigen::Isometry3d::Identity(), rule),
            Eigen::Vector3i::Zero());
  // 1.1 m to the right: 0.1 m past the trigger = 1.25 blocks, rounded up.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.1, 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule), Eigen::Vector3i(2, 0, 0));
  T.translation() = Eigen::Vector3d(1.05, 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule), Eigen::Vector3i(1, 0, 0));
  // 1.5 m: 6.25 blocks past, but a frame moves at most kMaxFollowStepBlocks.
  T.translation() = Eigen::Vector3d(1.5, 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule),
            Eigen::Vector3i(map::kMaxFollowStepBlocks, 0, 0));
  // Within the trigger: no move.
  T.translation() = Eigen::Vector3d(0.0, -0.99, 0.5);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule), Eigen::Vector3i::Zero());
  // Back 1.1 m: 0.1 m past = 1.25 blocks -> 2, backwards.
  T.translation() = Eigen::Vector3d(0.0, 0.0, -1.1);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule), Eigen::Vector3i(0, 0, -2));
  // Turned 90 deg to the right (about camera y, down): the focus is 2.56 m along +x, the
  // centre 2.56 m along +z: 1.56 m past on both = 19.5 blocks, caught up 2 blocks a frame; after
  // 10 frames the focus is within the trigger again.
  const Eigen::Isometry3d turned(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  Eigen::Isometry3d T_wv_moved = T_wv;
  int frames = 0;
  Eigen::Vector3i total = Eigen::Vector3i::Zero();
  for (; frames < 20; ++frames) {
    const Eigen::Vector3i move = map::followShift(spec, T_wv_moved, turned, rule);
    if (move.isZero()) break;
    EXPECT_LE(move.cwiseAbs().maxCoeff(), map::kMaxFollowStepBlocks);
    T_wv_moved.translate(move.cast<double>() * 0.08);
    total += move;
  }
  EXPECT_EQ(frames, 10);
  EXPECT_EQ(total, Eigen::Vector3i(20, 0, -20));
  // A trigger below one block acts as one block (8 cm): 0.1 m off moves by 1, not 2.
  map::FollowRule tight = rule;
  tight.trigger_m = 0.0;
  T.translation() = Eigen::Vector3d(0.1, 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, tight), Eigen::Vector3i(1, 0, 0));
  T.translation() = Eigen::Vector3d(0.07, 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, tight), Eigen::Vector3i::Zero());
  // A NaN pose moves nothing.
  T.translation() = Eigen::Vector3d(std::nan(""), 0.0, 0.0);
  EXPECT_EQ(map::followShift(spec, T_wv, T, rule), Eigen::Vector3i::Zero());
}

TEST_F(VolumeFollowTest, AShiftKeepsStayingVoxelsFreesLeavingBlocksAndMeshesWhatLeaves) {
  const map::MapOptions o = smallOptions();  // 32^3 blocks of 16 cm
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume bg(pool, spec, map::backgroundVolumePose(o, spec, T0));
  fuseThreeViews(bg, scene, k);
  const map::VolumeHostData before = bg.download();
  const map::Mesh full = map::extractMesh(before);
  const int used_before = pool.stats().used_slots;
  const Eigen::Isometry3d T_wv_before = bg.T_world_volume();

  // The scene spans the grid's middle: a move by (12, 0, 14) blocks (1.92 m, 2.24 m) cuts
  // through the walls and the spheres.
  const Eigen::Vector3i move(12, 0, 14);
  map::Mesh leaving;
  {
    struct Collect : map::MeshSink {
      map::Mesh* m;
      void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f* n, size_t c) override {
        m->vertices.insert(m->vertices.end(), p, p + c);
        m->normals.insert(m->normals.end(), n, n + c);
      }
      void addTriangles(const Eigen::Vector3i* t, size_t c) override {
        m->triangles.insert(m->triangles.end(), t, t + c);
      }
    } sink;
    sink.m = &leaving;
    map::extractLeavingMesh(bg, move, sink);
    // A GPU downloads only the blocks that mesh reads: the same mesh, vertex for vertex.
    map::Mesh partial;
    sink.m = &partial;
    map::extractLeavingMesh(bg, move, sink, true);
    ASSERT_EQ(partial.vertices.size(), leaving.vertices.size());
    for (size_t i = 0; i < partial.vertices.size(); ++i) {
      ASSERT_EQ(partial.vertices[i], leaving.vertices[i]) << "vertex " << i;
      ASSERT_EQ(partial.normals[i], leaving.normals[i]) << "normal " << i;
    }
    EXPECT_EQ(partial.triangles, leaving.triangles);
    // ... which are fewer than all.
    EXPECT_LT(bg.download(map::leavingMeshBlocks(move, spec.dims_blocks)).allocatedBlocks(),
              before.allocatedBlocks());
  }
  const int evicted = bg.shift(move);
  const map::VolumeHostData after = bg.download();

  // Staying blocks: same voxels at the same world place; leaving ones are gone.
  const Eigen::Vector3i dims = spec.dims_blocks;
  int leaving_allocated = 0, staying = 0;
  for (int z = 0; z < dims.z(); ++z) {
    for (int y = 0; y < dims.y(); ++y) {
      for (int x = 0; x < dims.x(); ++x) {
        const Eigen::Vector3i b_old(x, y, z);
        const int64_t i_old = x + dims.x() * (y + static_cast<int64_t>(dims.y()) * z);
        const Eigen::Vector3i b_new = b_old - move;
        const bool stays = (b_new.array() >= 0).all() && (b_new.array() < dims.array()).all();
        if (!stays) {
          leaving_allocated += before.index[i_old] >= 0;
          continue;
        }
        const int64_t i_new =
            b_new.x() + dims.x() * (b_new.y() + static_cast<int64_t>(dims.y()) * b_new.z());
        ASSERT_EQ(after.index[i_new] >= 0, before.index[i_old] >= 0) << b_old.transpose();
        if (before.index[i_old] < 0) continue;
        ++staying;
        for (int v = 0; v < map::kBlockVoxels; ++v) {
          const map::Voxel a = before.voxels[before.index[i_old] * map::kBlockVoxels + v];
          const map::Voxel c = after.voxels[after.index[i_new] * map::kBlockVoxels + v];
          ASSERT_EQ(a.tsdf_q, c.tsdf_q);
          ASSERT_EQ(a.weight_q, c.weight_q);
        }
      }
    }
  }
  // The new blocks entering the grid are unallocated.
  for (int i = 0; i < spec.blockCount(); ++i) {
    const Eigen::Vector3i b_new = map::blockCoords(dims, i);
    const Eigen::Vector3i b_old = b_new + move;
    if ((b_old.array() >= dims.array()).any()) {
      EXPECT_LT(after.index[i], 0);
    }
  }
  EXPECT_GT(leaving_allocated, 100);
  EXPECT_GT(staying, 100);
  EXPECT_EQ(evicted, leaving_allocated);
  EXPECT_EQ(bg.allocatedBlocks(), before.allocatedBlocks() - evicted);
  EXPECT_EQ(pool.stats().used_slots, used_before - evicted);
  const Eigen::Vector3d moved_m = T_wv_before.rotation() * (move.cast<double>() * map::kBlockSize *
                                                            static_cast<double>(spec.voxel_size_m));
  EXPECT_LT((bg.T_world_volume().translation() - T_wv_before.translation() - moved_m).norm(), 1e-9);

  // What left plus what stays is the surface before the move, triangle for triangle.
  const map::Mesh kept = map::extractMesh(after);
  EXPECT_GT(leaving.triangles.size(), 1000u);
  EXPECT_GT(kept.triangles.size(), 1000u);
  EXPECT_EQ(leaving.triangles.size() + kept.triangles.size(), full.triangles.size());
  std::vector<Eigen::Vector3f> parts = centroids(leaving);
  const std::vector<Eigen::Vector3f> kept_c = centroids(kept);
  parts.insert(parts.end(), kept_c.begin(), kept_c.end());
  EXPECT_EQ(eval::uncoveredPoints(centroids(full), parts, kSameVertexM), 0u);
  EXPECT_EQ(eval::uncoveredPoints(parts, centroids(full), kSameVertexM), 0u);

  // Freed slots are clean and reusable: the first view fused again allocates again.
  Frame f = makeFrame(renderDepth(scene, k, T0), k, T0);
  const map::AllocationReport rep = bg.fuse(f.input);
  EXPECT_EQ(rep.dropped_blocks, 0);
  EXPECT_EQ(pool.stats().used_slots, bg.allocatedBlocks());
}

// The allocation counts the pixels whose measured surface lies outside the grid: none in the
// 5.12 m grid, the far part of the room in a 1.28 m one (as the host counts them, to a few
// pixels on the grid's faces).
constexpr int kOutsideCountTolerancePx = 20;

TEST_F(VolumeFollowTest, AllocationCountsPixelsThatSeePastTheGrid) {
  map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(160, 120);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();
  const cv::Mat depth = renderDepth(scene, k, T0);
  for (int resolution : {256, 64}) {
    o.background_resolution = resolution;
    const map::VolumeSpec spec = map::VolumeSpec::background(o);
    const Eigen::Isometry3d T_wv = map::backgroundVolumePose(o, spec, T0);
    map::Volume bg(pool, spec, T_wv);
    Frame f = makeFrame(depth, k, T0);
    const map::AllocationReport rep = bg.allocate(f.input);
    int expected = 0;
    const Eigen::Vector3d ext = spec.extentM().cast<double>();
    for (int y = 0; y < k.height; ++y) {
      for (int x = 0; x < k.width; ++x) {
        const float z = depth.at<float>(y, x);
        if (!(z > 0.0f)) continue;
        const Eigen::Vector3d p =
            T_wv.inverse() * Eigen::Vector3d((x - k.cx) / k.fx * z, (y - k.cy) / k.fy * z, z);
        expected += (p.array() < 0.0).any() || (p.array() >= ext.array()).any();
      }
    }
    EXPECT_NEAR(rep.outside_pixels, expected, kOutsideCountTolerancePx) << resolution;
    if (resolution == 256) {
      EXPECT_EQ(expected, 0);
    } else {
      EXPECT_GT(expected, k.width * k.height / 4);
    }
  }
}

TEST_F(VolumeFollowTest, NoMoveLeavesTheVolumeAsItIsAndObjectsDoNotShift) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(160, 120);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume bg(pool, spec, map::backgroundVolumePose(o, spec, Eigen::Isometry3d::Identity()));
  Frame f = makeFrame(renderDepth(scene, k, Eigen::Isometry3d::Identity()), k,
                      Eigen::Isometry3d::Identity());
  bg.fuse(f.input);
  const map::VolumeHostData before = bg.download();
  struct Count : map::MeshSink {
    size_t v = 0, t = 0;
    void addVertices(const Eigen::Vector3f*, const Eigen::Vector3f*, size_t c) override { v += c; }
    void addTriangles(const Eigen::Vector3i*, size_t c) override { t += c; }
  } count;
  map::extractLeavingMesh(bg, Eigen::Vector3i::Zero(), count);
  EXPECT_EQ(count.v, 0u);
  EXPECT_EQ(count.t, 0u);
  EXPECT_EQ(bg.shift(Eigen::Vector3i::Zero()), 0u);
  EXPECT_EQ(bg.download().index, before.index);

  map::Volume obj(pool, map::VolumeSpec::object(o, 32, 0.02f), Eigen::Isometry3d::Identity());
  EXPECT_THROW(obj.shift(Eigen::Vector3i(1, 0, 0)), InvalidArgument);
}

}  // namespace
}  // namespace emf::test
