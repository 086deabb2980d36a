// Depth noise model: statistics on fronto-parallel planes against the model's sigma (axial part
// alone, and with disparity quantisation against expectedStd), range limits, dropouts,
// discontinuity effects and the projector shadow, determinism per seed.
#include "synth/depth_noise.h"

#include <gtest/gtest.h>

#include <cmath>

namespace emf::synth {
namespace {

/// Measured standard deviation vs. the model's (relative); the acceptance bound.
constexpr double kSigmaRelTolerance = 0.10;

struct Stats {
  double mean = 0, std = 0;
  int valid = 0;
};

Stats planeStats(const DepthNoiseModel& model, double z, uint64_t seed) {
  cv::Mat plane(480, 640, CV_32F, cv::Scalar(z));
  cv::Mat noisy;
  model.apply(plane, cv::Mat(), 525.0, seed, 0, &noisy);
  Stats s;
  double sum = 0, sum2 = 0;
  for (int v = 0; v < noisy.rows; ++v) {
    for (int u = 0; u < noisy.cols; ++u) {
      const float d = noisy.at<float>(v, u);
      if (std::isnan(d)) continue;
      sum += d;
      sum2 += static_cast<double>(d) * d;
      ++s.valid;
    }
  }
  s.mean = sum / s.valid;
  s.std = std::sqrt(std::max(0.0, sum2 / s.valid - s.mean * s.mean));
  return s;
}

TEST(SynthDepthNoise, ModelSigmaFollowsNguyen) {
  DepthNoiseModel model({});
  EXPECT_NEAR(model.axialSigma(1.0), 0.0012 + 0.0019 * 0.36, 1e-12);
  EXPECT_NEAR(model.axialSigma(3.0), 0.0012 + 0.0019 * 6.76, 1e-12);
  EXPECT_GT(model.axialSigma(1.0, 1.2), model.axialSigma(1.0));  // grazing angles are worse
  // One 1/8 px disparity step at 1 m: z^2 / (8 * 525 * 0.075).
  EXPECT_NEAR(model.quantizationStep(1.0), 1.0 / (8 * 525 * 0.075), 1e-12);
}

// The axial part alone (quantisation off): measured sigma within 10 % of sigma(z).
TEST(SynthDepthNoise, AxialSigmaAt1mAnd3mMatchesModel) {
  DepthNoiseOptions o;
  o.quantize = false;
  DepthNoiseModel model(o);
  for (double z : {1.0, 3.0}) {
    const Stats s = planeStats(model, z, 11);
    const double sigma = model.axialSigma(z);
    EXPECT_NEAR(s.std, sigma, kSigmaRelTolerance * sigma) << "z = " << z;
    EXPECT_NEAR(s.mean, z, 0.05 * sigma) << "z = " << z;  // unbiased (300k samples)
  }
}

// The full sensor output (axial noise + 1/8 px disparity quantisation) against
// expectedStd(z) = sqrt(sigma^2 + step^2 / 12).
TEST(SynthDepthNoise, QuantisedSigmaAt1mAnd3mMatchesExpectedStd) {
  DepthNoiseModel model({});
  for (double z : {1.0, 3.0}) {
    const Stats s = planeStats(model, z, 12);
    const double expected = model.expectedStd(z);
    EXPECT_NEAR(s.std, expected, kSigmaRelTolerance * expected) << "z = " << z;
    EXPECT_NEAR(s.mean, z, 0.25 * expected) << "z = " << z;
    // Random dropouts only: 0.2 % of the pixels.
    EXPECT_NEAR(1.0 - s.valid / (640.0 * 480.0), 0.002, 0.0005) << "z = " << z;
  }
}

TEST(SynthDepthNoise, QuantisedDepthsLieOnDisparitySteps) {
  DepthNoiseOptions o;
  DepthNoiseModel model(o);
  cv::Mat plane(40, 40, CV_32F, cv::Scalar(2.0f)), noisy;
  model.apply(plane, cv::Mat(), 525.0, 1, 0, &noisy);
  for (int v = 0; v < noisy.rows; ++v) {
    for (int u = 0; u < noisy.cols; ++u) {
      const float z = noisy.at<float>(v, u);
      if (std::isnan(z)) continue;
      const double steps = 525.0 * 0.075 / z * 8.0;
      EXPECT_NEAR(steps, std::round(steps), 1e-4) << u << "," << v;
    }
  }
}

TEST(SynthDepthNoise, RangeLimitsInvalidateTooNearAndTooFar) {
  DepthNoiseModel model({});
  for (double z : {0.3, 5.0}) {
    cv::Mat plane(30, 40, CV_32F, cv::Scalar(z)), noisy;
    model.apply(plane, cv::Mat(), 525.0, 1, 0, &noisy);
    EXPECT_EQ(cv::countNonZero(noisy == noisy), 0) << "z = " << z;  // all NaN
  }
}

TEST(SynthDepthNoise, GrazingSurfacesReturnNothing) {
  DepthNoiseModel model({});
  cv::Mat plane(30, 40, CV_32F, cv::Scalar(1.5)), noisy;
  cv::Mat cos_incidence(30, 40, CV_32F, cv::Scalar(std::cos(86.0 * 3.14159265 / 180)));
  model.apply(plane, cos_incidence, 525.0, 1, 0, &noisy);
  EXPECT_EQ(cv::countNonZero(noisy == noisy), 0);
}

// A foreground block at 1 m in front of a wall at 2 m: pixels at the jump are dropped or
// jittered with the configured probabilities, and the projector shadow removes a band of
// f b (1/z1 - 1/z2) = 525 * 0.075 * 0.5 = 19.7 px of wall left of the block.
TEST(SynthDepthNoise, DiscontinuitiesAndProjectorShadow) {
  DepthNoiseOptions o;
  o.axial_noise = false;
  o.quantize = false;
  o.dropout_prob = 0.0;
  DepthNoiseModel model(o);
  cv::Mat depth(200, 300, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(150, 0, 100, 200)).setTo(1.0f);  // block: columns 150..249
  cv::Mat noisy;
  model.apply(depth, cv::Mat(), 525.0, 5, 0, &noisy);
  const double band = 525.0 * 0.075 * (1.0 / 1.0 - 1.0 / 2.0);
  int shadow_width_sum = 0;
  int edge_total = 0, edge_dropped = 0, edge_jittered = 0;
  for (int v = 0; v < depth.rows; ++v) {
    // Shadow: invalid wall pixels immediately left of the block edge.
    int w = 0;
    for (int u = 149; u >= 0 && std::isnan(noisy.at<float>(v, u)); --u) ++w;
    shadow_width_sum += w;
    EXPECT_TRUE(std::isnan(noisy.at<float>(v, 140)));   // well inside the band
    EXPECT_FALSE(std::isnan(noisy.at<float>(v, 100)));  // well outside it
    // The block's right edge (column 249) borders the wall at 2 m (column 250, not shadowed).
    for (int u : {249, 250}) {
      ++edge_total;
      const float z = noisy.at<float>(v, u);
      if (std::isnan(z)) {
        ++edge_dropped;
      } else if (z != depth.at<float>(v, u)) {
        ++edge_jittered;
      }
    }
  }
  EXPECT_NEAR(shadow_width_sum / 200.0, band, 1.5);
  // Dropout 0.35; a jitter picks one of 8 neighbours, 3 of which lie across the edge.
  EXPECT_NEAR(static_cast<double>(edge_dropped) / edge_total, 0.35, 0.06);
  EXPECT_NEAR(static_cast<double>(edge_jittered) / edge_total, 0.35 * 3.0 / 8.0, 0.06);
  // Away from edges nothing changes (noise terms are off).
  EXPECT_EQ(noisy.at<float>(100, 50), 2.0f);
  EXPECT_EQ(noisy.at<float>(100, 200), 1.0f);
}

// Each part named by noisePartNames() switches off alone: on the block-before-wall scene above,
// without every part the output is the exact depth (a wall at 6 m too, beyond the range); without
// the shadow the wall left of the block is seen; without the edge effects the block's right edge is
// exact.
TEST(SynthDepthNoise, PartsSwitchOffOneByOne) {
  cv::Mat depth(200, 300, CV_32F, cv::Scalar(2.0f));
  depth(cv::Rect(150, 0, 100, 200)).setTo(1.0f);
  DepthNoiseOptions none;
  for (const auto& part : noisePartNames()) ASSERT_TRUE(disableNoisePart(part, &none)) << part;
  cv::Mat out;
  DepthNoiseModel(none).apply(depth, cv::Mat(), 525.0, 5, 0, &out);
  EXPECT_EQ(cv::countNonZero(out != depth), 0);  // NaN would differ too
  // Without "range" nothing is cut beyond max_range_m (4.5 m).
  const cv::Mat far(20, 30, CV_32F, cv::Scalar(6.0f));
  DepthNoiseModel(none).apply(far, cv::Mat(), 525.0, 5, 0, &out);
  EXPECT_EQ(cv::countNonZero(out != far), 0);
  DepthNoiseOptions ranged = none;
  ranged.max_range_m = DepthNoiseOptions().max_range_m;
  DepthNoiseModel(ranged).apply(far, cv::Mat(), 525.0, 5, 0, &out);
  EXPECT_EQ(cv::countNonZero(out == out), 0);

  DepthNoiseOptions no_shadow;  // geometry effects only, without the shadow
  for (const char* part : {"axial", "quantization", "dropouts", "shadow"}) {
    ASSERT_TRUE(disableNoisePart(part, &no_shadow));
  }
  DepthNoiseModel(no_shadow).apply(depth, cv::Mat(), 525.0, 5, 0, &out);
  int edge_changed = 0;
  for (int v = 0; v < depth.rows; ++v) {
    EXPECT_EQ(out.at<float>(v, 140), 2.0f) << v;  // shadowed with the default options
    edge_changed += out.at<float>(v, 249) != 1.0f;
  }
  EXPECT_GT(edge_changed, 0);  // edge effects still on

  DepthNoiseOptions no_edges = no_shadow;
  ASSERT_TRUE(disableNoisePart("edges", &no_edges));
  DepthNoiseModel(no_edges).apply(depth, cv::Mat(), 525.0, 5, 0, &out);
  for (int v = 0; v < depth.rows; ++v) {
    EXPECT_EQ(out.at<float>(v, 249), 1.0f) << v;
    EXPECT_EQ(out.at<float>(v, 250), 2.0f) << v;
  }

  DepthNoiseOptions unchanged;
  EXPECT_FALSE(disableNoisePart("tilt", &unchanged));
  EXPECT_TRUE(unchanged.axial_noise && unchanged.quantize && unchanged.projector_shadow);
}

TEST(SynthDepthNoise, DeterministicPerSeedAndFrame) {
  DepthNoiseModel model({});
  cv::Mat plane(60, 80, CV_32F, cv::Scalar(1.7f)), a, b, c, d;
  model.apply(plane, cv::Mat(), 525.0, 42, 3, &a);
  model.apply(plane, cv::Mat(), 525.0, 42, 3, &b, 3);  // threads do not matter
  model.apply(plane, cv::Mat(), 525.0, 43, 3, &c);
  model.apply(plane, cv::Mat(), 525.0, 42, 4, &d);
  EXPECT_EQ(std::memcmp(a.data, b.data, a.total() * a.elemSize()), 0);
  EXPECT_NE(std::memcmp(a.data, c.data, a.total() * a.elemSize()), 0);
  EXPECT_NE(std::memcmp(a.data, d.data, a.total() * a.elemSize()), 0);
}

TEST(SynthDepthNoise, DisabledCopiesExactDepth) {
  DepthNoiseOptions o;
  o.enabled = false;
  DepthNoiseModel model(o);
  cv::Mat depth(10, 10, CV_32F, cv::Scalar(1.234f)), out;
  model.apply(depth, cv::Mat(), 525.0, 1, 0, &out);
  EXPECT_EQ(cv::countNonZero(out != depth), 0);
}

}  // namespace
}  // namespace emf::synth
