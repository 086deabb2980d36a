// Distance of points to a triangle mesh (exact point-to-triangle distance, uniform grid of
// triangle buckets). Used to measure reconstruction error: mean distance of ground-truth
// points to the extracted surface.
#pragma once

#include <Eigen/Core>
#include <unordered_map>
#include <vector>

#include "map/mesh.h"

namespace emf::map {

class MeshDistance {
 public:
  /// Buckets the triangles of `mesh` into cells of `cell_m` metres.
  MeshDistance(const Mesh& mesh, float cell_m);

  /// Distance (metres) from p to the nearest triangle if it is within `max_m`, else a value
  /// > max_m (infinity when nothing was found).
  float distance(const Eigen::Vector3f& p, float max_m) const;

 private:
  int64_t key(const Eigen::Vector3i& c) const;
  const Mesh& mesh_;
  float cell_m_;
  std::unordered_map<int64_t, std::vector<int>> cells_;
};

/// Exact distance from p to triangle (a, b, c) (degenerate triangles: to their edges).
float pointTriangleDistance(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                            const Eigen::Vector3f& b, const Eigen::Vector3f& c);

}  // namespace emf::map
