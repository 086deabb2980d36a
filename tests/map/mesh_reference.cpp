#include "mesh_reference.h"

#include <cmath>
#include <unordered_map>

#include "map/cube_polygons.h"
#include "map/map_math.h"
#include "map/voxel_layout.h"

namespace emf::test {

map::Mesh extractMeshReference(const map::VolumeHostView& view,
                               const Eigen::Isometry3d& T_world_volume,
                               const map::MeshOptions& options) {
  const map::CubeTopology& topo = map::cubeTopology();
  const Eigen::Vector3i dims = view.dims_blocks;
  const Eigen::Vector3i n = dims * map::kBlockSize + Eigen::Vector3i::Ones();
  const float vs = view.voxel_size_m;
  const int min_weight_q = static_cast<int>(std::ceil(options.min_weight * map::kWeightScale));
  map::Mesh mesh;
  std::unordered_map<int64_t, int> vertex_of_edge;
  std::vector<Eigen::Vector3f> face_normal_sum;
  auto corner = [&](const Eigen::Vector3i& v, float* psi) {
    const int64_t i = view.voxelIndex(v);
    if (i < 0) return false;
    const map::Voxel& vox = view.voxels[i];
    if (vox.weight_q <= 0 || vox.weight_q < min_weight_q) return false;
    *psi = vox.tsdf();
    return true;
  };
  const int blocks = dims.prod();
  for (int lin = 0; lin < blocks; ++lin) {
    if (view.index[lin] < 0) continue;
    const Eigen::Vector3i base = map::blockCoords(dims, lin) * map::kBlockSize;
    for (int i = 0; i < map::kBlockVoxels; ++i) {
      const Eigen::Vector3i v0 = base + Eigen::Vector3i(i % 8, (i / 8) % 8, i / 64);
      float f[8];
      bool ok = true;
      int inside = 0;
      for (int c = 0; c < 8 && ok; ++c) {
        ok = corner(v0 + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1), &f[c]);
        if (ok && f[c] < 0.0f) inside |= 1 << c;
      }
      if (!ok || inside == 0 || inside == 255) continue;
      bool truncated = false;
      for (const auto& e : topo.edge) {
        const float a = f[e[0]], b = f[e[1]];
        truncated |= (a < 0.0f) != (b < 0.0f) && std::fabs(a) >= 0.999f && std::fabs(b) >= 0.999f;
      }
      if (options.skip_truncated_crossings && truncated) continue;
      if (options.foreground_only && view.count_index &&
          map::samplePfgReference(view, (v0.cast<float>() + Eigen::Vector3f::Ones()) * vs) <=
              0.5f) {
        continue;
      }
      int loops[4][12], lengths[4];
      bool simple[4];
      const int nloops = map::cubeLoops(f, loops, lengths, simple);
      for (int l = 0; l < nloops; ++l) {
        int ids[12];
        for (int k = 0; k < lengths[l]; ++k) {
          const int e = loops[l][k];
          const int c0 = topo.edge[e][0], c1 = topo.edge[e][1];
          const Eigen::Vector3i vlow = v0 + Eigen::Vector3i(c0 & 1, (c0 >> 1) & 1, (c0 >> 2) & 1);
          const int axis = topo.edge_axis[e];
          const int64_t key =
              ((static_cast<int64_t>(vlow.z()) * n.y() + vlow.y()) * n.x() + vlow.x()) * 3 + axis;
          auto it = vertex_of_edge.find(key);
          if (it == vertex_of_edge.end()) {
            const float t = f[c0] / (f[c0] - f[c1]);
            Eigen::Vector3f p = vlow.cast<float>() + Eigen::Vector3f::Constant(0.5f);
            p[axis] += t;
            it = vertex_of_edge.emplace(key, static_cast<int>(mesh.vertices.size())).first;
            mesh.vertices.push_back(p * vs);
            face_normal_sum.push_back(Eigen::Vector3f::Zero());
          }
          ids[k] = it->second;
        }
        auto add = [&](int a, int b, int c) {
          mesh.triangles.emplace_back(a, b, c);
          const Eigen::Vector3f nrm =
              (mesh.vertices[b] - mesh.vertices[a]).cross(mesh.vertices[c] - mesh.vertices[a]);
          face_normal_sum[a] += nrm;
          face_normal_sum[b] += nrm;
          face_normal_sum[c] += nrm;
        };
        if (simple[l]) {
          for (int k = 1; k + 1 < lengths[l]; ++k) add(ids[0], ids[k], ids[k + 1]);
        } else {
          Eigen::Vector3f centre = Eigen::Vector3f::Zero();
          for (int k = 0; k < lengths[l]; ++k) centre += mesh.vertices[ids[k]];
          const int c = static_cast<int>(mesh.vertices.size());
          mesh.vertices.push_back(centre / static_cast<float>(lengths[l]));
          face_normal_sum.push_back(Eigen::Vector3f::Zero());
          for (int k = 0; k < lengths[l]; ++k) add(c, ids[k], ids[(k + 1) % lengths[l]]);
        }
      }
    }
  }
  mesh.normals.resize(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    float psi = 0.f, w = 0.f;
    Eigen::Vector3f g;
    Eigen::Vector3f nrm = face_normal_sum[i];
    if (map::sampleSdfReference(view, mesh.vertices[i], &psi, &w, &g) && g.norm() > 0.f) nrm = g;
    const float len = nrm.norm();
    mesh.normals[i] = len > 0.f ? Eigen::Vector3f(nrm / len) : Eigen::Vector3f(0.f, 0.f, 1.f);
  }
  if (options.world_frame) {
    const Eigen::Matrix3f R = T_world_volume.rotation().cast<float>();
    const Eigen::Vector3f t = T_world_volume.translation().cast<float>();
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      mesh.vertices[i] = R * mesh.vertices[i] + t;
      mesh.normals[i] = R * mesh.normals[i];
    }
  }
  return mesh;
}

}  // namespace emf::test
