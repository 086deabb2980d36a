#include "pipeline/scene_up.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

namespace emf::pipeline {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr int kSamplesAcross = 80;      // normals sampled on a grid this many columns wide
constexpr int kModeCandidates = 256;    // normals tried as the mode
constexpr double kMaxEdgeRatio = 0.05;  // neighbour gap over this x depth x step: an edge

bool valid(const cv::Vec4f& p) { return p[3] != 0.0f; }

Eigen::Vector3d point(const cv::Vec4f& p) { return {p[0], p[1], p[2]}; }

}  // namespace

std::optional<Eigen::Vector3d> upInCamera(const cv::Mat& vertex) {
  const int step = std::max(1, vertex.cols / kSamplesAcross);
  const double cos_cone = std::cos(kMaxUpTiltDeg * kPi / 180.0);
  const double cos_cluster = std::cos(kUpClusterDeg * kPi / 180.0);
  const Eigen::Vector3d image_up(0.0, -1.0, 0.0);
  std::vector<Eigen::Vector3d> normals;  // facing the camera, within the cone
  int sampled = 0;
  for (int v = 0; v + step < vertex.rows; v += step) {
    for (int u = 0; u + step < vertex.cols; u += step) {
      const cv::Vec4f& p = vertex.at<cv::Vec4f>(v, u);
      const cv::Vec4f& pu = vertex.at<cv::Vec4f>(v, u + step);
      const cv::Vec4f& pv = vertex.at<cv::Vec4f>(v + step, u);
      if (!valid(p) || !valid(pu) || !valid(pv)) continue;
      const Eigen::Vector3d c = point(p);
      const Eigen::Vector3d du = point(pu) - c, dv = point(pv) - c;
      const double edge = kMaxEdgeRatio * c.z() * step;
      if (du.norm() > edge || dv.norm() > edge) continue;
      ++sampled;
      Eigen::Vector3d n = du.cross(dv);
      if (n.norm() <= 0.0) continue;
      n.normalize();
      if (n.dot(c) > 0.0) n = -n;  // towards the camera
      if (n.dot(image_up) >= cos_cone) normals.push_back(n);
    }
  }
  if (sampled == 0 || normals.empty()) return std::nullopt;
  // The mode: the candidate with the most normals within kUpClusterDeg.
  const size_t stride = std::max<size_t>(1, normals.size() / kModeCandidates);
  size_t best_count = 0;
  Eigen::Vector3d best = image_up;
  for (size_t i = 0; i < normals.size(); i += stride) {
    size_t count = 0;
    for (const auto& n : normals) count += n.dot(normals[i]) >= cos_cluster ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best = normals[i];
    }
  }
  if (static_cast<double>(best_count) < kMinUpSupport * sampled) return std::nullopt;
  // Refine: the mean of the mode's normals, twice.
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const auto& n : normals) {
      if (n.dot(best) >= cos_cluster) sum += n;
    }
    if (sum.norm() <= 0.0) break;
    best = sum.normalized();
  }
  return best;
}

}  // namespace emf::pipeline
