// Kinect-v1-like depth sensor model applied to an exact rendered depth image:
//  - axial noise: Gaussian with sigma_z(z, theta) = a + b (z - z0)^2
//      + c / sqrt(z) * theta^2 / (pi/2 - theta)^2   (Nguyen, Izadi, Lovell 2012, metres),
//    theta = angle between viewing ray and surface normal;
//  - disparity quantisation: d = f b / z quantised to 1/8 px (f = 525 px, b = 0.075 m), so
//    the depth step grows as z^2 / (8 f b) (3.2 mm at 1 m, 29 mm at 3 m);
//  - depth discontinuities: pixels next to a jump are dropped or take a neighbour's depth
//    (lateral jitter), and the projector shadow (background beside a foreground edge that the
//    projector, b to the side, cannot see) is invalid;
//  - range limits, grazing-angle dropouts and a few random dropouts.
// Invalid pixels are NaN. Deterministic per (seed, frame): each row draws from its own stream.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace emf::synth {

struct DepthNoiseOptions {
  bool enabled = true;  // false: apply() copies the exact depth unchanged
  double min_range_m = 0.4, max_range_m = 4.5;
  // Axial sigma(z) = sigma_base_m + sigma_quadratic_per_m * (z - sigma_offset_m)^2 (+ angle).
  double sigma_base_m = 0.0012;
  double sigma_quadratic_per_m = 0.0019;
  double sigma_offset_m = 0.4;
  double sigma_angle_m = 0.0001;  // c of the incidence-angle term (metres * sqrt(m))
  bool axial_noise = true;
  // Disparity quantisation.
  bool quantize = true;
  double baseline_m = 0.075;
  double focal_px = 525.0;  // the sensor's focal length for disparity (independent of the
                            // rendered resolution)
  double disparity_step_px = 0.125;
  // Discontinuities: a 4-neighbour differing by more than edge_threshold_rel * z (or invalid).
  double edge_threshold_rel = 0.04;
  double edge_dropout_prob = 0.35;  // edge pixel becomes invalid
  double edge_jitter_prob = 0.35;   // edge pixel takes a random 8-neighbour's depth
  bool projector_shadow = true;
  double max_incidence_deg = 84.0;  // more grazing surfaces return nothing
  double dropout_prob = 0.002;      // random invalid pixels
};

/// Names of the model's parts that disableNoisePart() switches off, in the order listed above:
/// axial, quantization, edges (dropout and jitter at discontinuities), shadow, grazing, dropouts,
/// range (the range limits).
const std::vector<std::string>& noisePartNames();
/// Switches one part of the model off (e.g. to find which part of the sensor a tracker is
/// sensitive to). Returns false for a name not in noisePartNames().
bool disableNoisePart(const std::string& name, DepthNoiseOptions* options);

class DepthNoiseModel {
 public:
  explicit DepthNoiseModel(const DepthNoiseOptions& options) : options_(options) {}
  const DepthNoiseOptions& options() const { return options_; }

  /// Standard deviation (metres) of the axial Gaussian at depth z (m) and incidence theta (rad).
  double axialSigma(double z_m, double theta_rad = 0.0) const;
  /// Depth step (metres) of one disparity quantum at depth z (0 when quantisation is off).
  double quantizationStep(double z_m) const;
  /// Expected standard deviation of the output depth over a fronto-parallel plane at z:
  /// sqrt(sigma^2 + step^2 / 12) (quantisation as uniform error, valid while sigma is not much
  /// smaller than the step: true up to ~4 m with the defaults).
  double expectedStd(double z_m) const;

  /// Applies the model to `depth` (CV_32F metres, NaN invalid). `cos_incidence` (CV_32F, may be
  /// empty = fronto-parallel) gives |cos theta| per pixel; fx_px is the rendered image's focal
  /// length (for the projector-shadow width). Writes a new CV_32F image into *out.
  void apply(const cv::Mat& depth, const cv::Mat& cos_incidence, double fx_px, uint64_t seed,
             int64_t frame_index, cv::Mat* out, int threads = 1) const;

 private:
  DepthNoiseOptions options_;
};

}  // namespace emf::synth
