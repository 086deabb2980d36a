#include "map/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace emf::map {

namespace {

float pointSegmentDistance(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                           const Eigen::Vector3f& b) {
  const Eigen::Vector3f ab = b - a;
  const float len2 = ab.squaredNorm();
  const float t = len2 > 0.f ? std::clamp((p - a).dot(ab) / len2, 0.f, 1.f) : 0.f;
  return (a + t * ab - p).norm();
}

Eigen::Vector3i cellOf(const Eigen::Vector3f& p, float cell) {
  return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / cell)),
                         static_cast<int>(std::floor(p.y() / cell)),
                         static_cast<int>(std::floor(p.z() / cell)));
}

}  // namespace

float pointTriangleDistance(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                            const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  // Project p on the plane; inside the triangle the plane distance is the answer, outside the
  // nearest point lies on an edge.
  const Eigen::Vector3f n = (b - a).cross(c - a);
  const float n2 = n.squaredNorm();
  if (n2 > 0.f) {
    const float dist_plane = (p - a).dot(n) / std::sqrt(n2);
    const Eigen::Vector3f q = p - dist_plane * n / std::sqrt(n2);
    // Barycentric signs via sub-triangle normals.
    const float wa = (c - b).cross(q - b).dot(n);
    const float wb = (a - c).cross(q - c).dot(n);
    const float wc = (b - a).cross(q - a).dot(n);
    if (wa >= 0.f && wb >= 0.f && wc >= 0.f) return std::fabs(dist_plane);
  }
  return std::min({pointSegmentDistance(p, a, b), pointSegmentDistance(p, b, c),
                   pointSegmentDistance(p, c, a)});
}

MeshDistance::MeshDistance(const Mesh& mesh, float cell_m) : mesh_(mesh), cell_m_(cell_m) {
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const Eigen::Vector3f lo =
        mesh.vertices[tri[0]].cwiseMin(mesh.vertices[tri[1]]).cwiseMin(mesh.vertices[tri[2]]);
    const Eigen::Vector3f hi =
        mesh.vertices[tri[0]].cwiseMax(mesh.vertices[tri[1]]).cwiseMax(mesh.vertices[tri[2]]);
    const Eigen::Vector3i c0 = cellOf(lo, cell_m), c1 = cellOf(hi, cell_m);
    for (int z = c0.z(); z <= c1.z(); ++z) {
      for (int y = c0.y(); y <= c1.y(); ++y) {
        for (int x = c0.x(); x <= c1.x(); ++x) {
          cells_[key(Eigen::Vector3i(x, y, z))].push_back(static_cast<int>(t));
        }
      }
    }
  }
}

int64_t MeshDistance::key(const Eigen::Vector3i& c) const {
  // 21 bits per axis (+-1M cells), enough for any scene at centimetre cells.
  const int64_t m = (1 << 21) - 1;
  return ((static_cast<int64_t>(c.x()) & m) << 42) | ((static_cast<int64_t>(c.y()) & m) << 21) |
         (static_cast<int64_t>(c.z()) & m);
}

float MeshDistance::distance(const Eigen::Vector3f& p, float max_m) const {
  const Eigen::Vector3i c = cellOf(p, cell_m_);
  const int max_ring = static_cast<int>(std::ceil(max_m / cell_m_));
  float best = std::numeric_limits<float>::infinity();
  for (int r = 0; r <= max_ring; ++r) {
    // Cells at Chebyshev distance exactly r.
    for (int z = -r; z <= r; ++z) {
      for (int y = -r; y <= r; ++y) {
        for (int x = -r; x <= r; ++x) {
          if (std::max({std::abs(x), std::abs(y), std::abs(z)}) != r) continue;
          auto it = cells_.find(key(c + Eigen::Vector3i(x, y, z)));
          if (it == cells_.end()) continue;
          for (int t : it->second) {
            const Eigen::Vector3i& tri = mesh_.triangles[static_cast<size_t>(t)];
            best = std::min(best,
                            pointTriangleDistance(p, mesh_.vertices[tri[0]], mesh_.vertices[tri[1]],
                                                  mesh_.vertices[tri[2]]));
          }
        }
      }
    }
    // Every triangle with a point within r cells has been seen.
    if (best <= static_cast<float>(r) * cell_m_) return best;
  }
  return best;
}

}  // namespace emf::map
