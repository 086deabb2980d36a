// Direct SDF-alignment tracking of the camera against one volume (docs/method.md#tracking).
//
// Minimises E(T) = sum_u q_u * c_u * rho(psi(T p_u)) over T = T_volume_camera, where p_u is the
// camera-frame vertex map, psi the volume's trilinear SDF (metres), c_u = W(T p_u) / max W the
// map confidence (max W over the frame's samples at the initial pose, fixed for the call), q_u
// the per-pixel association weight and rho the Huber cost with delta = huber_truncation_factor
// x truncation (rho(r) = r^2/2 for |r| <= delta, delta (|r| - delta/2) beyond; its IRLS form is
// 1/2 w_u r^2 with w_u = min(1, delta/|r|)). Levenberg-Marquardt on left-multiplied se(3)
// increments (translation first, see se3.h); the accumulation of H, g and E runs on the device
// (kernels_cl/track_reduce.cl), the 6x6 damped solve on the host (Eigen LDLT).
//
// LM details: mu0 = lm_tau * max diag(H); a step h solves (H + mu I) h = -g and is accepted
// when the actual cost reduction, measured over the pixels valid at both poses, is positive
// (gain ratio rho > 0: mu *= max(1/3, 1 - (2 rho - 1)^3)); otherwise mu *= nu, nu doubles.
// Stops when |g|_inf or |h| <= lm_eps, after max_iterations, or (early_exit_step > 0) once
// the Gauss-Newton step -H^-1 g is shorter than early_exit_step. Optional coarse levels run first
// on every 2^l-th pixel (pixel_stride x 2^l), each continuing with the damping the previous one
// reached. Step extrapolation (max_step_scale > 1): while accepted steps decrease the cost by more
// than 1.5x the model's prediction, the next LM steps are scaled by 2, 4, .. up to max_step_scale
// (the IRLS Hessian is too stiff far from the minimum); a disappointing or rejected scaled step
// falls back to scale 1 without changing the damping.
//
// Tracking loss (TrackResult::lost), checked in this order at the final pose of the finest level:
//   no pixel with valid depth                          -> kNoDepth
//   valid / input < min_valid_fraction                 -> kFewValidPoints
//   |T_init^-1 T| > max_motion_m or max_motion_deg     -> kLargeMotion
//   inliers / valid < min_inlier_ratio                 -> kFewInliers
//     (inlier: |r| <= max(inlier delta, inlier_noise_per_m2 z^2), the depth noise allowed for;
//     inlier delta = inlier_truncation_factor x truncation, the paper's Huber delta; both
//     counts weighted by the pixels' association q: points the E-step gives to another
//     volume, such as the floor around an object, do not count against it)
//   recovering and |T_init^-1 T| > recovery_max_motion_m or recovery_max_motion_deg
//                                                      -> kLargeMotion
//   recovering and strict_inliers / valid < min(recovery_min_inlier_ratio, typical - 0.05)
//                                                      -> kFewInliers
//     (strict: |r| <= inlier delta; typical: running mean of the volume's tracked calls. There
//     is no relocalisation, so a re-acquired pose must fit at the inlier delta: the wider
//     radius let a pose 1.9 m / 89 deg off pass on tum-fr3-cabinet-keyframes)
//   balancedInverseCondition(H) < min_inverse_condition -> kDegenerate
//   finest level ended at max_iterations (lost_if_not_converged) -> kNotConverged
// A lost result still carries the estimate; the caller keeps its last good pose and does not
// integrate the frame. "Recovering": the previous track() call on the same volume (its
// VolumeDeviceView::volume_key, which survives growth) was lost; the stricter inlier rule then
// applies until a call succeeds (no relocalisation yet: a re-acquired pose near the last good one
// may be a wrong fit), and so does the recovery motion rule (SlamSystem starts a recovering call at
// the last good pose).
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "map/volume_view.h"
#include "map/voxel_layout.h"
#include "track/se3.h"
#include "track/track_options.h"

namespace emf::track {

/// The Gauss-Newton terms of E at one pose, unnormalised (confidence c_u = q_u * W, not divided
/// by max W). H and g use the translation-first increment ordering.
struct NormalEquations {
  Matrix6d H = Matrix6d::Zero();  // sum c h J J^T
  Vector6d g = Vector6d::Zero();  // sum c h J r   (metres)
  double cost = 0.0;              // sum c rho(r)  (metres^2)
  int valid = 0;                  // pixels whose point landed on observed map
  double inliers = 0.0;           // sum of q over those with |r| <= max(delta, noise z^2)
  int input = 0;                  // pixels with a valid vertex and q > 0
  double max_weight = 0.0;        // max W over the valid samples
  /// Compared with an earlier evaluation (per-pixel costs): sum over the pixels valid at both
  /// poses of (cost now - cost then), and their number. What LM uses to accept a step, so
  /// that points entering or leaving the observed map do not make E jump.
  double cost_change = 0.0;
  int common = 0;
  double strict_inliers = 0.0;  // sum of q over valid samples with |r| <= inlier delta (recovery)
  double valid_weight = 0.0;    // sum of q over the valid samples (the inlier shares' base)
};

/// CPU reference of the track_accumulate kernel (and its reduction), in double. `vertex`:
/// CV_32FC4 camera-frame points (w = 0 invalid); `q`: CV_32F weights or empty (= ones). Only
/// pixels (u, v) with u % stride == 0 and v % stride == 0 are used. `prev_cost` (CV_32FC2: cost,
/// weight c; cost NaN where invalid; optional) gives cost_change/common: the change of c rho(r)
/// or, with fixed_weights, of rho(r) weighted by the previous c (TrackOptions::step_acceptance);
/// `pixel_cost` (optional) receives each used pixel's (c rho(r), c) (cost NaN where not valid;
/// other pixels untouched). A point counts as an inlier when |r| <= max(inlier_delta_m,
/// inlier_noise_per_m2 * z^2), z its camera-frame depth (TrackOptions::inlier_noise_per_m2), and
/// as a strict inlier when |r| <= inlier_delta_m (TrackOptions::inlier_truncation_factor; < 0:
/// the Huber delta); both counts add its q.
NormalEquations accumulateReference(const map::VolumeHostView& volume, const cv::Mat& vertex,
                                    const cv::Mat& q, int stride,
                                    const Eigen::Isometry3d& T_volume_camera, double huber_delta_m,
                                    const cv::Mat* prev_cost = nullptr,
                                    cv::Mat* pixel_cost = nullptr, double inlier_noise_per_m2 = 0.0,
                                    bool fixed_weights = false, double inlier_delta_m = -1.0);

/// Pixels [x0, x1) x [y0, y1) of an image.
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  int area() const { return empty() ? 0 : (x1 - x0) * (y1 - y0); }
  cv::Rect toCv() const {
    return empty() ? cv::Rect(x0, y0, 0, 0) : cv::Rect(x0, y0, x1 - x0, y1 - y0);
  }
};

/// The pixels whose back-projected point can lie inside a volume's box [0, extent_m] (volume
/// frame; T_volume_camera maps camera points into it): the bounding rectangle of the 8 projected
/// corners widened by one pixel, clipped to the image. The whole image when a corner is not in
/// front of the camera (z <= 1 mm). Pixel (u, v) back-projects along ((u - cx) / fx,
/// (v - cy) / fy, 1), as the preprocessing does.
PixelRect volumeImageBounds(const Eigen::Vector3d& extent_m,
                            const Eigen::Isometry3d& T_volume_camera, const core::Intrinsics& k);

/// The same for any box of the volume frame (e.g. the grid cut to a claim region).
PixelRect boxImageBounds(const Eigen::AlignedBox3d& box, const Eigen::Isometry3d& T_volume_camera,
                         const core::Intrinsics& k);

/// Why a frame was declared lost (TrackResult::loss).
enum class TrackLoss {
  kNone = 0,
  kNoDepth,         // no pixel with valid depth and q > 0
  kFewValidPoints,  // too few points landed on the observed map (min_valid_fraction)
  kLargeMotion,     // the estimate left the initial pose's neighbourhood (max_motion_*)
  kFewInliers,      // residuals too large for too many points (min_inlier_ratio)
  kNotConverged,    // the finest level hit max_iterations (lost_if_not_converged)
  kDegenerate,      // the geometry does not constrain all 6 DoF (min_inverse_condition)
};
const char* trackLossName(TrackLoss loss);

struct TrackResult {
  /// Final estimate (also returned when lost: the caller keeps its last good pose).
  Eigen::Isometry3d T_volume_camera = Eigen::Isometry3d::Identity();
  int iterations = 0;              // LM iterations over all levels (one device evaluation each)
  bool converged = false;          // stopped by lm_eps / early_exit_step, not by max_iterations
  double cost = 0.0;               // final E (metres^2, confidence normalised by max W)
  double cost_per_valid = 0;       // cost / valid_pixels
  int valid_pixels = 0;            // finest level: pixels landing on observed map
  int input_pixels = 0;            // finest level: pixels with valid depth and q > 0
  double valid_fraction = 0;       // valid_pixels / input_pixels
  double inlier_ratio = 0;         // inliers / valid, q-weighted (depth-dependent inlier radius)
  double strict_inlier_ratio = 0;  // strict_inliers / valid, q-weighted (|r| <= inlier delta)
  double inverse_condition = 0;    // lambda_min / lambda_max of the balanced Hessian
  double motion_m = 0;             // |translation| of T_init^-1 T_final (camera frame), metres
  double motion_deg = 0;           // rotation angle of T_init^-1 T_final, degrees
  bool lost = false;
  TrackLoss loss = TrackLoss::kNone;
  std::string loss_reason;  // human-readable, names the rule and the numbers; empty if ok
};

/// Tracks poses against volumes for images of one size. Buffers are allocated at
/// construction; track() allocates nothing on the device. Not thread-safe (one per thread).
class Tracker {
 public:
  /// Throws ConfigError for inconsistent options, InvalidArgument for a bad image size.
  Tracker(cl::Context& ctx, const TrackOptions& options, int width, int height);

  /// Aligns the vertex map (float4 per pixel, camera frame, w = 0 invalid; width x height as
  /// constructed) to `volume`, starting from T_volume_camera_init. `q`: float per pixel
  /// association weights, or nullptr for all ones. `roi` (optional): only its pixels are
  /// evaluated; the caller guarantees q = 0 outside it (e.g. volumeImageBounds of an object at
  /// the E-step's pose), so the result is that of the whole image up to summation order, for
  /// work in proportion to the rectangle. `inputs` (optional): a rectangle outside which q = 0
  /// as well (e.g. em::EStep::claimedPixels, the bounding rectangle of the pixels with q > 0);
  /// the work-groups of roi's grid that lie wholly outside it are not launched. Those groups'
  /// sums are zero and the others hold the same pixels, so the result is the same to the bit.
  TrackResult track(const map::VolumeDeviceView& volume, cl_mem vertex_map, cl_mem q,
                    const Eigen::Isometry3d& T_volume_camera_init, const PixelRect* roi = nullptr,
                    const PixelRect* inputs = nullptr);

  /// One device evaluation of the normal equations at T (unnormalised, like
  /// accumulateReference). With compare_with_last, cost_change/common compare with the
  /// per-pixel costs of the previous evaluate() call (same stride, roi and inputs). `roi` and
  /// `inputs` as in track().
  NormalEquations evaluate(const map::VolumeDeviceView& volume, cl_mem vertex_map, cl_mem q,
                           const Eigen::Isometry3d& T_volume_camera, int stride,
                           bool compare_with_last = false, const PixelRect* roi = nullptr,
                           const PixelRect* inputs = nullptr);
  /// Per-pixel (cost, weight c) of the last evaluate() call (CV_32FC2; cost NaN where the sample
  /// was not valid; weight 0 unless step_acceptance is fixed_weights; pixels not sampled at that
  /// stride keep stale values). Blocking read; for tests.
  cv::Mat lastPixelCosts() const;

  /// True when the last track() call on the volume (VolumeDeviceView::volume_key) was lost.
  bool recovering(uint64_t volume_key) const;
  /// Drops what the tracker remembers of the volume (lost state, typical inlier ratio): call
  /// when the volume is freed or when its next call must not count as a recovery (a pose found
  /// by other means).
  void forget(uint64_t volume_key);
  /// Inlier ratio a recovering call on the volume must reach: recovery_min_inlier_ratio, at
  /// most the volume's typical (running) inlier ratio minus a margin.
  double recoveryInlierRatio(uint64_t volume_key) const;

  const TrackOptions& options() const { return options_; }
  int width() const { return width_; }
  int height() const { return height_; }
  /// Work-group size of the accumulation kernel and the number of groups used at `stride`
  /// (over the whole image, or over `roi`, less the groups outside `inputs`).
  static int localSize();
  int numGroups(int stride, const PixelRect* roi = nullptr,
                const PixelRect* inputs = nullptr) const;
  /// Local memory one work-group of the accumulation kernel uses on this device (bytes).
  size_t kernelLocalMemoryBytes() const;

 private:
  struct LevelResult {
    int iterations = 0;
    bool converged = false;
    double final_damping = 0.0;  // mu / max diag(H) at exit, the next level's tau
  };
  // LM on one level; at_T holds the evaluation at *T (its per-pixel costs in costs_[current_]).
  LevelResult runLevel(const map::VolumeDeviceView& volume, cl_mem vertex_map, cl_mem q, int stride,
                       int max_iterations, double tau, double inv_max_weight, Eigen::Isometry3d* T,
                       NormalEquations* at_T, const PixelRect* roi, const PixelRect* inputs,
                       const Eigen::Isometry3d& T_prior, double prior_scale);
  // Evaluates at T writing per-pixel costs to costs_[1 - current_], comparing with
  // costs_[current_] if `compare`. The caller swaps current_ to accept.
  NormalEquations evaluateCandidate(const map::VolumeDeviceView& volume, cl_mem vertex_map,
                                    cl_mem q, const Eigen::Isometry3d& T, int stride, bool compare,
                                    const PixelRect* roi, const PixelRect* inputs);
  // The sampled grid cells [su0, su1) x [sv0, sv1) at `stride` covering `roi` (or the image),
  // less the whole work-groups of that grid outside `inputs` (when given).
  struct GridRange {
    int su0 = 0, sv0 = 0, su1 = 0, sv1 = 0;
  };
  GridRange gridRange(int stride, const PixelRect* roi, const PixelRect* inputs) const;

  cl::Context& ctx_;
  TrackOptions options_;
  int width_;
  int height_;
  cl::KernelHandle accumulate_;
  cl::KernelHandle reduce_;
  cl::MemHandle partials_;
  cl::MemHandle reduced_;
  cl::MemHandle ones_;
  cl::MemHandle costs_[2];    // per-pixel costs: accepted (current_) and candidate
  cl::MemHandle weights_[2];  // per-pixel weights c, the same (step_acceptance fixed_weights)
  int current_ = 0;
  std::vector<float> host_partials_;
  std::vector<uint64_t> lost_volumes_;  // keys of volumes whose last call was lost
  std::map<uint64_t, double>
      typical_inliers_;  // running inlier ratio of each volume's tracked calls
};

/// Centre c about which rotations decouple best from translations for the information H of
/// left increments about the origin (least-squares zero of the coupling block of M H M^T,
/// M = centringMap(c)); for constraints spread evenly over the points, their centroid.
Eigen::Vector3d stiffnessCentre(const Matrix6d& H);
/// M = [[I, 0], [-[c]x, I]]: maps increments about the origin to increments about c
/// (J' = M J, H' = M H M^T, g' = M g; back: h = M^T h').
Matrix6d centringMap(const Eigen::Vector3d& c);

/// Inverse condition number of H after moving the rotation centre to stiffnessCentre(H) and
/// balancing: the rotation block is scaled so that its trace equals the translation block's.
/// Neither where the volume's origin lies nor the metres-vs-radians unit choice changes it.
double balancedInverseCondition(const Matrix6d& H);

}  // namespace emf::track
