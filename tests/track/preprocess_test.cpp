// The preprocessing kernel (range check, bilateral filter, back-projection) against its CPU
// reference on real Kinect depth and on constructed cases, and the reference's own semantics.
#include "track/preprocess.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "common/error.h"
#include "test_support.h"
#include "track_test_support.h"

namespace emf::track {
namespace {

// Float exp() of the device and the host may differ by a few ulps; the filtered depth is a
// weighted mean of depths within a 7x7 window, so both agree to well below a micrometre.
constexpr float kPreprocessToleranceM = 2e-6f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Runs the device path and compares every pixel with the reference. Returns the number of
// valid pixels.
int compareWithReference(cl::Context& ctx, const cv::Mat& depth, const core::Intrinsics& k,
                         const PreprocessOptions& o) {
  Preprocessor pre(ctx, o, k);
  pre.process(depth);
  const PreprocessedFrame dev = pre.download();
  const PreprocessedFrame ref = preprocessReference(depth, k, o);
  int valid = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const float r = ref.depth_m.at<float>(v, u), d = dev.depth_m.at<float>(v, u);
      const cv::Vec4f rv = ref.vertex.at<cv::Vec4f>(v, u), dv = dev.vertex.at<cv::Vec4f>(v, u);
      if (std::isnan(r)) {
        EXPECT_TRUE(std::isnan(d)) << "pixel (" << u << "," << v << ") must stay invalid";
        EXPECT_EQ(dv[3], 0.0f);
        EXPECT_TRUE(std::isnan(dv[0]) && std::isnan(dv[1]) && std::isnan(dv[2]));
        if (!std::isnan(d)) return valid;
        continue;
      }
      ++valid;
      EXPECT_NEAR(d, r, kPreprocessToleranceM) << "pixel (" << u << "," << v << ")";
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(dv[c], rv[c], kPreprocessToleranceM);
      EXPECT_EQ(dv[3], 1.0f);
      if (std::abs(d - r) > kPreprocessToleranceM) return valid;  // one report is enough
    }
  }
  // What the map integrates: the input with the same pixels dropped, bit for bit.
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const float r = ref.input_m.at<float>(v, u), d = dev.input_m.at<float>(v, u);
      if (std::isnan(r) ? !std::isnan(d) : !(d == r)) {
        ADD_FAILURE() << "integrated depth at (" << u << "," << v << "): " << d << " vs " << r;
        return valid;
      }
    }
  }
  return valid;
}

class Preprocess : public test::WithClQueue {};

TEST_F(Preprocess, RealKinectDepthMatchesReference) {
  const cv::Mat depth =
      test::readDepthPng(test::dataPath("tum-fr1-xyz-pairs/case_1/dep_prev.png"), 5000.0);
  PreprocessOptions o;         // defaults: range sigma 0.04 m + 0.01 z^2, 4.5 px, 7x7
  o.range_guard_per_m2 = 0.0;  // counted below, on its own
  o.hole_margin_px = 1;
  const int valid = compareWithReference(ctx(), depth, test::kinectCamera(), o);
  // The frame has holes (zeros) that must stay invalid, and so must the pixels next to them;
  // most of it is valid.
  const int raw_valid = cv::countNonZero(depth == depth);
  const cv::Mat kept = dropHoleMarginReference(depth, o.hole_margin_px);
  EXPECT_EQ(valid, cv::countNonZero(kept == kept));
  EXPECT_LT(valid, raw_valid);
  EXPECT_GT(valid, 640 * 480 / 2);
  o.hole_margin_px = 0;
  EXPECT_EQ(compareWithReference(ctx(), depth, test::kinectCamera(), o), raw_valid);
  // The range guard on real depth: the same pixels dropped as by the reference, a few.
  o.range_guard_per_m2 = 0.05;
  const int guarded = compareWithReference(ctx(), depth, test::kinectCamera(), o);
  EXPECT_LT(guarded, raw_valid);
  EXPECT_GT(guarded, raw_valid / 2);
}

TEST_F(Preprocess, RealDepthWithRangeLimitsMatchesReference) {
  const cv::Mat depth =
      test::readDepthPng(test::dataPath("tum-fr1-xyz-pairs/case_1/dep_prev.png"), 5000.0);
  PreprocessOptions o;
  o.min_depth_m = 1.0;
  o.max_depth_m = 2.0;
  o.hole_margin_px = 1;
  o.range_guard_per_m2 = 0.0;  // it would drop the pixels near 2 m next to a hole
  const int valid = compareWithReference(ctx(), depth, test::kinectCamera(), o);
  // Depth out of range is no hole: only the pixels next to missing depth lose theirs.
  const cv::Mat kept = dropHoleMarginReference(depth, o.hole_margin_px);
  int in_range = 0;
  for (auto it = kept.begin<float>(); it != kept.end<float>(); ++it) {
    in_range += (*it >= 1.0f && *it <= 2.0f) ? 1 : 0;
  }
  EXPECT_EQ(valid, in_range);
}

// Constructed cases: a step edge, holes, image borders, NaN and 0 as invalid, out-of-range.
cv::Mat constructedDepth(int w, int h) {
  cv::Mat d(h, w, CV_32F);
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 0.003f);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      float z = u < w / 2 ? 1.0f : 2.5f;  // 1.5 m step edge
      z += 0.002f * static_cast<float>(v) + noise(rng);
      d.at<float>(v, u) = z;
    }
  }
  d(cv::Rect(10, 10, 6, 5)).setTo(cv::Scalar(kNaN));  // hole
  d(cv::Rect(40, 30, 3, 3)).setTo(cv::Scalar(0.0));   // zeros = invalid
  d.at<float>(0, 0) = kNaN;                           // corner
  d.at<float>(h - 1, w - 1) = 7.0f;                   // beyond max
  d.at<float>(h / 2, 5) = 0.05f;                      // below min
  // Exactly at the range limits (valid), the floats just outside them and a negative depth
  // (invalid), each among valid neighbours a few mm away so that wrongly including one moves
  // their filtered depth far beyond the tolerance. The kernel's neighbour test is
  // d > (the float below min) && d <= max.
  for (int v = 36; v <= 40; ++v) {
    for (int u = 46; u < w; ++u) {
      d.at<float>(v, u) = u < 58 ? 0.1005f + 0.0002f * static_cast<float>(u - 46)
                                 : 4.999f - 0.0002f * static_cast<float>(u - 58);
    }
  }
  d.at<float>(38, 50) = 0.1f;
  d.at<float>(38, 52) = std::nextafter(0.1f, 0.0f);
  d.at<float>(38, 54) = -1.0f;
  d.at<float>(38, 61) = 5.0f;
  d.at<float>(38, 63) = std::nextafter(5.0f, 6.0f);
  return d;
}

TEST_F(Preprocess, ConstructedEdgesAndHolesMatchReference) {
  const int w = 67, h = 45;  // not multiples of the work-group size
  core::Intrinsics k;
  k.fx = 60;
  k.fy = 58;
  k.cx = 33.0;
  k.cy = 21.5;
  k.width = w;
  k.height = h;
  const cv::Mat depth = constructedDepth(w, h);
  PreprocessOptions o;
  // Without the hole margin (the default) first: the negative depth among the range-limit cases
  // is a hole, and a margin would drop the neighbours whose filtered depth tests the range checks.
  ASSERT_EQ(o.hole_margin_px, 0);
  compareWithReference(ctx(), depth, k, o);
  o.min_depth_m = 0.0;  // no minimum: only d > 0 is valid
  compareWithReference(ctx(), depth, k, o);
  o.min_depth_m = PreprocessOptions().min_depth_m;
  o.bilateral_radius_px = 0;  // filter off: back-projection only
  compareWithReference(ctx(), depth, k, o);
  o.bilateral_radius_px = 5;
  o.sigma_space_px = 2.0;
  o.sigma_depth_m = 0.01;
  compareWithReference(ctx(), depth, k, o);
  o.sigma_depth_per_m2 = 0.0;  // a fixed range sigma (the paper)
  compareWithReference(ctx(), depth, k, o);
  o.sigma_depth_per_m2 = 0.5;
  compareWithReference(ctx(), depth, k, o);
  for (const int margin : {1, 2, 5}) {
    o.hole_margin_px = margin;
    compareWithReference(ctx(), depth, k, o);
  }
  // The range guard: 0.005 drops the far end of the 4.999-5 m strip (limit 5 - 0.125 m), 0.1
  // everything beyond 2.5 m: the far half of the step edge too (default filter settings).
  o = PreprocessOptions();
  for (const double guard : {0.005, 0.1}) {
    o.range_guard_per_m2 = guard;
    const int valid = compareWithReference(ctx(), depth, k, o);
    o.range_guard_per_m2 = 0.0;
    EXPECT_LT(valid, compareWithReference(ctx(), depth, k, o)) << guard;
  }
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

// A sample stride s: the pixels (u, v) with u, v multiples of s get the stride-1 filtered depth
// and vertex to the bit, the others stay invalid, and what the map integrates (the range guard
// at every pixel) is the same to the bit. Returns the number of pixels the guard dropped that
// the strided filter skips.
int compareStrided(cl::Context& ctx, const cv::Mat& depth, const core::Intrinsics& k,
                   const PreprocessOptions& o, int stride) {
  Preprocessor full(ctx, o, k);
  full.process(depth);
  const PreprocessedFrame ref = full.download();
  Preprocessor strided(ctx, o, k, stride);
  EXPECT_EQ(strided.sampleStride(), stride);
  strided.process(depth);
  const PreprocessedFrame dev = strided.download();
  int skipped_drops = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      const float r = ref.depth_m.at<float>(v, u), d = dev.depth_m.at<float>(v, u);
      const cv::Vec4f rv = ref.vertex.at<cv::Vec4f>(v, u), dv = dev.vertex.at<cv::Vec4f>(v, u);
      const bool sampled = u % stride == 0 && v % stride == 0;
      const bool same = sampled
                            ? sameBits(d, r) && sameBits(dv[0], rv[0]) && sameBits(dv[1], rv[1]) &&
                                  sameBits(dv[2], rv[2]) && sameBits(dv[3], rv[3])
                            : std::isnan(d) && std::isnan(dv[0]) && dv[3] == 0.0f;
      const float ri = ref.input_m.at<float>(v, u), di = dev.input_m.at<float>(v, u);
      if (!same || !sameBits(di, ri)) {
        ADD_FAILURE() << "stride " << stride << ", pixel (" << u << "," << v << "): depth " << d
                      << " vs " << r << ", integrated " << di << " vs " << ri;
        return skipped_drops;
      }
      const float raw = depth.at<float>(v, u);
      if (!sampled && std::isnan(ri) && raw > o.min_depth_m && raw <= o.max_depth_m) {
        ++skipped_drops;
      }
    }
  }
  return skipped_drops;
}

TEST_F(Preprocess, StridedFilterKeepsTheSampledPixelsToTheBit) {
  const cv::Mat depth =
      test::readDepthPng(test::dataPath("tum-fr1-xyz-pairs/case_1/dep_prev.png"), 5000.0);
  PreprocessOptions o;
  o.range_guard_per_m2 = 0.05;  // drops pixels, as in RealKinectDepthMatchesReference
  for (const int stride : {2, 3, 4}) {
    // The guard decides pixels the filter skips: some are dropped.
    EXPECT_GT(compareStrided(ctx(), depth, test::kinectCamera(), o, stride), 0) << stride;
  }
  o.range_guard_per_m2 = 0.0;  // no guard kernel: the integrated depth is the margin's input
  o.hole_margin_px = 1;
  compareStrided(ctx(), depth, test::kinectCamera(), o, 2);
  // Edges of an image whose size is no multiple of the stride or the work-group size.
  core::Intrinsics k;
  k.fx = 60;
  k.fy = 58;
  k.cx = 33.0;
  k.cy = 21.5;
  k.width = 67;
  k.height = 45;
  const cv::Mat constructed = constructedDepth(k.width, k.height);
  o = PreprocessOptions();
  o.range_guard_per_m2 = 0.1;  // everything beyond 2.5 m next to a hole
  for (const int stride : {2, 3}) {
    EXPECT_GT(compareStrided(ctx(), constructed, k, o, stride), 0) << stride;
  }
  EXPECT_THROW(Preprocessor(ctx(), o, k, 0), InvalidArgument);
}

// The hole margin of the reference on a constructed image: the pixels within the margin of a
// NaN or non-positive depth lose theirs; the image border, depth out of range and the pixels
// beyond the margin keep theirs. Margin 0 changes nothing.
TEST(PreprocessReference, HoleMarginDropsThePixelsNextToMissingDepthOnly) {
  cv::Mat d(12, 20, CV_32F, cv::Scalar(1.5f));
  d.at<float>(5, 6) = kNaN;
  d.at<float>(2, 15) = 0.0f;
  d.at<float>(9, 15) = -1.0f;
  d.at<float>(9, 2) = 9.0f;  // beyond any max depth: not a hole
  for (const int margin : {0, 1, 2}) {
    const cv::Mat out = dropHoleMarginReference(d, margin);
    for (int v = 0; v < d.rows; ++v) {
      for (int u = 0; u < d.cols; ++u) {
        const auto near = [&](int hu, int hv) {
          return std::abs(u - hu) <= margin && std::abs(v - hv) <= margin;
        };
        const bool dropped = margin > 0 && (near(6, 5) || near(15, 2) || near(15, 9));
        const float expected = dropped ? kNaN : d.at<float>(v, u);
        if (std::isnan(expected)) {
          EXPECT_TRUE(std::isnan(out.at<float>(v, u)))
              << "margin " << margin << ", pixel (" << u << "," << v << ")";
        } else {
          EXPECT_EQ(out.at<float>(v, u), expected)
              << "margin " << margin << ", pixel (" << u << "," << v << ")";
        }
      }
    }
  }
  // The frame's own border is no hole.
  EXPECT_EQ(dropHoleMarginReference(cv::Mat(4, 4, CV_32F, cv::Scalar(2.0f)), 2).at<float>(0, 0),
            2.0f);
}

// The range guard on a constructed frame: a wall at 2 m (columns 0-19) and one at 4.46 m
// (columns 20-59), one pixel at 4.5 m (the frame's largest depth: a sensor's range). Columns
// 20-39 of the far wall have a hole every 4 px in both directions (as a surface cut by a range
// limit), columns 40-59 none. With 0.005 the limit on the filtered depth is
// 4.5 - 0.005 x 4.5^2 = 4.39875 m: a far pixel goes, from the tracked and the integrated depth,
// when its 7x7 window holds a hole; the near wall and the far pixels without a hole near stay.
// Below max_depth_m the frame's largest in-range depth sets the limit; 0 is off.
TEST(PreprocessReference, RangeGuardDropsTheDepthNearTheFrameLimitNextToHoles) {
  constexpr float kLimitToleranceM = 1e-6f;
  const int w = 60, h = 30, r = PreprocessOptions().bilateral_radius_px;
  core::Intrinsics k;
  k.fx = k.fy = 40;
  k.cx = 29.5;
  k.cy = 14.5;
  k.width = w;
  k.height = h;
  cv::Mat depth(h, w, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(20, 0, 40, h)).setTo(4.46f);
  for (int v = 1; v < h; v += 4) {
    for (int u = 21; u < 40; u += 4) depth.at<float>(v, u) = kNaN;
  }
  depth.at<float>(15, 50) = 4.5f;
  const auto holeInWindow = [&](int u, int v) {
    for (int vv = std::max(0, v - r); vv <= std::min(h - 1, v + r); ++vv) {
      for (int uu = std::max(0, u - r); uu <= std::min(w - 1, u + r); ++uu) {
        if (std::isnan(depth.at<float>(vv, uu))) return true;
      }
    }
    return false;
  };
  PreprocessOptions o;
  o.range_guard_per_m2 = 0.0;
  EXPECT_EQ(maxDepthInRange(depth, o), 4.5f);
  EXPECT_TRUE(std::isinf(rangeGuardMaxDepth(o, 4.5f)));
  const int valid_input = cv::countNonZero(depth == depth);
  PreprocessedFrame out = preprocessReference(depth, k, o);
  EXPECT_EQ(cv::countNonZero(out.depth_m == out.depth_m), valid_input);

  o.range_guard_per_m2 = 0.005;
  EXPECT_NEAR(rangeGuardMaxDepth(o, 4.5f), 4.39875f, kLimitToleranceM);
  out = preprocessReference(depth, k, o);
  int dropped = 0;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float d = depth.at<float>(v, u);
      if (std::isnan(d)) continue;
      const bool drop = u >= 20 && holeInWindow(u, v);
      dropped += drop ? 1 : 0;
      EXPECT_EQ(std::isnan(out.depth_m.at<float>(v, u)), drop) << u << "," << v;
      EXPECT_EQ(out.vertex.at<cv::Vec4f>(v, u)[3], drop ? 0.0f : 1.0f);
      if (drop) {
        EXPECT_TRUE(std::isnan(out.input_m.at<float>(v, u)));
      } else {
        EXPECT_EQ(out.input_m.at<float>(v, u), d);
      }
    }
  }
  // Columns 20-39 (600 pixels, 40 of them holes) and column 40, 3 px from the holes of column 37.
  EXPECT_EQ(dropped, 560 + 30);
  // max_depth_m 4.48: the 4.5 m pixel is out of range, the 4.46 m wall sets the limit
  // (4.46 - 0.005 x 4.46^2 = 4.360542 m), and the out-of-range pixel is a hole for its window.
  o.max_depth_m = 4.48;
  EXPECT_EQ(maxDepthInRange(depth, o), 4.46f);
  EXPECT_NEAR(rangeGuardMaxDepth(o, 4.46f), 4.360542f, kLimitToleranceM);
  out = preprocessReference(depth, k, o);
  EXPECT_EQ(cv::countNonZero(out.depth_m == out.depth_m), valid_input - 1 - dropped - 48);
  // max_depth_m below the frame's largest depth caps the limit: 4 - 0.005 x 16 = 3.92 m.
  o.max_depth_m = 4.0;
  EXPECT_NEAR(rangeGuardMaxDepth(o, 4.5f), 3.92f, kLimitToleranceM);
}

TEST(PreprocessReference, SemanticsOnConstructedDepth) {
  const int w = 67, h = 45;
  core::Intrinsics k;
  k.fx = 60;
  k.fy = 58;
  k.cx = 33.0;
  k.cy = 21.5;
  k.width = w;
  k.height = h;
  const cv::Mat depth = constructedDepth(w, h);
  PreprocessOptions o;
  o.range_guard_per_m2 = 0.0;  // the range limits below are tested without it
  const PreprocessedFrame out = preprocessReference(depth, k, o);
  // Invalid inputs stay invalid.
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(12, 12)));
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(31, 41)));
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(0, 0)));
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(h - 1, w - 1)));
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(h / 2, 5)));
  EXPECT_EQ(out.vertex.at<cv::Vec4f>(12, 12)[3], 0.0f);
  EXPECT_FALSE(std::isnan(out.depth_m.at<float>(38, 50))) << "exactly min_depth is valid";
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(38, 52))) << "just below min_depth";
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(38, 54))) << "negative depth";
  EXPECT_FALSE(std::isnan(out.depth_m.at<float>(38, 61))) << "exactly max_depth is valid";
  EXPECT_TRUE(std::isnan(out.depth_m.at<float>(38, 63))) << "just above max_depth";
  // The step edge survives: the pixel left of the edge stays near 1 m (the 2.5 m side has
  // weight exp(-1.5^2 / (2 0.05^2)) ~ 0, range sigma 0.04 + 0.01 z^2 at 1 m), and the filter
  // reduces the 3 mm noise.
  const int v = 25, u = w / 2 - 1;
  EXPECT_NEAR(out.depth_m.at<float>(v, u), 1.0f + 0.002f * v, 0.004f);
  EXPECT_NEAR(out.depth_m.at<float>(v, u + 1), 2.5f + 0.002f * v, 0.004f);
  double raw_err = 0, filt_err = 0;
  int n = 0;
  for (int vv = 5; vv < h - 5; ++vv) {
    for (int uu = 20; uu < 28; ++uu) {
      const float truth = 1.0f + 0.002f * vv;
      raw_err += std::pow(depth.at<float>(vv, uu) - truth, 2);
      filt_err += std::pow(out.depth_m.at<float>(vv, uu) - truth, 2);
      ++n;
    }
  }
  EXPECT_LT(std::sqrt(filt_err / n), 0.5 * std::sqrt(raw_err / n));
  // Back-projection p = D K^-1 (u, v, 1).
  const cv::Vec4f p = out.vertex.at<cv::Vec4f>(v, u);
  const float z = out.depth_m.at<float>(v, u);
  EXPECT_FLOAT_EQ(p[0], (u - 33.0f) / 60.0f * z);
  EXPECT_FLOAT_EQ(p[1], (v - 21.5f) / 58.0f * z);
  EXPECT_FLOAT_EQ(p[2], z);
  EXPECT_EQ(p[3], 1.0f);
  // With the filter off the output equals the input where valid.
  o.bilateral_radius_px = 0;
  const PreprocessedFrame raw = preprocessReference(depth, k, o);
  EXPECT_EQ(raw.depth_m.at<float>(v, u), depth.at<float>(v, u));
}

// A w x h pinhole camera with focal length f (px) and the principal point at the image centre.
core::Intrinsics centredCamera(int w, int h, double f) {
  core::Intrinsics k;
  k.fx = k.fy = f;
  k.cx = 0.5 * (w - 1);
  k.cy = 0.5 * (h - 1);
  k.width = w;
  k.height = h;
  return k;
}

// A slanted plane at 3.5-4 m as a structured-light sensor sees it: axial noise (1.9-2.5 cm
// here) and disparity quantised to 1/8 px (f 525 px, baseline 7.5 cm, as Kinect v1: depth
// steps of 0.003 z^2, 4-5 cm here). Returns the RMS error (metres) of the filtered depth against
// the true plane over the image's interior.
double staircaseError(const PreprocessOptions& o, bool device, cl::Context* ctx) {
  const int w = 64, h = 24;
  const core::Intrinsics k = centredCamera(w, h, 525.0);
  const double fb = 525.0 * 0.075, step_px = 0.125;
  cv::Mat truth(h, w, CV_32F), depth(h, w, CV_32F);
  std::mt19937 rng(5);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double z = 3.5 + 0.008 * u;
      const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);  // Kinect v1 axial noise
      const double disparity = std::round(fb / (z + sigma * unit(rng)) / step_px) * step_px;
      truth.at<float>(v, u) = static_cast<float>(z);
      depth.at<float>(v, u) = static_cast<float>(fb / disparity);
    }
  }
  cv::Mat out;
  if (device) {
    Preprocessor pre(*ctx, o, k);
    pre.process(depth);
    out = pre.download().depth_m;
  } else {
    out = preprocessReference(depth, k, o).depth_m;
  }
  double sum = 0.0;
  int n = 0;
  for (int v = 4; v < h - 4; ++v) {
    for (int u = 4; u < w - 4; ++u) {
      sum += std::pow(out.at<float>(v, u) - truth.at<float>(v, u), 2);
      ++n;
    }
  }
  return std::sqrt(sum / n);
}

// With the default range sigma growing with depth^2 (0.16-0.2 m here), the filter smooths the
// noisy quantisation staircase towards the plane; a fixed 4 cm range sigma keeps much of each
// 4-5 cm step as if it were an edge. Measured RMS error: raw 25.2 mm, fixed sigma 10.1 mm,
// default 3.2 mm.
TEST_F(Preprocess, FarQuantisationStepsAreSmoothedNotKeptAsEdges) {
  PreprocessOptions o;
  PreprocessOptions fixed;
  fixed.sigma_depth_per_m2 = 0.0;
  PreprocessOptions raw;
  raw.bilateral_radius_px = 0;
  const double e_raw = staircaseError(raw, false, nullptr);
  const double e_fixed = staircaseError(fixed, false, nullptr);
  const double e_default = staircaseError(o, false, nullptr);
  constexpr double kMaxDefaultErrorM = 0.005;  // half a 1 cm voxel
  constexpr double kMinFixedToDefaultRatio = 2.5;
  EXPECT_LT(e_default, kMaxDefaultErrorM) << "raw " << e_raw << ", fixed " << e_fixed;
  EXPECT_GT(e_fixed, kMinFixedToDefaultRatio * e_default);
  EXPECT_GT(e_raw, e_fixed);
  // The kernel agrees with the reference on this input.
  EXPECT_NEAR(staircaseError(o, true, &ctx()), e_default, 1e-5);
}

// The price of the wider range sigma at depth: a 0.3 m jump at 2 m (range sigma 0.08 m on the
// near side, 0.093 m on the far side) leaks a little across. Measured: 0.2 / 1.2 mm next to
// the edge, 0.04 / 0.2 mm two columns away (a fixed 4 cm sigma: 0.0 mm; sigma_depth_per_m2
// 0.02 would give 24 mm next to the edge).
TEST(PreprocessReference, ThirtyCentimetreEdgeAtTwoMetresStaysSharp) {
  const int w = 32, h = 16;
  const core::Intrinsics k = centredCamera(w, h, 525.0);
  cv::Mat depth(h, w, CV_32F);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) depth.at<float>(v, u) = u < w / 2 ? 2.0f : 2.3f;
  }
  const PreprocessedFrame out = preprocessReference(depth, k, PreprocessOptions());
  constexpr float kMaxEdgeLeakM = 0.003f;
  constexpr float kMaxLeakTwoColumnsAwayM = 0.0005f;
  EXPECT_NEAR(out.depth_m.at<float>(8, w / 2 - 1), 2.0f, kMaxEdgeLeakM);
  EXPECT_NEAR(out.depth_m.at<float>(8, w / 2), 2.3f, kMaxEdgeLeakM);
  EXPECT_NEAR(out.depth_m.at<float>(8, w / 2 - 3), 2.0f, kMaxLeakTwoColumnsAwayM);
  EXPECT_NEAR(out.depth_m.at<float>(8, w / 2 + 2), 2.3f, kMaxLeakTwoColumnsAwayM);
}

TEST_F(Preprocess, BadInputIsAClearError) {
  core::Intrinsics k = test::kinectCamera();
  PreprocessOptions o;
  Preprocessor pre(ctx(), o, k);
  try {
    pre.process(cv::Mat(240, 320, CV_32F, cv::Scalar(1.0f)));
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("640x480"), std::string::npos) << e.what();
  }
  EXPECT_THROW(pre.process(cv::Mat(480, 640, CV_16U, cv::Scalar(1))), InvalidArgument);
  o.min_depth_m = 3.0;
  o.max_depth_m = 2.0;
  try {
    Preprocessor bad(ctx(), o, k);
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("preprocess.min_depth_m"), std::string::npos);
  }
  k.fx = 0;
  EXPECT_THROW(Preprocessor(ctx(), PreprocessOptions{}, k), InvalidArgument);
}

}  // namespace
}  // namespace emf::track
