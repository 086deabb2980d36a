#include "map/mesh.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "common/error.h"
#include "map/cube_polygons.h"

namespace emf::map {

namespace {

/// Streams the mesh of a volume to a MeshSink one z-layer of blocks at a time.
///
/// Vertices sit on cube edges; edge (v, axis) from voxel v is keyed by v (z-major, so keys order
/// by z) and the axis, a loop's centre vertex by its cube and loop. A cube at voxel v0 touches
/// only edges whose lower voxel has z >= v0.z, so once the walk (in block order: z-layers of
/// blocks ascending) reaches a layer starting at voxel z0, every vertex with z < z0 is final:
/// its normal is computed and it is handed to the sink with its output index. Triangles wait
/// until their three vertices are final (at most one layer). Memory: the vertices of about two
/// block layers, not the whole mesh.
class MeshStreamer {
 public:
  MeshStreamer(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
               const MeshOptions& options, MeshSink& sink)
      : view_(view),
        options_(options),
        sink_(sink),
        stride_x_(view.dims_blocks.x() * kBlockSize + 1),
        stride_y_(view.dims_blocks.y() * kBlockSize + 1),
        R_(T_world_volume.rotation().cast<float>()),
        t_(T_world_volume.translation().cast<float>()) {}

  void run() {
    const CubeTopology& topo = cubeTopology();
    const Eigen::Vector3i dims = view_.dims_blocks;
    const int64_t blocks = static_cast<int64_t>(dims.x()) * dims.y() * dims.z();
    const int64_t layer_blocks = static_cast<int64_t>(dims.x()) * dims.y();
    const float vs = view_.voxel_size_m;
    int current_layer = -1;
    for (int64_t lin = 0; lin < blocks; ++lin) {
      if (view_.index[lin] < 0) continue;
      const int layer = static_cast<int>(lin / layer_blocks);
      if (layer != current_layer) {
        finalizeBelow(static_cast<int64_t>(layer) * kBlockSize * stride_y_ * stride_x_ * 8);
        current_layer = layer;
      }
      const Eigen::Vector3i base = blockCoords(dims, static_cast<int>(lin)) * kBlockSize;
      // The block's cubes have their corners in [base, base + kBlockSize].
      if (options_.leaving && allInside(base, base + Eigen::Vector3i::Constant(kBlockSize))) {
        continue;
      }
      for (int lz = 0; lz < kBlockSize; ++lz) {
        for (int ly = 0; ly < kBlockSize; ++ly) {
          for (int lx = 0; lx < kBlockSize; ++lx) {
            const Eigen::Vector3i v0 = base + Eigen::Vector3i(lx, ly, lz);
            if (options_.leaving && allInside(v0, v0 + Eigen::Vector3i::Ones())) continue;
            float f[8];
            bool ok = true;
            int inside = 0;
            for (int n = 0; n < 8 && ok; ++n) {
              ok = corner(v0 + Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1), &f[n]);
              if (ok && f[n] < 0.0f) inside |= 1 << n;
            }
            if (!ok || inside == 0 || inside == 255) continue;
            if (options_.skip_truncated_crossings) {
              bool truncated = false;
              for (const auto& e : topo.edge) {
                const float a = f[e[0]], b = f[e[1]];
                if ((a < 0.0f) != (b < 0.0f) && std::fabs(a) >= 0.999f && std::fabs(b) >= 0.999f) {
                  truncated = true;
                }
              }
              if (truncated) continue;
            }
            if (options_.foreground_only && view_.count_index &&
                samplePfgReference(view_, (v0.cast<float>() + Eigen::Vector3f::Ones()) * vs) <=
                    0.5f) {
              continue;
            }
            meshCube(v0, f);
          }
        }
      }
    }
    finalizeBelow(std::numeric_limits<int64_t>::max());
    if (!pending_.empty()) {
      throw std::logic_error("mesh extraction: " + std::to_string(pending_.size()) +
                             " triangles reference vertices never finalised");
    }
  }

 private:
  struct LiveVertex {
    Eigen::Vector3f p;     // volume frame, metres
    Eigen::Vector3f nsum;  // area-weighted sum of the adjacent triangles' normals
  };
  using Triangle = std::array<int64_t, 3>;  // vertex keys

  /// Whether the voxels of [lo, hi] (inclusive) all lie in options_.leaving's box.
  bool allInside(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const {
    const MeshOptions::VoxelBox& box = *options_.leaving;
    return (lo.array() >= box.min.array()).all() && (hi.array() < box.max.array()).all();
  }

  /// Key of edge `axis` (0-2) from voxel v, or of loop centre `axis` - 3 (3-6) of cube v.
  int64_t key(const Eigen::Vector3i& v, int slot) const {
    return ((static_cast<int64_t>(v.z()) * stride_y_ + v.y()) * stride_x_ + v.x()) * 8 + slot;
  }

  bool corner(const Eigen::Vector3i& v, float* psi) const {
    const int64_t i = view_.voxelIndex(v);
    if (i < 0) return false;
    const Voxel& vox = view_.voxels[i];
    if (vox.weight_q <= 0 || vox.weight_q < min_weight_q_) return false;
    *psi = vox.tsdf();
    return true;
  }

  void meshCube(const Eigen::Vector3i& v0, const float f[8]) {
    const CubeTopology& topo = cubeTopology();
    const float vs = view_.voxel_size_m;
    int loops[4][12];
    int lengths[4];
    bool simple[4];
    const int nloops = cubeLoops(f, loops, lengths, simple);
    for (int l = 0; l < nloops; ++l) {
      int64_t ids[12];
      LiveVertex* verts[12];
      for (int k = 0; k < lengths[l]; ++k) {
        const int e = loops[l][k];
        const int c0 = topo.edge[e][0], c1 = topo.edge[e][1];
        const Eigen::Vector3i vlow = v0 + Eigen::Vector3i(c0 & 1, (c0 >> 1) & 1, (c0 >> 2) & 1);
        const int axis = topo.edge_axis[e];
        ids[k] = key(vlow, axis);
        auto it = live_.find(ids[k]);
        if (it == live_.end()) {
          const float t = f[c0] / (f[c0] - f[c1]);
          Eigen::Vector3f p = vlow.cast<float>() + Eigen::Vector3f::Constant(0.5f);
          p[axis] += t;
          it = live_.emplace(ids[k], LiveVertex{p * vs, Eigen::Vector3f::Zero()}).first;
        }
        verts[k] = &it->second;
      }
      if (simple[l]) {
        for (int k = 1; k + 1 < lengths[l]; ++k) {
          addTriangle({ids[0], ids[k], ids[k + 1]}, {verts[0], verts[k], verts[k + 1]});
        }
      } else {
        // Fan around a vertex at the loop's centroid, inside this cube only.
        Eigen::Vector3f centre = Eigen::Vector3f::Zero();
        for (int k = 0; k < lengths[l]; ++k) centre += verts[k]->p;
        const int64_t c = key(v0, 3 + l);
        LiveVertex* cv = &live_
                              .emplace(c, LiveVertex{centre / static_cast<float>(lengths[l]),
                                                     Eigen::Vector3f::Zero()})
                              .first->second;
        for (int k = 0; k < lengths[l]; ++k) {
          const int k1 = (k + 1) % lengths[l];
          addTriangle({c, ids[k], ids[k1]}, {cv, verts[k], verts[k1]});
        }
      }
    }
  }

  void addTriangle(const Triangle& tri, const std::array<LiveVertex*, 3>& v) {
    pending_.push_back(tri);
    const Eigen::Vector3f nrm = (v[1]->p - v[0]->p).cross(v[2]->p - v[0]->p);
    for (LiveVertex* x : v) x->nsum += nrm;
  }

  /// Hands every vertex with a key below `end` (below a voxel layer) to the sink, in key order,
  /// then every waiting triangle whose vertices are all final.
  void finalizeBelow(int64_t end) {
    std::vector<int64_t> keys;
    for (const auto& [k, v] : live_) {
      if (k < end) keys.push_back(k);
    }
    std::sort(keys.begin(), keys.end());
    if (keys.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max() - next_index_)) {
      throw ResourceError(
          "mesh extraction: more than 2^31 - 1 vertices (PLY and emf_mesh "
          "indices are 32-bit); extract a smaller volume");
    }
    done_prev_ = std::move(done_);
    done_.clear();
    positions_.clear();
    normals_.clear();
    for (int64_t k : keys) {
      auto it = live_.find(k);
      const LiveVertex& v = it->second;
      // Normal: the SDF gradient where the trilinear field is available, else the
      // area-weighted normal of the adjacent triangles.
      float psi = 0.f, w = 0.f;
      Eigen::Vector3f g;
      Eigen::Vector3f n = v.nsum;
      if (sampleSdfReference(view_, v.p, &psi, &w, &g) && g.norm() > 0.f) n = g;
      const float len = n.norm();
      n = len > 0.f ? Eigen::Vector3f(n / len) : Eigen::Vector3f(0.f, 0.f, 1.f);
      positions_.push_back(options_.world_frame ? Eigen::Vector3f(R_ * v.p + t_) : v.p);
      normals_.push_back(options_.world_frame ? Eigen::Vector3f(R_ * n) : n);
      done_.emplace(k, next_index_++);
      live_.erase(it);
    }
    if (!positions_.empty())
      sink_.addVertices(positions_.data(), normals_.data(), positions_.size());
    triangles_.clear();
    std::vector<Triangle> waiting;
    for (const Triangle& tri : pending_) {
      Eigen::Vector3i out;
      bool ready = true;
      for (int c = 0; c < 3 && ready; ++c) {
        auto it = done_.find(tri[c]);
        if (it == done_.end()) {
          it = done_prev_.find(tri[c]);
          ready = it != done_prev_.end();
        }
        if (ready) out[c] = it->second;
      }
      if (ready) {
        triangles_.push_back(out);
      } else {
        waiting.push_back(tri);
      }
    }
    pending_.swap(waiting);
    if (!triangles_.empty()) sink_.addTriangles(triangles_.data(), triangles_.size());
  }

  const VolumeHostView& view_;
  const MeshOptions& options_;
  MeshSink& sink_;
  const int64_t stride_x_, stride_y_;
  const Eigen::Matrix3f R_;
  const Eigen::Vector3f t_;
  const int min_weight_q_ = static_cast<int>(std::ceil(options_.min_weight * kWeightScale));
  std::unordered_map<int64_t, LiveVertex> live_;
  std::unordered_map<int64_t, int32_t> done_, done_prev_;  // key -> output index
  std::vector<Triangle> pending_;
  int32_t next_index_ = 0;
  std::vector<Eigen::Vector3f> positions_, normals_;  // one batch for the sink
  std::vector<Eigen::Vector3i> triangles_;
};

/// Collects the streamed mesh in memory.
class MeshCollector : public MeshSink {
 public:
  explicit MeshCollector(Mesh* mesh) : mesh_(mesh) {}
  void addVertices(const Eigen::Vector3f* positions, const Eigen::Vector3f* normals,
                   size_t count) override {
    mesh_->vertices.insert(mesh_->vertices.end(), positions, positions + count);
    mesh_->normals.insert(mesh_->normals.end(), normals, normals + count);
  }
  void addTriangles(const Eigen::Vector3i* triangles, size_t count) override {
    mesh_->triangles.insert(mesh_->triangles.end(), triangles, triangles + count);
  }

 private:
  Mesh* mesh_;
};

}  // namespace

void extractMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                 const MeshOptions& options, MeshSink& sink) {
  MeshStreamer(view, T_world_volume, options, sink).run();
}

Mesh extractMesh(const VolumeHostView& view, const Eigen::Isometry3d& T_world_volume,
                 const MeshOptions& options) {
  Mesh mesh;
  MeshCollector collector(&mesh);
  extractMesh(view, T_world_volume, options, collector);
  return mesh;
}

Mesh extractMesh(const VolumeHostData& vol, const MeshOptions& options) {
  return extractMesh(vol.view(), vol.T_world_volume, options);
}

}  // namespace emf::map
