// How much of a surface a mesh holds: for sample points of the true surface, whether a mesh
// vertex lies within a distance of each (a hash grid of cells of that distance, 27 cells
// searched per point). Used by the moving-map bench and tests to check that the background mesh
// holds the surface of a whole walk.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace emf::eval {

/// How many of `points` have no point of `reference` within `tol_m` (metres, > 0).
size_t uncoveredPoints(const std::vector<Eigen::Vector3f>& reference,
                       const std::vector<Eigen::Vector3f>& points, double tol_m);

/// The share of `points` with a point of `reference` within `tol_m`; 0 without points.
double coveredFraction(const std::vector<Eigen::Vector3f>& reference,
                       const std::vector<Eigen::Vector3f>& points, double tol_m);

}  // namespace emf::eval
