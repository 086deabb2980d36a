// The view check of a generated scene: detectability of the objects, the camera's nearest surface
// and the spread of the static scene's surface normals, rendered at 96x72.
#include "synth/scene_check.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace emf::synth::random_gen {

double normalSpread(const cv::Mat& depth, const cv::Mat& ids, const core::Intrinsics& K) {
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  int n = 0;
  auto point = [&](int u, int v) {
    const float z = depth.at<float>(v, u);
    return Eigen::Vector3d((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z);
  };
  auto valid = [&](int u, int v) {
    const float z = depth.at<float>(v, u);
    return ids.at<uint16_t>(v, u) == 0 && z == z && z > 0.4f && z < 4.5f;
  };
  for (int v = 0; v + 1 < depth.rows; ++v) {
    for (int u = 0; u + 1 < depth.cols; ++u) {
      if (!valid(u, v) || !valid(u + 1, v) || !valid(u, v + 1)) continue;
      const Eigen::Vector3d p = point(u, v);
      const Eigen::Vector3d a = point(u + 1, v) - p, b = point(u, v + 1) - p;
      // Skip pixels across depth edges.
      if (a.norm() > 0.05 * p.z() || b.norm() > 0.05 * p.z()) continue;
      const Eigen::Vector3d normal = a.cross(b).normalized();
      S += normal * normal.transpose();
      ++n;
    }
  }
  if (n < 20) return 0.0;
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S / n).eigenvalues()(0);
}

void viewCheck(const Scene& scene, int frames, std::vector<double>* detectable, double* nearest_m,
               std::vector<double>* spread) {
  constexpr double kMinBoxFraction = 48.0 / 640.0;
  RenderOptions ro;
  ro.width = 96;
  ro.height = 72;
  ro.threads = 1;
  const Renderer renderer(ro);
  detectable->assign(scene.objects.size(), 0.0);
  *nearest_m = 1e9;
  spread->clear();
  const int min_side = static_cast<int>(std::ceil(kMinBoxFraction * ro.width));
  const int min_pixels = minVisiblePixels(ro.width, ro.height);
  int checked = 0;
  for (int f = 0; f < frames; f += 8, ++checked) {
    const double t = scene.timeOf(f);
    std::vector<Eigen::Isometry3d> poses;
    for (const auto& o : scene.objects) poses.push_back(o.trajectory.pose(t));
    RenderOutput r;
    renderer.render(scene, scene.camera.pose(t), poses, &r);
    spread->push_back(normalSpread(r.depth, r.instance_ids, renderer.intrinsics()));
    for (size_t k = 0; k < scene.objects.size(); ++k) {
      const cv::Mat mask = r.instance_ids == scene.objects[k].id;
      if (cv::countNonZero(mask) < min_pixels) continue;
      const cv::Rect box = cv::boundingRect(mask);
      if (box.width >= min_side && box.height >= min_side) (*detectable)[k] += 1.0;
    }
    double lo, hi;
    cv::minMaxIdx(r.depth, &lo, &hi, nullptr, nullptr, r.depth == r.depth);
    *nearest_m = std::min(*nearest_m, lo);
  }
  for (auto& v : *detectable) v /= std::max(1, checked);
}

}  // namespace emf::synth::random_gen
