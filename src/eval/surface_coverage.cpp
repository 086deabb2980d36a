#include "eval/surface_coverage.h"

#include <cmath>
#include <cstdint>
#include <unordered_map>

namespace emf::eval {

size_t uncoveredPoints(const std::vector<Eigen::Vector3f>& reference,
                       const std::vector<Eigen::Vector3f>& points, double tol_m) {
  const auto key = [tol_m](const Eigen::Vector3f& p, int dx, int dy, int dz) {
    const int64_t x = static_cast<int64_t>(std::floor(p.x() / tol_m)) + dx;
    const int64_t y = static_cast<int64_t>(std::floor(p.y() / tol_m)) + dy;
    const int64_t z = static_cast<int64_t>(std::floor(p.z() / tol_m)) + dz;
    return (x * 73856093) ^ (y * 19349663) ^ (z * 83492791);
  };
  std::unordered_multimap<int64_t, Eigen::Vector3f> grid;
  grid.reserve(reference.size());
  for (const Eigen::Vector3f& r : reference) grid.emplace(key(r, 0, 0, 0), r);
  size_t missing = 0;
  for (const Eigen::Vector3f& p : points) {
    bool found = false;
    for (int n = 0; n < 27 && !found; ++n) {
      const auto range = grid.equal_range(key(p, n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1));
      for (auto it = range.first; it != range.second && !found; ++it) {
        found = (it->second - p).norm() <= tol_m;
      }
    }
    missing += !found;
  }
  return missing;
}

double coveredFraction(const std::vector<Eigen::Vector3f>& reference,
                       const std::vector<Eigen::Vector3f>& points, double tol_m) {
  if (points.empty()) return 0.0;
  return 1.0 - static_cast<double>(uncoveredPoints(reference, points, tol_m)) /
                   static_cast<double>(points.size());
}

}  // namespace emf::eval
