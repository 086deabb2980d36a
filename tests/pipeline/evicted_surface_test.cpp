// pipeline::EvictedSurface: the surface a moving background leaves, meshed on a worker thread,
// comes back as the synchronous meshes of the same moves would, part after part, also when more
// moves are queued than it lets wait; a folder that cannot hold it is named. (Label threads:
// runs under ThreadSanitizer.)
#include "pipeline/evicted_surface.h"

#include "common/error.h"
#include "map/volume_follow.h"
#include "map_fixture.h"

namespace emf::test {
namespace {

class EvictedSurfaceTest : public MapTest {};

struct Collect : map::MeshSink {
  map::Mesh m;
  size_t base = 0;  // added to triangle indices (parts of the reference)
  void addVertices(const Eigen::Vector3f* p, const Eigen::Vector3f* n, size_t c) override {
    m.vertices.insert(m.vertices.end(), p, p + c);
    m.normals.insert(m.normals.end(), n, n + c);
  }
  void addTriangles(const Eigen::Vector3i* t, size_t c) override {
    for (size_t i = 0; i < c; ++i) m.triangles.push_back(t[i] + Eigen::Vector3i::Constant(base));
  }
};

TEST_F(EvictedSurfaceTest, MeshesOnTheWorkerWhatSynchronousMeshingGives) {
  const map::MapOptions o = smallOptions();  // 32^3 blocks of 16 cm
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(320, 240);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume bg(pool, spec, map::backgroundVolumePose(o, spec, Eigen::Isometry3d::Identity()));
  fuseThreeViews(bg, scene, k);

  // More moves than may wait (kMaxPending), through the walls and the spheres.
  std::vector<Eigen::Vector3i> moves = {{2, 0, 0}, {0, 0, 3}, {-1, 1, 0}};
  for (size_t i = 0; i < pipeline::EvictedSurface::kMaxPending + 2; ++i)
    moves.emplace_back(0, 0, 1);
  Collect reference;
  size_t reference_vertices = 0;
  {
    pipeline::EvictedSurface surface(tempDir("evicted_surface"));
    for (const Eigen::Vector3i& move : moves) {
      reference.base = reference.m.vertices.size();
      map::extractLeavingMesh(bg, move, reference);  // synchronous, before the move
      surface.add(bg, move);
      bg.shift(move);
    }
    Collect replayed;
    reference_vertices = surface.replay(replayed);
    ASSERT_EQ(replayed.m.vertices.size(), reference.m.vertices.size());
    EXPECT_EQ(reference_vertices, reference.m.vertices.size());
    for (size_t i = 0; i < replayed.m.vertices.size(); ++i) {
      ASSERT_EQ(replayed.m.vertices[i], reference.m.vertices[i]) << "vertex " << i;
      ASSERT_EQ(replayed.m.normals[i], reference.m.normals[i]) << "normal " << i;
    }
    EXPECT_EQ(replayed.m.triangles, reference.m.triangles);
    // Moves queued after a replay are meshed too.
    surface.add(bg, Eigen::Vector3i(0, 0, 1));
    bg.shift(Eigen::Vector3i(0, 0, 1));
    Collect again;
    EXPECT_GE(surface.replay(again), reference_vertices);
  }
  EXPECT_GT(reference.m.triangles.size(), 1000u);
}

TEST_F(EvictedSurfaceTest, AFolderThatCannotHoldItIsNamed) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume bg(pool, spec, Eigen::Isometry3d::Identity());
  const std::string missing = tempDir("evicted_surface_missing") + "/no/such/folder";
  pipeline::EvictedSurface surface(missing);
  try {
    surface.add(bg, Eigen::Vector3i(1, 0, 0));
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace emf::test
