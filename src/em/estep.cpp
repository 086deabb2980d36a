#include "em/estep.h"

#include <cmath>

#include "common/error.h"
#include "map/map_math.h"

namespace emf::em {

namespace {

bool insideGrid(const map::VolumeHostView& v, const Eigen::Vector3f& p) {
  const Eigen::Vector3f extent =
      v.dims_blocks.cast<float>() * (static_cast<float>(map::kBlockSize) * v.voxel_size_m);
  return (p.array() >= 0.0f).all() && (p.array() < extent.array()).all();
}

Eigen::Matrix<float, 3, 4> poseRows(const Eigen::Isometry3d& T) {
  return T.matrix().topRows<3>().cast<float>();
}

}  // namespace

float associationLikelihood(const EStepHostVolume& volume, const Eigen::Vector3f& p_camera,
                            const EmOptions& options, float* abs_psi) {
  const Eigen::Matrix<float, 3, 4> M = poseRows(volume.T_volume_camera);
  // Same operation order as emf_transform (FP_CONTRACT OFF on the device).
  Eigen::Vector3f p;
  for (int r = 0; r < 3; ++r) {
    p[r] = M(r, 0) * p_camera.x() + M(r, 1) * p_camera.y() + M(r, 2) * p_camera.z() + M(r, 3);
  }
  *abs_psi = NAN;
  if (!insideGrid(volume.view, p) || !volume.claim.contains(p)) return 0.0f;
  float psi = NAN, weight = 0.0f;
  Eigen::Vector3f gradient;
  const bool ok = map::sampleSdfReference(volume.view, p, &psi, &weight, &gradient);
  const float truncation = volume.view.truncation_m;
  *abs_psi = (ok && weight >= static_cast<float>(options.min_weight)) ? std::fabs(psi) : truncation;
  const float pfg = volume.view.count_index ? map::samplePfgReference(volume.view, p) : 1.0f;
  if (options.association == Association::kPfg) return volume.view.count_index ? pfg : 1.0f;
  const float sigma = static_cast<float>(options.sigma_m);
  const float alpha = static_cast<float>(options.alpha);
  return alpha / (2.0f * sigma) * std::exp(-*abs_psi / sigma) * pfg +
         (1.0f - alpha) * static_cast<float>(options.p_uniform);
}

std::vector<cv::Mat> eStepReference(const std::vector<EStepHostVolume>& volumes,
                                    const cv::Mat& vertex, const EmOptions& options,
                                    cv::Mat* residual) {
  if (vertex.type() != CV_32FC4) throw InvalidArgument("eStepReference: vertex must be CV_32FC4");
  std::vector<cv::Mat> q;
  for (size_t i = 0; i < volumes.size(); ++i) q.emplace_back(vertex.size(), CV_32F, 0.0f);
  cv::Mat res(vertex.size(), CV_32F, NAN);
  std::vector<float> lik(volumes.size());
  for (int v = 0; v < vertex.rows; ++v) {
    for (int u = 0; u < vertex.cols; ++u) {
      const cv::Vec4f p = vertex.at<cv::Vec4f>(v, u);
      if (p[3] == 0.0f) continue;
      float sum = 0.0f, best = -1.0f;
      for (size_t i = 0; i < volumes.size(); ++i) {
        float abs_psi = NAN;
        lik[i] = associationLikelihood(volumes[i], {p[0], p[1], p[2]}, options, &abs_psi);
        sum += lik[i];
        if (lik[i] > best) {
          best = lik[i];
          res.at<float>(v, u) = lik[i] > 0.0f ? abs_psi : NAN;
        }
      }
      if (options.association == Association::kPfg) {
        float max_pfg = 0.0f;
        for (size_t i = 1; i < volumes.size(); ++i) max_pfg = std::max(max_pfg, lik[i]);
        for (size_t i = 0; i < volumes.size(); ++i) {
          q[i].at<float>(v, u) = i == 0 ? lik[0] * (1.0f - max_pfg) : lik[i];
        }
        float abs_psi = NAN;
        associationLikelihood(volumes[0], {p[0], p[1], p[2]}, options, &abs_psi);
        res.at<float>(v, u) = abs_psi;
        continue;
      }
      for (size_t i = 0; i < volumes.size(); ++i) {
        q[i].at<float>(v, u) = sum > 0.0f ? lik[i] / sum : 0.0f;
      }
    }
  }
  if (residual) *residual = res;
  return q;
}

EStep::EStep(cl::Context& ctx, const EmOptions& options, int width, int height, int max_volumes)
    : ctx_(ctx), options_(options), width_(width), height_(height) {
  if (width <= 0 || height <= 0 || max_volumes < 1) {
    throw InvalidArgument("EStep: bad image size " + std::to_string(width) + "x" +
                          std::to_string(height) + " or volume count " +
                          std::to_string(max_volumes));
  }
  const size_t bytes = sizeof(float) * static_cast<size_t>(width) * height;
  for (int i = 0; i < max_volumes; ++i) q_.push_back(ctx.buffer(CL_MEM_READ_WRITE, bytes));
  sum_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  best_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  residual_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  likelihood16_ = ctx.kernel("estep", "estep_likelihood16");
  normalize_ = ctx.kernel("estep", "estep_normalize");
}

void EStep::compute(cl_mem vertex_map, const std::vector<EStepVolume>& volumes) {
  if (volumes.empty() || volumes.size() > q_.size()) {
    throw InvalidArgument("EStep::compute: " + std::to_string(volumes.size()) +
                          " volumes, capacity " + std::to_string(q_.size()));
  }
  const int count = width_ * height_;
  const cl_int pfg_mode = options_.association == Association::kPfg ? 1 : 0;
  for (size_t i = 0; i < volumes.size(); ++i) {
    const EStepVolume& v = volumes[i];
    const Eigen::Matrix<float, 3, 4> M = poseRows(v.T_volume_camera);
    cl_float4 rows[3];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) rows[r].s[c] = M(r, c);
    }
    const cl_int4 dims = {
        {v.view.dims_blocks.x(), v.view.dims_blocks.y(), v.view.dims_blocks.z(), 0}};
    const cl_int has_counts = v.count_index != nullptr ? 1 : 0;
    const cl_float4 claim_lo = {{v.claim.lo.x(), v.claim.lo.y(), v.claim.lo.z(), 0.0f}};
    const cl_float4 claim_hi = {{v.claim.hi.x(), v.claim.hi.y(), v.claim.hi.z(), 0.0f}};
    // 16 pixels per work item.
    cl::setArgs(likelihood16_, vertex_map, count, rows[0], rows[1], rows[2], v.view.index,
                has_counts ? v.count_index : v.view.index, has_counts, dims, claim_lo, claim_hi,
                v.view.voxels, v.view.voxel_size_m, v.view.truncation_m,
                static_cast<float>(options_.sigma_m), static_cast<float>(options_.alpha),
                static_cast<float>(options_.p_uniform), static_cast<float>(options_.min_weight),
                pfg_mode, static_cast<cl_int>(i == 0 ? 1 : 0), q_[i].get(), sum_.get(), best_.get(),
                residual_.get());
    cl::enqueue(ctx_.queue(), likelihood16_, static_cast<size_t>((count + 15) / 16), 0, 0, 64);
  }
  for (size_t i = 0; i < volumes.size(); ++i) {
    cl::setArgs(normalize_, q_[i].get(), sum_.get(), count, pfg_mode,
                static_cast<cl_int>(i == 0 ? 1 : 0));
    cl::enqueue(ctx_.queue(), normalize_, static_cast<size_t>(count), 0, 0, 64);
  }
  count_ = static_cast<int>(volumes.size());
}

cv::Mat EStep::downloadQ(int i) const {
  cv::Mat m(height_, width_, CV_32F);
  ctx_.read(q_.at(static_cast<size_t>(i)), m.data, m.total() * sizeof(float));
  return m;
}

cv::Mat EStep::downloadResidual() const {
  cv::Mat m(height_, width_, CV_32F);
  ctx_.read(residual_, m.data, m.total() * sizeof(float));
  return m;
}

}  // namespace emf::em
