// The SLAM state a detector plugin reads (emf_detector_frame.background_association and
// .residual): which pixels the background already explains. Used by detectors that propose
// what the models explain badly (motion).
#include <cmath>

#include "pipeline/slam_system.h"

namespace emf::pipeline {

cv::Mat SlamSystem::backgroundSdf(const cv::Mat& vertex) {
  const int n = vertex.rows * vertex.cols;
  const Eigen::Isometry3f T_volume_camera =
      (background_->T_world_volume().inverse() * T_world_camera_).cast<float>();
  cv::Mat points(vertex.rows, vertex.cols, CV_32FC4);
  for (int v = 0; v < vertex.rows; ++v) {
    const cv::Vec4f* in = vertex.ptr<cv::Vec4f>(v);
    cv::Vec4f* out = points.ptr<cv::Vec4f>(v);
    for (int u = 0; u < vertex.cols; ++u) {
      // Invalid pixels sample far outside every grid (NaN psi).
      const Eigen::Vector3f p =
          in[u][3] > 0.0f ? T_volume_camera * Eigen::Vector3f(in[u][0], in[u][1], in[u][2])
                          : Eigen::Vector3f::Constant(-1e6f);
      out[u] = cv::Vec4f(p.x(), p.y(), p.z(), 0.0f);
    }
  }
  ctx_.write(probe_points_, points.data, static_cast<size_t>(n) * sizeof(cv::Vec4f));
  sdf_sampler_->sample(*background_, probe_points_, n, probe_psi_, probe_weight_, probe_gradient_,
                       probe_pfg_);
  cv::Mat psi(vertex.rows, vertex.cols, CV_32F), weight(vertex.rows, vertex.cols, CV_32F);
  ctx_.read(probe_psi_, psi.data, static_cast<size_t>(n) * sizeof(float));
  ctx_.read(probe_weight_, weight.data, static_cast<size_t>(n) * sizeof(float));
  psi.setTo(std::nanf(""), weight < static_cast<float>(config_.em.min_weight));
  return psi;
}

void SlamSystem::detectorFeedback(cv::Mat* q0, cv::Mat* residual) {
  if (objects_->eStepIds().empty()) {  // no E-step this frame yet (no objects were tracked)
    estep_.compute(
        objects_->vertexMap(),
        objects_->eStepVolumes(T_world_camera_, objects_->posesInCamera(T_world_camera_, false)));
  }
  *q0 = estep_.downloadQ(0);
  *residual = estep_.downloadResidual();
  const cv::Mat sdf = backgroundSdf(objects_->downloadVertexMap());
  // q_0 is normalised over the volumes only, so with the background alone it is 1 wherever the
  // background volume reaches. The detector gets what "explained by the background" means:
  // at most the posterior of the background's inlier term against the outlier term; and fully
  // explained where the point lies behind the background's surface by more than sigma: a
  // disocclusion (what stood there moved away; the background carves it), not a new object.
  const em::EmOptions& e = config_.em;
  const double outlier = (1.0 - e.alpha) * e.p_uniform;
  for (int v = 0; v < q0->rows; ++v) {
    float* q = q0->ptr<float>(v);
    const float* r = residual->ptr<float>(v);
    const float* s = sdf.ptr<float>(v);
    for (int u = 0; u < q0->cols; ++u) {
      if (!std::isfinite(r[u])) continue;
      if (std::isfinite(s[u]) && s[u] < -e.sigma_m) {
        q[u] = 1.0f;
        continue;
      }
      const double inlier = e.alpha / (2.0 * e.sigma_m) * std::exp(-r[u] / e.sigma_m);
      q[u] = std::min(q[u], static_cast<float>(inlier / (inlier + outlier)));
    }
  }
}

}  // namespace emf::pipeline
