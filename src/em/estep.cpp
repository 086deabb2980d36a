#include "em/estep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "cl/cl_error.h"
#include "cl/work_counters.h"
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
  for (int i = 0; i < max_volumes; ++i) {
    q_.push_back(ctx.buffer(CL_MEM_READ_WRITE, bytes));
    likelihood_.push_back(ctx.buffer(CL_MEM_READ_WRITE, bytes));
  }
  sum_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  best_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  residual_ = ctx.buffer(CL_MEM_READ_WRITE, bytes);
  host_claimed_.assign(4 * static_cast<size_t>(max_volumes), std::numeric_limits<cl_int>::max());
  claimed_ =
      ctx.buffer(CL_MEM_READ_WRITE, sizeof(cl_int) * host_claimed_.size(), host_claimed_.data());
  likelihood_lanes_ = ctx.kernel("estep", "estep_likelihood_lanes");
  normalize_ = ctx.kernel("estep", "estep_normalize");
  clear_ = ctx.kernel("estep", "estep_clear");
  accumulate_ = ctx.kernel("estep", "estep_accumulate");
  written_.assign(q_.size(), cv::Rect(0, 0, width, height));
  rects_.reserve(q_.size());
  keys_.reserve(q_.size());
  last_objects_.reserve(q_.size());
}

// The background pass's object rectangles (kernels_cl/estep.cl EStepCover).
constexpr int kCoverRects = 8;
struct EStepCover {
  cl_int4 rects[kCoverRects];
  cl_int count;
  cl_int pad[3];
};
static_assert(sizeof(EStepCover) == 144, "layout of kernels_cl/estep.cl EStepCover");

namespace {
cl_int4 rectArg(const cv::Rect& r) { return {{r.x, r.y, r.width, r.height}}; }

// At most kCoverRects rectangles covering `rects`: while there are more, the pair whose
// bounding rectangle adds the least area is merged.
EStepCover coverOf(std::vector<cv::Rect> rects) {
  rects.erase(
      std::remove_if(rects.begin(), rects.end(), [](const cv::Rect& r) { return r.empty(); }),
      rects.end());
  while (rects.size() > static_cast<size_t>(kCoverRects)) {
    size_t best_a = 0, best_b = 1;
    int64_t best_cost = std::numeric_limits<int64_t>::max();
    for (size_t a = 0; a < rects.size(); ++a) {
      for (size_t b = a + 1; b < rects.size(); ++b) {
        const int64_t cost =
            static_cast<int64_t>((rects[a] | rects[b]).area()) - rects[a].area() - rects[b].area();
        if (cost < best_cost) {
          best_cost = cost;
          best_a = a;
          best_b = b;
        }
      }
    }
    rects[best_a] |= rects[best_b];
    rects.erase(rects.begin() + static_cast<std::ptrdiff_t>(best_b));
  }
  EStepCover cover{};
  cover.count = static_cast<cl_int>(rects.size());
  for (size_t i = 0; i < rects.size(); ++i) cover.rects[i] = rectArg(rects[i]);
  return cover;
}

// Work-group shapes: 4 x 16 items of ctx_.lanes() pixels, and 32 x 4 items of one pixel.
constexpr size_t kLikelihoodLocalX = 4, kLikelihoodLocalY = 16;
constexpr size_t kPixelLocalX = 32, kPixelLocalY = 4;
}  // namespace

void EStep::compute(cl_mem vertex_map, const std::vector<EStepVolume>& volumes,
                    bool residual_everywhere, bool same_objects) {
  if (volumes.empty() || volumes.size() > q_.size()) {
    throw InvalidArgument("EStep::compute: " + std::to_string(volumes.size()) +
                          " volumes, capacity " + std::to_string(q_.size()));
  }
  const cl_int pfg_mode = options_.association == Association::kPfg ? 1 : 0;
  setRectsAndKeys(volumes);
  const std::vector<cv::Rect>& rects = rects_;
  // The objects' likelihoods of the last call still hold: add them instead of sampling again.
  const bool reuse =
      same_objects && !residual_everywhere && vertex_map == last_vertex_ && keys_ == last_objects_;
  EStepCover cover{};
  if (residual_everywhere) {
    cover.count = -1;
  } else if (reuse) {
    // The objects' likelihoods are known: the background's SDF is wanted only where they claim
    // pixels (elsewhere q_0 is 1 wherever the background's grid holds the point, exact or not).
    if (!claimed_read_) readClaimed(volumes.size());
    std::vector<cv::Rect> claimed;
    for (size_t i = 1; i < volumes.size(); ++i) {
      claimed.push_back(rects[i].empty() ? cv::Rect() : decodeClaimed(i));
    }
    cover = coverOf(claimed);
  } else {
    cover = coverOf(std::vector<cv::Rect>(rects.begin() + 1, rects.end()));
  }
  for (size_t i = 0; i < volumes.size(); ++i) {
    const EStepVolume& v = volumes[i];
    const cv::Rect& rect = rects[i];
    // Keep q_i at 0 outside this E-step's rectangle: clear what an earlier one wrote outside it.
    const cv::Rect& old = written_[i];
    if (!old.empty() && (old & rect) != old) {
      cl::setArgs(clear_, q_[i].get(), width_, rectArg(old));
      cl::enqueue(ctx_.queue(), clear_, static_cast<size_t>(old.width),
                  static_cast<size_t>(old.height), 0, kPixelLocalX, kPixelLocalY);
    }
    written_[i] = rect;
    if (rect.empty()) continue;
    if (reuse && i > 0) {
      cl::setArgs(accumulate_, likelihood_[i].get(), sum_.get(), width_, rectArg(rect), pfg_mode);
      cl::enqueue(ctx_.queue(), accumulate_, static_cast<size_t>(rect.width),
                  static_cast<size_t>(rect.height), 0, kPixelLocalX, kPixelLocalY);
      continue;
    }
    enqueueLikelihood(vertex_map, v, static_cast<int>(i), rect, cover, 1);
  }
  for (size_t i = 0; i < volumes.size(); ++i) {
    if (!rects[i].empty()) enqueueNormalize(static_cast<int>(i), rects[i], 1);
  }
  count_ = static_cast<int>(volumes.size());
  last_objects_.swap(keys_);
  last_vertex_ = vertex_map;
  reused_ = reuse;
}

cv::Rect EStep::claimedPixels(int i) {
  if (i < 1 || i >= count_) {
    throw InvalidArgument("EStep::claimedPixels: volume " + std::to_string(i) + " of " +
                          std::to_string(count_));
  }
  if (rects_[static_cast<size_t>(i)].empty()) return cv::Rect();  // no pass: q is 0 everywhere
  // Reused likelihoods keep the rectangles of the pass that sampled them.
  if (!claimed_read_) readClaimed(static_cast<size_t>(count_));
  return decodeClaimed(static_cast<size_t>(i));
}

void EStep::readClaimed(size_t n) {
  ctx_.read(claimed_, host_claimed_.data(), sizeof(cl_int) * 4 * n);
  claimed_read_ = true;
}

cv::Rect EStep::decodeClaimed(size_t i) const {
  const cl_int* c = host_claimed_.data() + 4 * i;
  if (c[0] == std::numeric_limits<cl_int>::max()) return cv::Rect();  // no pixel claimed
  return cv::Rect(c[0], c[1], -c[2] - c[0] + 1, -c[3] - c[1] + 1);
}

void EStep::setRectsAndKeys(const std::vector<EStepVolume>& volumes) {
  const cv::Rect image(0, 0, width_, height_);
  rects_.assign(volumes.size(), image);
  keys_.clear();
  for (size_t i = 1; i < volumes.size(); ++i) {
    const EStepVolume& v = volumes[i];
    if (v.pixels) rects_[i] = *v.pixels & image;
    keys_.push_back({v.view.index, v.count_index, v.view.voxels, poseRows(v.T_volume_camera),
                     v.claim.lo, v.claim.hi, rects_[i]});
  }
}

void EStep::enqueueLikelihood(cl_mem vertex_map, const EStepVolume& v, int i, const cv::Rect& grid,
                              const EStepCover& cover, int stride) {
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
  const cl_int pfg_mode = options_.association == Association::kPfg ? 1 : 0;
  if (i > 0) {
    // The pass keeps the rectangle of the pixels it gives a likelihood above 0.
    const cl_int none = std::numeric_limits<cl_int>::max();
    EMF_CL_CHECK(clEnqueueFillBuffer(ctx_.queue(), claimed_.get(), &none, sizeof(none),
                                     sizeof(cl_int) * 4 * static_cast<size_t>(i),
                                     sizeof(cl_int) * 4, 0, nullptr, nullptr));
    cl::countLaunch();
    claimed_read_ = false;
  }
  // ctx_.lanes() pixels of a row per work item.
  cl::setArgs(likelihood_lanes_, vertex_map, width_, rectArg(grid), rows[0], rows[1], rows[2],
              v.view.index, has_counts ? v.count_index : v.view.index, has_counts, dims, claim_lo,
              claim_hi, v.view.voxels, v.view.voxel_size_m, v.view.truncation_m,
              static_cast<float>(options_.sigma_m), static_cast<float>(options_.alpha),
              static_cast<float>(options_.p_uniform), static_cast<float>(options_.min_weight),
              pfg_mode, static_cast<cl_int>(i == 0 ? 1 : 0), cover, static_cast<cl_int>(stride),
              likelihood_[static_cast<size_t>(i)].get(), sum_.get(), best_.get(), residual_.get(),
              claimed_.get(), static_cast<cl_int>(i));
  cl::enqueue(ctx_.queue(), likelihood_lanes_,
              static_cast<size_t>((grid.width + ctx_.lanes() - 1) / ctx_.lanes()),
              static_cast<size_t>(grid.height), 0, kLikelihoodLocalX, kLikelihoodLocalY);
}

void EStep::enqueueNormalize(int i, const cv::Rect& grid, int stride) {
  const cl_int pfg_mode = options_.association == Association::kPfg ? 1 : 0;
  cl::setArgs(normalize_, q_[static_cast<size_t>(i)].get(),
              likelihood_[static_cast<size_t>(i)].get(), sum_.get(), width_, rectArg(grid),
              pfg_mode, static_cast<cl_int>(i == 0 ? 1 : 0), static_cast<cl_int>(stride));
  cl::enqueue(ctx_.queue(), normalize_, static_cast<size_t>(grid.width),
              static_cast<size_t>(grid.height), 0, kPixelLocalX, kPixelLocalY);
}

void EStep::computeBackgroundWeights(cl_mem vertex_map, const std::vector<EStepVolume>& volumes,
                                     int stride) {
  if (volumes.empty() || volumes.size() > q_.size() || stride < 1) {
    throw InvalidArgument("EStep::computeBackgroundWeights: " + std::to_string(volumes.size()) +
                          " volumes (capacity " + std::to_string(q_.size()) + "), stride " +
                          std::to_string(stride));
  }
  setRectsAndKeys(volumes);
  const EStepCover cover = coverOf(std::vector<cv::Rect>(rects_.begin() + 1, rects_.end()));
  // The background at the sampled pixels; the objects over their whole rectangles, as compute()
  // samples them, so that the frame's second E-step can reuse their likelihoods (they add to the
  // sum at the other pixels too, where this call leaves it unspecified).
  // The image's pixels whose x and y are multiples of the stride: (0, 0, columns, rows).
  const cv::Rect bg(0, 0, (width_ + stride - 1) / stride, (height_ + stride - 1) / stride);
  enqueueLikelihood(vertex_map, volumes[0], 0, bg, cover, stride);
  for (size_t i = 1; i < volumes.size(); ++i) {
    if (!rects_[i].empty()) {
      enqueueLikelihood(vertex_map, volumes[i], static_cast<int>(i), rects_[i], cover, 1);
    }
  }
  enqueueNormalize(0, bg, stride);
  last_objects_.swap(keys_);  // their q is untouched
  last_vertex_ = vertex_map;
  reused_ = false;
  count_ = 1;
}

cv::Mat EStep::downloadQ(int i) const {
  cv::Mat m(height_, width_, CV_32F);
  ctx_.read(q_.at(static_cast<size_t>(i)), m.data, m.total() * sizeof(float));
  return m;
}

cv::Mat EStep::downloadQRows(int i, int row0, int rows) const {
  if (row0 < 0 || rows < 0 || row0 + rows > height_) {
    throw InvalidArgument("EStep::downloadQRows: rows " + std::to_string(row0) + " + " +
                          std::to_string(rows) + " outside the image's " + std::to_string(height_));
  }
  cv::Mat m(rows, width_, CV_32F);
  if (rows > 0) {
    ctx_.read(q_.at(static_cast<size_t>(i)), m.data, m.total() * sizeof(float),
              static_cast<size_t>(row0) * static_cast<size_t>(width_) * sizeof(float));
  }
  return m;
}

cv::Mat EStep::downloadResidual() const {
  cv::Mat m(height_, width_, CV_32F);
  ctx_.read(residual_, m.data, m.total() * sizeof(float));
  return m;
}

}  // namespace emf::em
