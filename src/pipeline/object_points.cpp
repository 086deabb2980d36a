#include "pipeline/object_points.h"

#include <algorithm>

namespace emf::pipeline {

std::vector<Eigen::Vector3d> maskedPoints(const cv::Mat& vertex, const cv::Mat& mask) {
  std::vector<Eigen::Vector3d> points;
  for (int v = 0; v < vertex.rows; ++v) {
    for (int u = 0; u < vertex.cols; ++u) {
      if (mask.at<float>(v, u) <= kMaskInside) continue;
      const cv::Vec4f p = vertex.at<cv::Vec4f>(v, u);
      if (p[3] == 0.0f) continue;
      points.emplace_back(p[0], p[1], p[2]);
    }
  }
  return points;
}

Eigen::Vector3d percentile(std::vector<Eigen::Vector3d> points, double f) {
  Eigen::Vector3d out;
  const size_t k = std::min(points.size() - 1, static_cast<size_t>(f * (points.size() - 1)));
  for (int a = 0; a < 3; ++a) {
    std::nth_element(
        points.begin(), points.begin() + static_cast<std::ptrdiff_t>(k), points.end(),
        [a](const Eigen::Vector3d& x, const Eigen::Vector3d& y) { return x[a] < y[a]; });
    out[a] = points[k][a];
  }
  return out;
}

}  // namespace emf::pipeline
