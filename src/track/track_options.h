// Options of preprocessing (section `preprocess`) and pose tracking (section `track`).
#pragma once

#include <string>

#include "common/option_binder.h"

namespace emf::track {

struct PreprocessOptions {
  /// Range sigma of the bilateral filter at a pixel of depth z: sigma_depth_m +
  /// sigma_depth_per_m2 * z^2 (the paper: 0.04 m at every depth, sigma_depth_per_m2 = 0).
  /// Depth noise and the disparity quantisation step of structured-light and stereo sensors
  /// grow with z^2 (Kinect v1: step 0.003 z^2, 5 cm at 4 m). A fixed 4 cm range sigma keeps
  /// far quantisation steps and noise as if they were edges, and tracking against them shrinks
  /// the camera's motion: occlusion preset 640x480 seed 3, after 90 frames (0.57 m) the camera
  /// is 1.95 cm off and 3.3 % short with 0, 1.43 cm and 2.5 % short with 0.01 (quantisation
  /// without axial noise: 7-19 % short with 0).
  /// bench/slam_bench, 300 frames 640x480, ATE with 0 / 0.01 / 0.02 / 0.05: synthetic room
  /// 0.336 / 0.238 / 0.209 / 0.140 cm, redkitchen 2.217 / 2.218 / 2.219 / 2.214 cm. Occlusion
  /// preset, 150 frames, camera ATE of seeds 2 and 3: 1.11 / 1.04 cm with 0, 0.69 / 0.70 with
  /// 0.01, 0.66 / 0.65 with 0.02. Larger values blur real edges: a 0.3 m jump at 2 m leaks
  /// 1.2 mm into the next pixel with 0.01, 24 mm with 0.02.
  double sigma_depth_m = 0.04;
  double sigma_depth_per_m2 = 0.01;
  double sigma_space_px = 4.5;
  int bilateral_radius_px = 3;  // 7x7 window
  double min_depth_m = 0.1;
  double max_depth_m = 5.0;
  /// Valid pixels within this many pixels (Chebyshev distance) of a pixel without depth (NaN or
  /// <= 0; the image border does not count) are dropped before filtering, tracking and
  /// integration; 0 keeps them (the paper, the default). Next to a hole are a structured-light
  /// sensor's edge dropouts, projector shadows and flying pixels, and with them the tracker's
  /// minimum sits 3-4 mm back along the camera's path even on a map fused at ground-truth poses
  /// (bench/track_bias, 150 frames of the occlusion preset with its objects held still, x: -3.57
  /// mm with 0, -0.78 with 1, -0.02 with 2; played backwards +2.93 / +0.34 mm). In SLAM that
  /// offset becomes a drift while the camera explores: occlusion preset, 600 frames, camera ATE
  /// 1.37 -> 0.57 cm at 640x480 and 1.99 -> 0.98 cm at 320x240 with 1; redkitchen unchanged
  /// (bench/slam_bench 2.218 -> 2.216 cm).
  /// Not the default: with the synthetic sensor's edge dropouts, holes line every depth edge
  /// and a margin of 1 removes 90 % of the edge pixels (6 % of all), which are what holds the
  /// camera against a large mover nobody detected: the undetected panel of
  /// tests/pipeline/slam_occlusion_test.cpp drags the camera 0.82 m along with 1 (seeds 1-5;
  /// 2.4-3.9 cm at most with 0, then recovered). The part of that offset that makes the camera
  /// drift on the synthetic presets turned out to come from the pixels next to the holes that
  /// a range limit cuts into far surfaces: range_guard_per_m2 (below, on by default) drops
  /// those and keeps the edges.
  int hole_margin_px = 0;
  /// Range guard: a pixel whose filtered depth lies within range_guard_per_m2 * L^2 of the
  /// frame's depth limit L, and whose filter window holds a pixel without usable depth, is
  /// dropped before tracking and integration (0 = off, the paper).
  /// L = min(max_depth_m, the largest valid depth of the frame): a sensor returns nothing
  /// beyond its range, and this preprocessing uses nothing beyond max_depth_m. The noisy depth
  /// of a surface near such a limit is cut on one side only, so what remains of it lies nearer
  /// the camera than the surface (a truncated Gaussian), and such a surface is riddled with
  /// holes. The map fuses it too near while the camera is farther away and measures it less
  /// near when the camera comes closer, so the tracker's minimum follows the camera's motion;
  /// while exploring that becomes drift. The filtered depth decides (its noise is a fraction of
  /// the raw depth's, so the guard itself cuts little on one side), and only next to holes (a
  /// clean far wall, the frame's farthest surface without a range limit behind it, stays).
  /// 0.002 is about 1.2 standard deviations of a Kinect v1's depth at the range limit (sigma
  /// 0.0012 + 0.0019 (z - 0.4)^2 m: 3.2 cm at 4.5 m; 4 cm at L = 4.5 m).
  /// bench/track_bias, `emf synth room` (range 4.5 m), 150 frames, x offset forward / played
  /// backwards: -1.89 / +1.22 mm without, -1.45 / -0.72 mm with 0.002. Camera ATE, `emf synth`
  /// + `emf run --detector maskfile` + `emf eval`, seed 1, 0 -> 0.002: occlusion 600 frames
  /// 1.37 -> 0.29 cm (640x480), 1.99 -> 0.54 cm (320x240); occlusion 150 frames
  /// 0.60 -> 0.21 cm; bench/slam_bench synthetic room 0.238 -> 0.180 cm, redkitchen 2.218 cm
  /// either way. 0.003-0.005 take the camera no further, but the undetected panel of
  /// tests/pipeline/slam_occlusion_test.cpp then drags the camera 0.81 m on seed 2 (seeds 1-6:
  /// 3.1-4.3 cm at most with 0, 3.4-6.5 cm with 0.002). See README (bench/track_bias).
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

struct TrackOptions {
  int max_iterations = 100;
  /// LM's initial damping mu0 = lm_tau * max diag(H). The paper's 1e3 spends the first ~7
  /// iterations of every level ramping the damping down (each accepted step divides it by 3 at
  /// most). bench/slam_bench, 300 frames at 640x480, LM iterations median / p90 per frame and ATE:
  /// redkitchen 15 / 22, 2.214 cm (1e3) -> 5 / 9, 2.217 cm (1e-3); synthetic room 15 / 17, 0.335
  /// cm -> 5 / 7, 0.336 cm. 0.1 and 1e-6: 7-8 / 10-16 and 5 / 7-11 iterations, the same ATE.
  double lm_tau = 1e-3;
  double lm_eps = 1e-8;
  double lm_nu = 2.0;
  /// Huber threshold as a fraction of the truncation distance: 0.05 x 10 voxels = half a voxel
  /// (the paper: 0.2 = 2 voxels). A tighter delta bounds the pull of surfaces the map does not
  /// explain, such as a mover no detector has found yet. bench/slam_bench, 300 frames, ATE at
  /// 0.2 / 0.1 / 0.05 / 0.025: synthetic room 640x480 0.518 / 0.516 / 0.487 / 0.687 cm, 320x240
  /// 0.988 / 0.854 / 0.843 cm; redkitchen 640x480 2.250 / 2.229 / 2.214 / 2.217 cm, 320x240
  /// 2.156 / 2.166 / 2.171 cm. Objects have their own (objects.huber_truncation_factor).
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

  // Speed (bench/track_bench measures these against the paper's settings above). Camera
  // defaults from bench/slam_bench on redkitchen, 300 frames (quiet machine): ATE 2.155 cm at
  // 320x240 / 2 cm either way and 2.259 vs 2.250 cm at 640x480 / 1 cm, whole frame 10.5 vs
  // 21.2 ms and 34.3 vs 78.1 ms against stride 1, 2 coarse levels, early exit 1e-5. Object
  // tracking uses every pixel (pipeline::objectTrackOptions).
  /// Use every n-th pixel in x and y at the finest level (1 = all pixels).
  int pixel_stride = 2;
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
  std::string final_reduction = "host";
  /// Centre of the rotation increments LM solves for: "camera" (the camera centre, the usual
  /// camera-frame parametrisation), "stiffness" (stiffnessCentre of the Hessian: about the
  /// centroid of the constraining points) or "origin" (the volume's origin, the left increments
  /// as such). Only the LM path and step sizes change, not the minimum: a far origin couples
  /// rotation and translation (a 7.68 m background lost 230 of redkitchen's 300 frames).
  /// Redkitchen 300 frames at 640x480, back to back on a busy machine: track 30.7 / 20.5 /
  /// 14.0 ms, ATE 2.254 / 2.250 / 2.252 cm (origin / camera / stiffness); synthetic room 0.527
  /// / 0.528 / 0.504 cm. "stiffness" is not the camera default: on tum-fr3-cabinet-keyframes
  /// it stops converging at keyframe 5 and re-acquires a wrong pose at keyframe 15 that passes
  /// every loss rule. Objects use "stiffness" (pipeline::objectTrackOptions).
  std::string rotation_centre = "camera";
  /// What LM's step acceptance compares with the model's predicted decrease: "cost" (the cost
  /// sum c rho(r) at both poses, c = q W(p) sampled at each) or "fixed_weights" (the new
  /// residuals weighted by the c of the accepted pose, as in the model; IRLS). The model holds c
  /// constant while W(p) moves with the pose: where W varies strongly (a small, partly observed
  /// object model) "cost" measures about half the predicted decrease even for tiny steps, so LM's
  /// damping barely falls, and LM crawled and stopped near the prediction (occlusion
  /// preset, 320x240: the bear "converged" after 5 + 5 iterations with 0.05 mm of motion on 9
  /// frames in a row, then was lost 0.8 m off). The camera keeps "cost" (synthetic room at
  /// 640x480: ATE 0.518 / 0.527 cm with cost / fixed_weights); objects use "fixed_weights"
  /// (pipeline::objectTrackOptions).
  std::string step_acceptance = "cost";

  // Tracking loss: a frame is lost when any rule fires (evaluated at the final pose, finest
  // level). See track::Tracker.
  /// Lost when (pixels landing on observed map) / (pixels with valid depth) is below this.
  double min_valid_fraction = 0.3;
  /// Lost when (points within the inlier radius, below) / (points landing on observed map) is
  /// below. 0.75: real frames tracked correctly show >= 0.85 (redkitchen-0-299), frames integrated
  /// 4-9 cm / 6-9 deg off on tum-fr3-cabinet-keyframes 0.65-0.71.
  double min_inlier_ratio = 0.75;
  /// The loss rules' inlier delta as a fraction of the truncation: the paper's Huber delta, 0.2
  /// (2 voxels), on which the ratios here were set. It is separate from huber_truncation_factor,
  /// so that a tighter Huber delta does not change which frames are called lost.
  double inlier_truncation_factor = 0.2;
  /// Inlier radius of the loss rules: a point is an inlier when |psi| <= max(inlier delta,
  /// inlier_noise_per_m2 * z^2), z its depth (metres). The depth noise of triangulating sensors
  /// grows with z^2 (Kinect v1 and its synthetic model: sigma ~ 0.0018 z^2 with the disparity
  /// quantisation, 1.6 cm at 3 m), so beyond ~2 m a fixed 2 cm delta (1 cm voxels) counts
  /// correctly tracked points as outliers: the occlusion preset at 640x480, 3 m away, showed
  /// inlier ratios 0.68-0.72 on frames tracked to 0.7 cm and lost 29 of 30. 0.005 is ~2 sigma of
  /// the residual between two such measurements; it changes nothing nearer than 2 m at 1 cm voxels
  /// (2.8 m at 2 cm). 0 = the inlier delta only. Only the count changes, not the cost.
  double inlier_noise_per_m2 = 0.005;
  /// After a lost call on a volume, its next calls must reach this inlier ratio until one is
  /// not lost: there is no relocalisation, so a pose re-acquired near the last good one after
  /// the camera moved on is often a wrong but locally consistent fit (0.76-0.85 seen on the
  /// cabinet keyframes, about 1 m off). Capped at the volume's typical inlier ratio (running
  /// mean of its tracked calls) minus 0.05, so that a noisy sensor whose good frames stay below
  /// it can recover (synthetic Kinect-v1 noise at 1 cm voxels: ~0.85). 0 = no extra rule.
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
  /// back near its last tracked view is re-acquired. LM started from the stale pose of the
  /// cabinet keyframes converged to wrong fits 0.16-0.23 m / 4-8 deg away that passed every
  /// other rule (1.9-2.8 m off the ground truth).
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
    b.integer("pixel_stride", pixel_stride, 1, 16, "px",
              "use every n-th pixel in x and y at the finest level");
    b.integer("coarse_levels", coarse_levels, 0, 4, "",
              "coarse levels (stride doubled per level) run before the finest level");
    b.integer("coarse_max_iterations", coarse_max_iterations, 1, 1000, "",
              "LM iterations per coarse level");
    b.real("early_exit_step", early_exit_step, 0.0, 1.0, "m|rad",
           "stop when the Gauss-Newton step is below this norm (0 = off)");
    b.real("max_step_scale", max_step_scale, 1.0, 64.0, "",
           "LM step extrapolation limit where the cost falls faster than predicted (1 = off)");
    b.choice("final_reduction", final_reduction, {"host", "device"},
             "where the per-work-group partial sums are added");
    b.choice("rotation_centre", rotation_centre, {"camera", "stiffness", "origin"},
             "centre of the rotation increments LM solves for (objects: stiffness)");
    b.choice("step_acceptance", step_acceptance, {"cost", "fixed_weights"},
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
