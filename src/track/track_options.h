// Options of preprocessing (section `preprocess`) and pose tracking (section `track`).
#pragma once

#include <algorithm>
#include <string>

#include "common/option_binder.h"

namespace emf::track {

struct PreprocessOptions {
  /// Range sigma of the bilateral filter at a pixel of depth z, metres: sigma_depth_m +
  /// sigma_depth_per_m2 * z^2 (default 0.04 + 0.01 z^2; the paper: 0.04 m at every depth,
  /// sigma_depth_per_m2 = 0). Depth noise and the disparity quantisation step of
  /// structured-light and stereo sensors grow with z^2 (Kinect v1: step 0.003 z^2); a fixed
  /// sigma keeps far steps and noise as edges, and tracking against them shrinks the camera's
  /// motion. Larger values blur real depth edges. docs/method.md#preprocessing.
  double sigma_depth_m = 0.04;
  double sigma_depth_per_m2 = 0.01;
  double sigma_space_px = 4.5;
  int bilateral_radius_px = 3;  // 7x7 window
  double min_depth_m = 0.1;
  double max_depth_m = 5.0;
  /// Valid pixels within this many pixels (Chebyshev distance) of a pixel without depth (NaN or
  /// <= 0; the image border does not count) are dropped before filtering, tracking and
  /// integration; 0 keeps them (the paper, the default). Next to a hole are a structured-light
  /// sensor's edge dropouts, projector shadows and flying pixels. Not the default: holes line
  /// every depth edge, and the edge pixels are what holds the camera against a large mover
  /// nobody detected; range_guard_per_m2 removes the drift these pixels cause and keeps the
  /// edges. docs/method.md#preprocessing.
  int hole_margin_px = 0;
  /// Range guard, m/m^2: a pixel whose filtered depth lies within range_guard_per_m2 * L^2 of
  /// the frame's depth limit L = min(max_depth_m, the largest valid depth of the frame), and
  /// whose filter window holds a pixel without usable depth, is dropped before tracking and
  /// integration (default 0.002: 4 cm at L = 4.5 m, about 1.2 sigma of a Kinect v1 there;
  /// 0 = off, the paper). The noisy depth of a surface near a range limit is cut on one side,
  /// so the map fuses it too near while the camera is far and less near as it comes closer: the
  /// tracker's minimum follows the camera's motion and the camera drifts while exploring. The
  /// filtered depth decides (the guard's own cut is then hardly one-sided), and only next to
  /// holes (a clean far wall stays). docs/method.md#preprocessing,
  /// docs/benchmarks.md#the-camera-trackers-bias-benchtrack_bias.
  double range_guard_per_m2 = 0.002;

  void bind(OptionBinder& b) {
    b.real("sigma_depth_m", sigma_depth_m, 1e-4, 10.0, "m",
           "bilateral filter range sigma at depth 0");
    b.real("sigma_depth_per_m2", sigma_depth_per_m2, 0.0, 10.0, "m/m^2",
           "growth of the range sigma with the pixel's depth^2 (0 = fixed, the paper)");
    b.real("sigma_space_px", sigma_space_px, 0.1, 50.0, "px", "bilateral filter spatial sigma");
    b.integer("bilateral_radius_px", bilateral_radius_px, 0, 10, "px",
              "bilateral half window (3 = 7x7, 0 = off)");
    b.real("min_depth_m", min_depth_m, 0.0, 100.0, "m", "depths below are invalid");
    b.real("max_depth_m", max_depth_m, 0.01, 100.0, "m", "depths above are invalid");
    b.integer("hole_margin_px", hole_margin_px, 0, 5, "px",
              "valid pixels this close to a pixel without depth are dropped (0 = keep)");
    b.real("range_guard_per_m2", range_guard_per_m2, 0.0, 0.1, "m/m^2",
           "pixels whose filtered depth is within this x L^2 of the frame's depth limit L and "
           "that have a hole in their filter window are dropped (0 = off)");
  }
};

enum class FinalReduction { kHost, kDevice };
inline const ChoiceNames<FinalReduction>& finalReductionNames() {
  static const ChoiceNames<FinalReduction> names = {{FinalReduction::kHost, "host"},
                                                    {FinalReduction::kDevice, "device"}};
  return names;
}
enum class RotationCentre { kCamera, kStiffness, kOrigin };
inline const ChoiceNames<RotationCentre>& rotationCentreNames() {
  static const ChoiceNames<RotationCentre> names = {{RotationCentre::kCamera, "camera"},
                                                    {RotationCentre::kStiffness, "stiffness"},
                                                    {RotationCentre::kOrigin, "origin"}};
  return names;
}
enum class StepAcceptance { kCost, kFixedWeights };
inline const ChoiceNames<StepAcceptance>& stepAcceptanceNames() {
  static const ChoiceNames<StepAcceptance> names = {
      {StepAcceptance::kCost, "cost"}, {StepAcceptance::kFixedWeights, "fixed_weights"}};
  return names;
}

struct TrackOptions {
  int max_iterations = 100;
  /// LM's initial damping mu0 = lm_tau * max diag(H) (default 1e-3; the paper: 1e3, whose first
  /// iterations of every level only ramp the damping down: same minimum, more iterations).
  /// docs/method.md#tracking.
  double lm_tau = 1e-3;
  double lm_eps = 1e-8;
  double lm_nu = 2.0;
  /// Huber threshold as a fraction of the truncation distance: 0.05 x 10 voxels = half a voxel
  /// (the paper: 0.2 = 2 voxels). A tighter delta bounds the pull of surfaces the map does not
  /// explain, such as a mover no detector has found yet. Objects have their own
  /// (objects.huber_truncation_factor). docs/method.md#tracking.
  double huber_truncation_factor = 0.05;
  /// Motion prior (not a config key; objects set it from objects.motion_prior_rotation): the
  /// cost gets E_p = (lt |d_t|^2 + lr |d_w|^2) / 2, d = (d_t, d_w) the pose's left difference
  /// from the initial pose (the prediction) in the increments LM solves for (d_w in radians,
  /// d_t in metres at the rotation centre), lt = prior_translation_weight, lr =
  /// prior_rotation_weight. Their unit is the data term's: a pixel with map weight max W, q = 1
  /// and a unit SDF gradient adds r^2 / 2. Coarse levels, with 1/4 of the pixels per level, use
  /// 1/4 of the weights per level. 0 = off (the paper).
  double prior_translation_weight = 0.0;
  double prior_rotation_weight = 0.0;

  // Speed: the camera's defaults below trade almost no accuracy for a fraction of the time of
  // the paper's settings (every pixel, one level, LM's own convergence test, plain steps;
  // bench/track_bench compares them, docs/benchmarks.md#the-slam-against-a-peer-benchslam_bench).
  // Object tracking uses every pixel (pipeline::objectTrackOptions).
  /// Use every n-th pixel in x and y at the finest level (1 = all pixels); 0 = by the image's
  /// width, every (width / 160)-th pixel and at least every 2nd (2 at 320x240, 4 at 640x480: the
  /// same density on the scene). pixelStrideFor resolves it; Tracker does so on construction.
  int pixel_stride = 0;
  int pixelStrideFor(int width) const {
    return pixel_stride > 0 ? pixel_stride : std::max(2, width / 160);
  }
  /// Extra coarse levels run before the finest one, level l using stride pixel_stride * 2^l.
  int coarse_levels = 1;
  /// LM iteration cap on each coarse level (the finest level uses max_iterations).
  int coarse_max_iterations = 10;
  /// Early exit: stop once the Gauss-Newton step at the current pose (the model's distance to
  /// its minimum, whatever LM's damping) is below this norm (metres and radians mixed, 1e-4 =
  /// 0.1 mm / 0.1 mrad). 0 = only the LM criteria (lm_eps).
  double early_exit_step = 1e-4;
  /// Step extrapolation: an accepted LM step whose cost decrease exceeds 1.5x the model's
  /// prediction doubles the scale of the next steps, up to this factor (1 = plain LM).
  double max_step_scale = 8.0;
  /// Where the per-work-group partial sums are added up: "host" or "device" (second kernel).
  FinalReduction final_reduction = FinalReduction::kHost;
  /// Centre of the rotation increments LM solves for: "camera" (the camera centre, the usual
  /// camera-frame parametrisation), "stiffness" (stiffnessCentre of the Hessian: about the
  /// centroid of the constraining points) or "origin" (the volume's origin, the left increments
  /// as such). Only the LM path and step sizes change, not the minimum: a far origin couples
  /// rotation and translation. "stiffness" is not the camera default: on the tum-fr3-cabinet
  /// keyframes it stopped converging and re-acquired a wrong pose that passed every loss rule.
  /// Objects use "stiffness" (pipeline::objectTrackOptions, docs/method.md#object-tracking).
  RotationCentre rotation_centre = RotationCentre::kCamera;
  /// What LM's step acceptance compares with the model's predicted decrease: "cost" (the cost
  /// sum c rho(r) at both poses, c = q W(p) sampled at each) or "fixed_weights" (the new
  /// residuals weighted by the c of the accepted pose, as in the model; IRLS). The model holds c
  /// constant while W(p) moves with the pose: where W varies strongly (a small, partly observed
  /// object model) "cost" measures about half the predicted decrease even for tiny steps, LM's
  /// damping barely falls, and LM crawls and stops near the prediction. The camera keeps
  /// "cost"; objects use "fixed_weights" (pipeline::objectTrackOptions,
  /// docs/method.md#object-tracking).
  StepAcceptance step_acceptance = StepAcceptance::kCost;

  // Tracking loss: a frame is lost when any rule fires (evaluated at the final pose, finest
  // level). See track::Tracker.
  /// Lost when (pixels landing on observed map) / (pixels with valid depth) is below this.
  double min_valid_fraction = 0.3;
  /// Lost when (points within the inlier radius, below) / (points landing on observed map) is
  /// below, each point weighted by its association q. 0.75 lies between correctly tracked real
  /// frames and wrong fits (docs/method.md#tracking-loss).
  double min_inlier_ratio = 0.75;
  /// The loss rules' inlier delta as a fraction of the truncation: the paper's Huber delta, 0.2
  /// (2 voxels), on which the ratios here were set. It is separate from huber_truncation_factor,
  /// so that a tighter Huber delta does not change which frames are called lost.
  double inlier_truncation_factor = 0.2;
  /// Inlier radius of the loss rules, m/m^2: a point is an inlier when |psi| <= max(inlier
  /// delta, inlier_noise_per_m2 * z^2), z its depth (metres). The depth noise of triangulating
  /// sensors grows with z^2 (Kinect v1 and its synthetic model: sigma ~ 0.0018 z^2 with the
  /// disparity quantisation, 1.6 cm at 3 m), so beyond ~2 m a fixed 2 cm delta (1 cm voxels)
  /// counts correctly tracked points as outliers. 0.005 is ~2 sigma of the residual between two
  /// such measurements; it changes nothing nearer than 2 m at 1 cm voxels (2.8 m at 2 cm). 0 =
  /// the inlier delta only. Only the count changes, not the cost.
  double inlier_noise_per_m2 = 0.005;
  /// After a lost call on a volume, its next calls must reach this inlier ratio until one is
  /// not lost: there is no relocalisation, so a pose re-acquired near the last good one after
  /// the camera moved on is often a wrong but locally consistent fit. Capped at the volume's
  /// typical inlier ratio (running mean of its tracked calls) minus 0.05, so that a noisy sensor
  /// whose good frames stay below it can recover. 0 = no extra rule.
  double recovery_min_inlier_ratio = 0.9;
  /// Lost when the inverse condition number of the balanced Hessian (rotation block scaled to
  /// the translation block's trace) is below this: the geometry does not constrain all 6 DoF.
  double min_inverse_condition = 1e-3;
  /// Lost when the finest level used all max_iterations without converging (large motion or a
  /// flat valley: the estimate is not trusted).
  bool lost_if_not_converged = true;
  /// Lost when the estimate moved farther than this from the initial pose in one call (a
  /// wrong basin: real cameras move a few cm per frame).
  double max_motion_m = 0.3;
  double max_motion_deg = 20.0;
  /// While recovering after a lost call (see recovery_min_inlier_ratio), lost when the estimate
  /// moved farther than this from the last tracked pose: with no relocalisation, only a camera
  /// back near its last tracked view is re-acquired; LM started from a stale pose converges to
  /// wrong fits nearby that pass every other rule. Objects use max_motion_* instead
  /// (pipeline::objectTrackOptions): a lost object may have moved on.
  double recovery_max_motion_m = 0.1;
  double recovery_max_motion_deg = 5.0;

  void bind(OptionBinder& b) {
    b.integer("max_iterations", max_iterations, 1, 1000, "", "LM iterations per frame and volume");
    b.real("lm_tau", lm_tau, 1e-12, 1e12, "", "LM initial damping scale");
    b.real("lm_eps", lm_eps, 0.0, 1.0, "", "LM convergence threshold on the increment");
    b.real("lm_nu", lm_nu, 1.0, 100.0, "",
           "LM damping growth factor after a rejected step (doubles per further rejection)");
    b.real("huber_truncation_factor", huber_truncation_factor, 0.0, 10.0, "truncation",
           "Huber delta as a fraction of the truncation distance");
    b.integer("pixel_stride", pixel_stride, 0, 16, "px",
              "use every n-th pixel in x and y at the finest level (0 = width / 160, at least 2)");
    b.integer("coarse_levels", coarse_levels, 0, 4, "",
              "coarse levels (stride doubled per level) run before the finest level");
    b.integer("coarse_max_iterations", coarse_max_iterations, 1, 1000, "",
              "LM iterations per coarse level");
    b.real("early_exit_step", early_exit_step, 0.0, 1.0, "m|rad",
           "stop when the Gauss-Newton step is below this norm (0 = off)");
    b.real("max_step_scale", max_step_scale, 1.0, 64.0, "",
           "LM step extrapolation limit where the cost falls faster than predicted (1 = off)");
    b.choice("final_reduction", final_reduction, finalReductionNames(),
             "where the per-work-group partial sums are added");
    b.choice("rotation_centre", rotation_centre, rotationCentreNames(),
             "centre of the rotation increments LM solves for (objects: stiffness)");
    b.choice("step_acceptance", step_acceptance, stepAcceptanceNames(),
             "LM accepts a step by the cost change (cost) or by the change of the residuals "
             "at the accepted pose's weights (fixed_weights, IRLS; objects use this)");
    b.real("min_valid_fraction", min_valid_fraction, 0.0, 1.0, "",
           "lost below this fraction of depth pixels landing on the observed map");
    b.real("min_inlier_ratio", min_inlier_ratio, 0.0, 1.0, "",
           "lost below this fraction of map points within the inlier radius");
    b.real("inlier_truncation_factor", inlier_truncation_factor, 0.0, 10.0, "truncation",
           "loss rules: inlier delta as a fraction of the truncation (strict inliers within it)");
    b.real("inlier_noise_per_m2", inlier_noise_per_m2, 0.0, 1.0, "m/m^2",
           "loss rules: inlier radius max(inlier delta, this x depth^2) (depth noise; 0 = delta)");
    b.real("recovery_min_inlier_ratio", recovery_min_inlier_ratio, 0.0, 1.0, "",
           "after a lost frame: lost below this inlier ratio until a frame is tracked again");
    b.real("min_inverse_condition", min_inverse_condition, 0.0, 1.0, "",
           "lost below this inverse condition number of the balanced 6x6 Hessian");
    b.boolean("lost_if_not_converged", lost_if_not_converged,
              "lost when the finest level ends at max_iterations without converging");
    b.real("max_motion_m", max_motion_m, 0.0, 100.0, "m",
           "lost when the pose moved farther than this from its initial value");
    b.real("max_motion_deg", max_motion_deg, 0.0, 180.0, "deg",
           "lost when the pose rotated more than this from its initial value");
    b.real("recovery_max_motion_m", recovery_max_motion_m, 0.0, 100.0, "m",
           "after a lost frame: lost when the pose moved farther than this from the last tracked");
    b.real("recovery_max_motion_deg", recovery_max_motion_deg, 0.0, 180.0, "deg",
           "after a lost frame: lost when the pose rotated more than this from the last tracked");
  }
};

}  // namespace emf::track
