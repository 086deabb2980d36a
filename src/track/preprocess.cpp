#include "track/preprocess.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"

namespace emf::track {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

bool depthInRange(float d, float min_depth, float max_depth) {
  return !std::isnan(d) && d > 0.0f && d >= min_depth && d <= max_depth;
}

void checkIntrinsics(const core::Intrinsics& k) {
  if (!k.valid()) {
    std::ostringstream s;
    s << "preprocessing: invalid intrinsics (fx " << k.fx << ", fy " << k.fy << ", " << k.width
      << "x" << k.height << "): set source.fx/fy/cx/cy or fix the dataset's calibration";
    throw InvalidArgument(s.str());
  }
}

void checkDepth(const cv::Mat& depth_m, const core::Intrinsics& k) {
  if (depth_m.type() != CV_32F || depth_m.cols != k.width || depth_m.rows != k.height) {
    std::ostringstream s;
    s << "preprocessing: depth image must be CV_32F metres of " << k.width << "x" << k.height
      << " (the intrinsics' size), got type " << depth_m.type() << " of " << depth_m.cols << "x"
      << depth_m.rows << ": convert raw depth with the source's depth_scale first";
    throw InvalidArgument(s.str());
  }
}

}  // namespace

void validatePreprocessOptions(const PreprocessOptions& o) {
  if (!(o.min_depth_m < o.max_depth_m)) {
    std::ostringstream s;
    s << "preprocess.min_depth_m (" << o.min_depth_m << ") must be below preprocess.max_depth_m ("
      << o.max_depth_m << ")";
    throw ConfigError(s.str());
  }
}

float maxDepthInRange(const cv::Mat& depth_m, const PreprocessOptions& o) {
  CV_Assert(depth_m.type() == CV_32F);
  // depthInRange as two comparisons (both false for NaN), so that the loop vectorises:
  // d > 0 && d >= min  <=>  d >= max(min, the smallest positive float).
  const float lo =
      std::max(static_cast<float>(o.min_depth_m), std::numeric_limits<float>::denorm_min());
  const float hi = static_cast<float>(o.max_depth_m);
  float m = 0.0f;
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* row = depth_m.ptr<float>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const float d = row[u];
      m = (d >= lo && d <= hi && d > m) ? d : m;
    }
  }
  return m;
}

float rangeGuardMaxDepth(const PreprocessOptions& o, float frame_max_m) {
  if (!(o.range_guard_per_m2 > 0.0)) return std::numeric_limits<float>::infinity();
  const double limit = std::min(o.max_depth_m, static_cast<double>(frame_max_m));
  return static_cast<float>(limit - o.range_guard_per_m2 * limit * limit);
}

cv::Mat dropHoleMarginReference(const cv::Mat& depth_m, int radius) {
  CV_Assert(depth_m.type() == CV_32F);
  cv::Mat out = depth_m.clone();
  if (radius <= 0) return out;
  for (int v = 0; v < depth_m.rows; ++v) {
    for (int u = 0; u < depth_m.cols; ++u) {
      if (depth_m.at<float>(v, u) > 0.0f) continue;  // a valid pixel is no hole
      // A hole (NaN or <= 0): every pixel within the radius loses its depth.
      for (int vv = std::max(0, v - radius); vv <= std::min(depth_m.rows - 1, v + radius); ++vv) {
        for (int uu = std::max(0, u - radius); uu <= std::min(depth_m.cols - 1, u + radius); ++uu) {
          out.at<float>(vv, uu) = kNaN;
        }
      }
    }
  }
  return out;
}

PreprocessedFrame preprocessReference(const cv::Mat& input_m, const core::Intrinsics& k,
                                      const PreprocessOptions& o) {
  checkIntrinsics(k);
  checkDepth(input_m, k);
  validatePreprocessOptions(o);
  const cv::Mat depth_m = dropHoleMarginReference(input_m, o.hole_margin_px);
  const float guard_max = rangeGuardMaxDepth(o, maxDepthInRange(input_m, o));
  const int w = k.width, h = k.height, r = o.bilateral_radius_px;
  const float min_d = static_cast<float>(o.min_depth_m);
  const float max_d = static_cast<float>(o.max_depth_m);
  const float inv_s = static_cast<float>(1.0 / (2.0 * o.sigma_space_px * o.sigma_space_px));
  const float sigma_d = static_cast<float>(o.sigma_depth_m);
  const float sigma_d_per_m2 = static_cast<float>(o.sigma_depth_per_m2);
  const float fx = static_cast<float>(k.fx), fy = static_cast<float>(k.fy);
  const float cx = static_cast<float>(k.cx), cy = static_cast<float>(k.cy);
  PreprocessedFrame out;
  out.depth_m.create(h, w, CV_32F);
  out.vertex.create(h, w, CV_32FC4);
  out.input_m = depth_m.clone();
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float d0 = depth_m.at<float>(v, u);
      if (!depthInRange(d0, min_d, max_d)) {
        out.depth_m.at<float>(v, u) = kNaN;
        out.vertex.at<cv::Vec4f>(v, u) = cv::Vec4f(kNaN, kNaN, kNaN, 0.0f);
        continue;
      }
      const float sigma_r = sigma_d + sigma_d_per_m2 * (d0 * d0);  // as the kernel
      const float inv_d = 0.5f / (sigma_r * sigma_r);
      float sum_w = 0.0f, sum_wd = 0.0f;
      bool hole = false;
      for (int dv = -r; dv <= r; ++dv) {
        const int vv = v + dv;
        if (vv < 0 || vv >= h) continue;
        for (int du = -r; du <= r; ++du) {
          const int uu = u + du;
          if (uu < 0 || uu >= w) continue;
          const float d = depth_m.at<float>(vv, uu);
          if (!depthInRange(d, min_d, max_d)) {
            hole = true;
            continue;
          }
          const float dd = d - d0;
          const float wt =
              std::exp(-static_cast<float>(du * du + dv * dv) * inv_s - dd * dd * inv_d);
          sum_w += wt;
          sum_wd += wt * d;
        }
      }
      const float z = sum_wd / sum_w;
      if (hole && !(z <= guard_max)) {  // the range guard
        out.depth_m.at<float>(v, u) = kNaN;
        out.vertex.at<cv::Vec4f>(v, u) = cv::Vec4f(kNaN, kNaN, kNaN, 0.0f);
        out.input_m.at<float>(v, u) = kNaN;
        continue;
      }
      out.depth_m.at<float>(v, u) = z;
      out.vertex.at<cv::Vec4f>(v, u) = cv::Vec4f((static_cast<float>(u) - cx) / fx * z,
                                                 (static_cast<float>(v) - cy) / fy * z, z, 1.0f);
    }
  }
  return out;
}

Preprocessor::Preprocessor(cl::Context& ctx, const PreprocessOptions& options,
                           const core::Intrinsics& intrinsics, int sample_stride)
    : ctx_(ctx), options_(options), intrinsics_(intrinsics), stride_(sample_stride) {
  checkIntrinsics(intrinsics_);
  validatePreprocessOptions(options_);
  if (stride_ < 1) {
    throw InvalidArgument("Preprocessor: sample stride " + std::to_string(stride_) +
                          " must be >= 1");
  }
  const size_t n = static_cast<size_t>(intrinsics_.width) * intrinsics_.height;
  const std::string radius = "-DPRE_RADIUS=" + std::to_string(options_.bilateral_radius_px);
  kernel_ = ctx_.kernel("preprocess", "preprocess_depth",
                        radius + " -DPRE_STRIDE=" + std::to_string(stride_));
  if (stride_ > 1 && options_.range_guard_per_m2 > 0) {
    guard_rows_kernel_ = ctx_.kernel("preprocess", "preprocess_guard_rows", radius);
    guard_kernel_ = ctx_.kernel("preprocess", "preprocess_guard", radius);
    row_max_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(float));
  }
  if (options_.hole_margin_px > 0) {
    margin_kernel_ = ctx_.kernel("preprocess", "drop_hole_margin",
                                 "-DPRE_RADIUS=" + std::to_string(options_.bilateral_radius_px));
    margin_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(float));
  }
  if (options_.range_guard_per_m2 > 0) guarded_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(float));
  input_ = ctx_.buffer(CL_MEM_READ_ONLY, n * sizeof(float));
  filtered_ = ctx_.buffer(CL_MEM_READ_WRITE, n * sizeof(float));
  vertex_ = ctx_.buffer(CL_MEM_READ_WRITE, n * 4 * sizeof(float));
  if (stride_ > 1) {
    // The pixels the kernel skips stay invalid from here on.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::vector<float> depth(n, nan);
    ctx_.write(filtered_, depth.data(), n * sizeof(float));
    std::vector<float> vertex(n * 4, nan);
    for (size_t i = 0; i < n; ++i) vertex[4 * i + 3] = 0.0f;
    ctx_.write(vertex_, vertex.data(), n * 4 * sizeof(float));
  }
}

void Preprocessor::process(const cv::Mat& depth_m) {
  checkDepth(depth_m, intrinsics_);
  process(depth_m, options_.range_guard_per_m2 > 0 ? maxDepthInRange(depth_m, options_)
                                                   : std::numeric_limits<float>::infinity());
}

void Preprocessor::process(const cv::Mat& depth_m, float frame_max_m) {
  checkDepth(depth_m, intrinsics_);
  const size_t row_bytes = static_cast<size_t>(intrinsics_.width) * sizeof(float);
  if (depth_m.isContinuous()) {
    ctx_.write(input_, depth_m.ptr<float>(0), row_bytes * intrinsics_.height);
  } else {
    const cv::Mat copy = depth_m.clone();
    ctx_.write(input_, copy.ptr<float>(0), row_bytes * intrinsics_.height);
  }
  process(input_.get(), frame_max_m);
}

void Preprocessor::process(cl_mem input_m, float frame_max_m) {
  const auto& o = options_;
  cl_mem depth_m = input_m;
  if (o.hole_margin_px > 0) {
    cl::setArgs(margin_kernel_, input_m, margin_.get(), intrinsics_.width, intrinsics_.height,
                o.hole_margin_px);
    cl::enqueue(ctx_.queue(), margin_kernel_, static_cast<size_t>(intrinsics_.width),
                static_cast<size_t>(intrinsics_.height), 0, 16, 8);
    depth_m = margin_.get();
  }
  const float inv_s = static_cast<float>(1.0 / (2.0 * o.sigma_space_px * o.sigma_space_px));
  const float guard_max = rangeGuardMaxDepth(o, frame_max_m);
  const bool guard = o.range_guard_per_m2 > 0;
  cl::setArgs(kernel_, depth_m, filtered_.get(), vertex_.get(), intrinsics_.width,
              intrinsics_.height, inv_s, static_cast<float>(o.sigma_depth_m),
              static_cast<float>(o.sigma_depth_per_m2), static_cast<float>(o.min_depth_m),
              static_cast<float>(o.max_depth_m), static_cast<float>(intrinsics_.fx),
              static_cast<float>(intrinsics_.fy), static_cast<float>(intrinsics_.cx),
              static_cast<float>(intrinsics_.cy), guard_max,
              guard ? guarded_.get() : filtered_.get(), guard && stride_ == 1 ? 1 : 0);
  // ctx_.lanes() sampled pixels per work item along x.
  const int lanes = ctx_.lanes();
  const int sampled_w = (intrinsics_.width + stride_ - 1) / stride_;
  const int sampled_h = (intrinsics_.height + stride_ - 1) / stride_;
  cl::enqueue(ctx_.queue(), kernel_, static_cast<size_t>((sampled_w + lanes - 1) / lanes),
              static_cast<size_t>(sampled_h), 0, 8, 8);
  if (guard_kernel_) {
    const size_t items_x = static_cast<size_t>((intrinsics_.width + lanes - 1) / lanes);
    cl::setArgs(guard_rows_kernel_, depth_m, row_max_.get(), intrinsics_.width, intrinsics_.height,
                static_cast<float>(o.min_depth_m), static_cast<float>(o.max_depth_m));
    cl::enqueue(ctx_.queue(), guard_rows_kernel_, items_x, static_cast<size_t>(intrinsics_.height),
                0, 8, 8);
    cl::setArgs(guard_kernel_, depth_m, row_max_.get(), guarded_.get(), intrinsics_.width,
                intrinsics_.height, inv_s, static_cast<float>(o.sigma_depth_m),
                static_cast<float>(o.sigma_depth_per_m2), static_cast<float>(o.min_depth_m),
                static_cast<float>(o.max_depth_m), guard_max);
    cl::enqueue(ctx_.queue(), guard_kernel_, items_x, static_cast<size_t>(intrinsics_.height), 0, 8,
                8);
  }
}

PreprocessedFrame Preprocessor::download() const {
  PreprocessedFrame out;
  out.depth_m.create(intrinsics_.height, intrinsics_.width, CV_32F);
  out.vertex.create(intrinsics_.height, intrinsics_.width, CV_32FC4);
  const size_t n = static_cast<size_t>(intrinsics_.width) * intrinsics_.height;
  ctx_.read(filtered_, out.depth_m.ptr<float>(0), n * sizeof(float));
  ctx_.read(vertex_, out.vertex.ptr<float>(0), n * 4 * sizeof(float));
  out.input_m.create(intrinsics_.height, intrinsics_.width, CV_32F);
  ctx_.read(inputDepth(), out.input_m.ptr<float>(0), n * sizeof(float));
  return out;
}

}  // namespace emf::track
