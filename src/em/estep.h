// The E-step of the EM loop (docs/method.md#e-step; kernels_cl/estep.cl): association weights
// q_i(u) of every pixel to every volume (background i = 0, objects 1..N), plus the residual
// |psi| of the best-associated volume per pixel (the feedback the motion detector reads).
//
// A volume is seen through its device view and the pose of the camera in its frame,
// T_volume_camera. Buffers for up to `max_volumes` volumes are allocated at construction;
// compute() allocates no device memory. Not thread-safe (one SLAM thread).
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "cl/context.h"
#include "em/em_options.h"
#include "map/volume_view.h"
#include "map/voxel_layout.h"

namespace emf::em {

struct EStepCover;  // estep.cpp: the object rectangles the background pass samples exactly

/// A claim region that bounds nothing.
constexpr float kUnboundedClaim = 1e30f;

/// The part of a volume's grid a volume may claim pixels in (volume frame, metres; objects:
/// ObjectOptions::claim_region). Points outside it are treated as outside the volume.
struct ClaimBox {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(-kUnboundedClaim);
  Eigen::Vector3f hi = Eigen::Vector3f::Constant(kUnboundedClaim);
  /// lo <= p < hi on every axis (the grid's own test).
  bool contains(const Eigen::Vector3f& p) const {
    return (p.array() >= lo.array()).all() && (p.array() < hi.array()).all();
  }
};

/// One volume as the E-step reads it.
struct EStepVolume {
  map::VolumeDeviceView view;
  cl_mem count_index = nullptr;  // objects: the count-block index grid; nullptr = p_fg 1
  Eigen::Isometry3d T_volume_camera = Eigen::Isometry3d::Identity();
  ClaimBox claim;
  /// Objects: the pixels whose points can fall in the grid (and claim box), e.g. the
  /// projection of the grid's box (track::volumeImageBounds); the likelihood is evaluated only
  /// there and q is 0 elsewhere (an empty rectangle: nowhere). Unset = the whole image. The
  /// background always takes the whole image.
  std::optional<cv::Rect> pixels;
};

/// The same on the host, for the CPU reference.
struct EStepHostVolume {
  map::VolumeHostView view;  // view.count_index set for objects
  Eigen::Isometry3d T_volume_camera = Eigen::Isometry3d::Identity();
  ClaimBox claim;
};

/// Likelihood p(u | i) of one camera-frame point for one volume (0 outside its grid or its
/// claim box), the CPU mirror of estep_likelihood_lanes (per lane). *abs_psi receives |psi| used
/// (NaN outside).
float associationLikelihood(const EStepHostVolume& volume, const Eigen::Vector3f& p_camera,
                            const EmOptions& options, float* abs_psi);

/// CPU reference of a whole E-step. `vertex` CV_32FC4 (camera frame, w = 0 invalid). Returns
/// q per volume (CV_32F, same size); `residual` (optional) gets |psi| of the volume with the
/// largest likelihood (NaN where none).
std::vector<cv::Mat> eStepReference(const std::vector<EStepHostVolume>& volumes,
                                    const cv::Mat& vertex, const EmOptions& options,
                                    cv::Mat* residual = nullptr);

class EStep {
 public:
  /// Throws InvalidArgument for a bad size or max_volumes < 1.
  EStep(cl::Context& ctx, const EmOptions& options, int width, int height, int max_volumes);

  /// Computes q for `volumes` (at most max_volumes; [0] is the background) from the vertex map
  /// (float4 per pixel, camera frame, w = 0 invalid). Enqueues only; q(i) / residual() are
  /// ready for kernels enqueued after it on the same queue.
  /// Without `residual_everywhere` the background's SDF is sampled only where an object's
  /// pixels reach, as q does not depend on it elsewhere, and residual() is unspecified.
  /// `same_objects`: the caller vouches that the object volumes have not changed since the last
  /// compute() (no integration in between; the frame's second E-step, which moves only the
  /// background). When their views, poses, claim boxes and rectangles and the vertex map are
  /// also those of the last call (checked), their likelihoods are reused instead of sampled
  /// again (not with `residual_everywhere`). q is the same either way, to the bit.
  void compute(cl_mem vertex_map, const std::vector<EStepVolume>& volumes,
               bool residual_everywhere = true, bool same_objects = false);
  /// Whether the last compute() reused the objects' likelihoods (tests).
  bool reusedObjects() const { return reused_; }

  /// q of the background alone, at the pixels whose x and y are multiples of `stride` (the
  /// camera tracker's samples at its track.pixel_stride): there it equals compute()'s q(0) to the
  /// bit; elsewhere q(0) is unspecified, and the objects' q keep what compute() gave them. The
  /// objects' likelihoods are sampled over their whole rectangles: a next compute() with
  /// `same_objects` reuses them. Enqueues only. Throws InvalidArgument for too many volumes or a
  /// stride below 1.
  void computeBackgroundWeights(cl_mem vertex_map, const std::vector<EStepVolume>& volumes,
                                int stride);

  /// q of volume i of the last compute() (float per pixel).
  const cl::MemHandle& q(int i) const { return q_.at(static_cast<size_t>(i)); }
  /// |psi| of the best-associated volume per pixel (float, NaN = none) after a compute() with
  /// residual_everywhere.
  const cl::MemHandle& residual() const { return residual_; }
  /// Number of volumes whose q the last call gave (1 after computeBackgroundWeights()).
  int volumeCount() const { return count_; }
  int maxVolumes() const { return static_cast<int>(q_.size()); }

  /// The bounding rectangle of the pixels where q(i) > 0 (object i >= 1) after the last
  /// compute(); empty when there are none. Kept by the likelihood pass on the device; the first
  /// call after a compute() reads all volumes' rectangles back at once (one blocking read).
  /// Throws InvalidArgument for i outside 1 .. volumeCount() - 1 (every i after
  /// computeBackgroundWeights(), which gives no object's q).
  cv::Rect claimedPixels(int i);

  /// Blocking downloads (outputs, tests): CV_32F images of the frame size.
  cv::Mat downloadQ(int i) const;
  /// Rows row0 .. row0 + rows - 1 of q(i) (CV_32F, rows x width; throws for a bad range).
  cv::Mat downloadQRows(int i, int row0, int rows) const;
  cv::Mat downloadResidual() const;

 private:
  // rects_ (the image for the background, an object's pixels cut to the image) and keys_ of
  // `volumes`.
  void setRectsAndKeys(const std::vector<EStepVolume>& volumes);
  // One likelihood pass of volume i (0 = the background) over `grid` (first pixel x, y,
  // columns, rows of every stride-th pixel), and q_i's normalisation over one.
  void enqueueLikelihood(cl_mem vertex_map, const EStepVolume& v, int i, const cv::Rect& grid,
                         const EStepCover& cover, int stride);
  void enqueueNormalize(int i, const cv::Rect& grid, int stride);
  // Reads the claimed rectangles of volumes 0 .. n - 1 back (blocking), and decodes volume i's
  // (empty where its pass claimed nothing).
  void readClaimed(size_t n);
  cv::Rect decodeClaimed(size_t i) const;

  cl::Context& ctx_;
  EmOptions options_;
  int width_, height_;
  // What an object's likelihood pass depended on (compute()'s reuse test).
  struct ObjectKey {
    cl_mem index = nullptr, count_index = nullptr, voxels = nullptr;
    Eigen::Matrix<float, 3, 4> rows;
    Eigen::Vector3f claim_lo, claim_hi;
    cv::Rect rect;
    bool operator==(const ObjectKey& o) const {
      return index == o.index && count_index == o.count_index && voxels == o.voxels &&
             rows == o.rows && claim_lo == o.claim_lo && claim_hi == o.claim_hi && rect == o.rect;
    }
  };

  std::vector<cl::MemHandle> q_, likelihood_;
  cl::MemHandle sum_, best_, residual_;
  // Per volume (min x, min y, -max x, -max y) of its likelihood pass's pixels with a likelihood
  // above 0 (kernels_cl/estep.cl), and the host's copy once read after the last pass.
  cl::MemHandle claimed_;
  std::vector<cl_int> host_claimed_;
  bool claimed_read_ = false;
  cl::KernelHandle likelihood_lanes_, normalize_, clear_, accumulate_;
  std::vector<ObjectKey> last_objects_, keys_;
  cl_mem last_vertex_ = nullptr;
  bool reused_ = false;
  // Per q buffer: the rectangle outside which it holds 0 (the whole image until first written).
  std::vector<cv::Rect> written_;
  std::vector<cv::Rect> rects_;  // this compute()'s rectangles (kept between calls)
  int count_ = 0;
};

}  // namespace emf::em
