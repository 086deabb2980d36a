// Host access to device volumes: the mapped view (CPU devices, PoCL here) shows the
// same voxels as a download, and the meshes extracted from both are identical, for the
// background and for an object volume with counts (foreground-only meshing).
#include "map/volume_host_access.h"

#include "map/mesh.h"
#include "map_fixture.h"

namespace emf::test {
namespace {

class VolumeHostAccessTest : public MapTest {};

void expectSameMesh(const map::Mesh& a, const map::Mesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  for (size_t i = 0; i < a.vertices.size(); ++i) {
    ASSERT_EQ(a.vertices[i], b.vertices[i]) << "vertex " << i;
    ASSERT_EQ(a.normals[i], b.normals[i]) << "normal " << i;
  }
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST_F(VolumeHostAccessTest, MappedAndDownloadedVolumesGiveTheSameMesh) {
  const map::MapOptions o = smallOptions();
  map::VoxelPool pool(ctx(), o);
  const Scene scene;
  const core::Intrinsics k = testIntrinsics(320, 240);
  const Eigen::Isometry3d T0 = Eigen::Isometry3d::Identity();

  // Background: three views.
  const map::VolumeSpec spec = map::VolumeSpec::background(o);
  map::Volume bg(pool, spec, map::backgroundVolumePose(o, spec, T0));
  fuseThreeViews(bg, scene, k);
  const map::VolumeHostAccess mapped(bg);
  EXPECT_EQ(mapped.mapped(), ctx().device().type == "cpu" && ctx().device().host_unified_memory);
  const map::VolumeHostAccess copied = map::VolumeHostAccess::downloaded(bg);
  EXPECT_FALSE(copied.mapped());
  EXPECT_TRUE(mapped.T_world_volume().isApprox(bg.T_world_volume(), 0.0));
  // The same voxel values through both views (different slot numbering: pool vs compact).
  int observed = 0;
  const Eigen::Vector3i dims = spec.dims_blocks * map::kBlockSize;
  for (int z = 0; z < dims.z(); z += 3) {
    for (int y = 0; y < dims.y(); y += 3) {
      for (int x = 0; x < dims.x(); x += 3) {
        const Eigen::Vector3i v(x, y, z);
        const int64_t a = mapped.view().voxelIndex(v), b = copied.view().voxelIndex(v);
        ASSERT_EQ(a < 0, b < 0) << "voxel " << v.transpose();
        if (a < 0) continue;
        const map::Voxel va = mapped.view().voxels[a], vb = copied.view().voxels[b];
        ASSERT_EQ(va.tsdf_q, vb.tsdf_q);
        ASSERT_EQ(va.weight_q, vb.weight_q);
        observed += va.weight_q > 0;
      }
    }
  }
  EXPECT_GT(observed, 1000);
  const map::Mesh bg_mapped = map::extractMesh(mapped.view(), mapped.T_world_volume());
  const map::Mesh bg_copied = map::extractMesh(copied.view(), copied.T_world_volume());
  EXPECT_GT(bg_mapped.triangles.size(), 5000u);
  expectSameMesh(bg_mapped, bg_copied);

  // Object volume with counts around a sphere, its mask from the sphere's own rendering.
  const Sphere& s = scene.spheres[1];
  Eigen::Isometry3d T_wv = Eigen::Isometry3d::Identity();
  T_wv.translation() = s.centre_w - Eigen::Vector3d::Constant(0.48);
  map::Volume obj(pool, map::VolumeSpec::object(o, 48, 0.02f), T_wv);
  const cv::Mat depth = renderDepth(scene, k, T0);
  const cv::Mat mask = sphereMask(scene, 1, k, T0);
  Frame f = makeFrame(depth, k, T0, cv::Mat(), mask);
  obj.fuse(f.input);
  const map::VolumeHostAccess obj_mapped(obj);
  const map::VolumeHostAccess obj_copied = map::VolumeHostAccess::downloaded(obj);
  ASSERT_NE(obj_mapped.view().count_index, nullptr);
  const map::Mesh m_mapped = map::extractMesh(obj_mapped.view(), obj_mapped.T_world_volume());
  const map::Mesh m_copied = map::extractMesh(obj_copied.view(), obj_copied.T_world_volume());
  EXPECT_GT(m_mapped.triangles.size(), 100u);
  expectSameMesh(m_mapped, m_copied);
  // Foreground only: the floor inside the box is left out (4557 vertices with it, 2864 without),
  // and the vertices are the sphere's: 91.5 % within 2 cm of it (the rest around the contact
  // with the floor and the silhouette, where one frame's counts are split).
  map::MeshOptions all_voxels;
  all_voxels.foreground_only = false;
  const map::Mesh with_floor =
      map::extractMesh(obj_mapped.view(), obj_mapped.T_world_volume(), all_voxels);
  EXPECT_GT(with_floor.vertices.size(), m_mapped.vertices.size() + 1000);
  size_t on_sphere = 0;
  for (const Eigen::Vector3f& p : m_mapped.vertices) {
    on_sphere += std::abs((p.cast<double>() - s.centre_w).norm() - s.radius_m) < 0.02;
  }
  EXPECT_GT(on_sphere, m_mapped.vertices.size() * 90 / 100);
}

}  // namespace
}  // namespace emf::test
