#include "synth/depth_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "synth/parallel.h"
#include "synth/rng.h"

namespace emf::synth {
namespace {

constexpr uint64_t kNoiseStream = 0x6e6f697365ull;  // "noise"
constexpr double kPi = 3.141592653589793;

/// acos on [0, 1] (Abramowitz & Stegun 4.4.45, |error| < 7e-5 rad): plenty for the noise
/// model's angle term and much cheaper than std::acos.
double fastAcos(double x) {
  return std::sqrt(1.0 - x) * (1.5707288 + x * (-0.2121144 + x * (0.0742610 - 0.0187293 * x)));
}

/// Nguyen et al.'s axial sigma (metres) at depth z (m) and incidence angle theta (rad).
inline double sigmaOf(const DepthNoiseOptions& o, double z, double theta) {
  const double dz = z - o.sigma_offset_m;
  double sigma = o.sigma_base_m + o.sigma_quadratic_per_m * dz * dz;
  if (theta > 0.0 && z > 0.0) {
    const double ratio = theta / std::max(kPi / 2 - theta, 1e-3);
    sigma += o.sigma_angle_m / std::sqrt(z) * ratio * ratio;
  }
  return sigma;
}

/// Below this angle the incidence term is < 3e-6 m (under 0.3 % of the smallest sigma): skipped.
constexpr double kMinAngleTermRad = 0.2;

bool isEdge(const cv::Mat& depth, int u, int v, double z, double rel) {
  static constexpr int kDu[4] = {1, -1, 0, 0};
  static constexpr int kDv[4] = {0, 0, 1, -1};
  for (int k = 0; k < 4; ++k) {
    const int uu = u + kDu[k], vv = v + kDv[k];
    if (uu < 0 || vv < 0 || uu >= depth.cols || vv >= depth.rows) continue;
    const float zn = depth.at<float>(vv, uu);
    if (!std::isfinite(zn) || std::fabs(zn - z) > rel * z) return true;
  }
  return false;
}

}  // namespace

const std::vector<std::string>& noisePartNames() {
  static const std::vector<std::string> names = {"axial",   "quantization", "edges", "shadow",
                                                 "grazing", "dropouts",     "range"};
  return names;
}

bool disableNoisePart(const std::string& name, DepthNoiseOptions* options) {
  if (name == "axial") {
    options->axial_noise = false;
  } else if (name == "quantization") {
    options->quantize = false;
  } else if (name == "edges") {
    options->edge_dropout_prob = 0.0;
    options->edge_jitter_prob = 0.0;
  } else if (name == "shadow") {
    options->projector_shadow = false;
  } else if (name == "grazing") {
    options->max_incidence_deg = 90.0;
  } else if (name == "dropouts") {
    options->dropout_prob = 0.0;
  } else if (name == "range") {
    options->min_range_m = 0.0;
    options->max_range_m = std::numeric_limits<double>::infinity();
  } else {
    return false;
  }
  return true;
}

double DepthNoiseModel::axialSigma(double z, double theta) const {
  return sigmaOf(options_, z, theta);
}

double DepthNoiseModel::quantizationStep(double z) const {
  if (!options_.quantize) return 0.0;
  return z * z * options_.disparity_step_px / (options_.focal_px * options_.baseline_m);
}

double DepthNoiseModel::expectedStd(double z) const {
  const double sigma = options_.axial_noise ? axialSigma(z) : 0.0;
  const double step = quantizationStep(z);
  return std::sqrt(sigma * sigma + step * step / 12.0);
}

void DepthNoiseModel::apply(const cv::Mat& depth, const cv::Mat& cos_incidence, double fx_px,
                            uint64_t seed, int64_t frame_index, cv::Mat* out, int threads) const {
  CV_Assert(depth.type() == CV_32F);
  CV_Assert(cos_incidence.empty() ||
            (cos_incidence.type() == CV_32F && cos_incidence.size() == depth.size()));
  const auto& o = options_;
  if (!o.enabled) {
    depth.copyTo(*out);
    return;
  }
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  cv::Mat result(depth.size(), CV_32F);
  const double fb_quant = o.focal_px * o.baseline_m;
  const double inv_step = 1.0 / o.disparity_step_px;
  // Depth of k quantisation steps of disparity: fb / (k * step), tabulated for the range of
  // interest (k beyond it falls back to the division).
  const double cos_small_angle = std::cos(kMinAngleTermRad);
  std::vector<double> depth_of_steps;
  if (o.quantize) {
    const size_t k_max = static_cast<size_t>(
        std::min(1e6, fb_quant * inv_step / std::max(0.5 * o.min_range_m, 0.05)) + 2);
    depth_of_steps.resize(k_max);
    depth_of_steps[0] = 0.0;
    for (size_t k = 1; k < k_max; ++k) {
      depth_of_steps[k] = fb_quant / (static_cast<double>(k) * o.disparity_step_px);
    }
  }
  const double fb_shadow = fx_px * o.baseline_m;
  const double cos_min = std::cos(o.max_incidence_deg * kPi / 180.0);
  const int W = depth.cols;

  parallelFor(depth.rows, resolveThreads(threads), [&](int vb, int ve) {
    std::vector<uint8_t> shadow(static_cast<size_t>(W));
    for (int v = vb; v < ve; ++v) {
      const float* in = depth.ptr<float>(v);
      float* dst = result.ptr<float>(v);
      // Projector shadow: scanning right to left, a point whose projector column lies right of
      // one already seen further right is hidden from the projector.
      std::fill(shadow.begin(), shadow.end(), uint8_t{0});
      if (o.projector_shadow) {
        double running_min = std::numeric_limits<double>::infinity();
        for (int u = W - 1; u >= 0; --u) {
          if (!std::isfinite(in[u]) || in[u] <= 0.f) continue;
          const double up = u - fb_shadow / in[u];
          if (up > running_min) shadow[static_cast<size_t>(u)] = 1;
          running_min = std::min(running_min, up);
        }
      }
      Rng rng(streamSeed(seed, static_cast<uint64_t>(frame_index), static_cast<uint64_t>(v),
                         kNoiseStream));
      for (int u = 0; u < W; ++u) {
        // The same draws for every pixel, so one pixel's fate never shifts another's noise.
        // One 64-bit draw gives the edge decision (24 bits), the neighbour (3 bits) and the
        // dropout decision (24 bits).
        const uint64_t bits = rng.next();
        const double r_edge = static_cast<double>(bits & 0xffffff) * 0x1.0p-24;
        const int neighbour = static_cast<int>((bits >> 24) & 7);
        const double r_drop = static_cast<double>(bits >> 40) * 0x1.0p-24;
        const double n = rng.normal();
        double z = in[u];
        dst[u] = kNaN;
        if (!std::isfinite(z) || z <= 0.0 || shadow[static_cast<size_t>(u)]) continue;
        if (isEdge(depth, u, v, z, o.edge_threshold_rel)) {
          if (r_edge < o.edge_dropout_prob) continue;
          if (r_edge < o.edge_dropout_prob + o.edge_jitter_prob) {
            static constexpr int kDu[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
            static constexpr int kDv[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
            const int uu = std::clamp(u + kDu[neighbour], 0, W - 1);
            const int vv = std::clamp(v + kDv[neighbour], 0, depth.rows - 1);
            const float zn = depth.at<float>(vv, uu);
            if (std::isfinite(zn)) z = zn;
          }
        }
        if (r_drop < o.dropout_prob) continue;
        double theta = 0.0;
        if (!cos_incidence.empty()) {
          const double c = cos_incidence.at<float>(v, u);
          if (c < cos_min) continue;
          if (c < cos_small_angle) theta = fastAcos(c);
        }
        if (o.axial_noise) z += sigmaOf(o, z, theta) * n;
        if (o.quantize && z > 0.0) {
          // Disparity in steps (positive): rounding by truncation of x + 0.5 avoids a libm call.
          const auto k = static_cast<int64_t>(fb_quant / z * inv_step + 0.5);
          if (k <= 0) continue;
          z = static_cast<size_t>(k) < depth_of_steps.size()
                  ? depth_of_steps[static_cast<size_t>(k)]
                  : fb_quant / (static_cast<double>(k) * o.disparity_step_px);
        }
        if (z < o.min_range_m || z > o.max_range_m) continue;
        dst[u] = static_cast<float>(z);
      }
    }
  });
  *out = result;
}

}  // namespace emf::synth
