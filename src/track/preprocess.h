// Preprocessing of a depth frame (docs/method.md#preprocessing) on the device: range check,
// bilateral filter, back-projection to a vertex map. Host wrapper of kernels_cl/preprocess.cl and
// its CPU reference.
#pragma once

#include <limits>
#include <opencv2/core.hpp>

#include "cl/context.h"
#include "core/frame.h"
#include "track/track_options.h"

namespace emf::track {

/// Output of the CPU reference (same content as the device buffers).
struct PreprocessedFrame {
  cv::Mat depth_m;  // CV_32F filtered depth, metres, NaN = invalid
  cv::Mat vertex;   // CV_32FC4 camera-frame points (x, y, z, 1) in metres; (NaN x3, 0) invalid
  cv::Mat input_m;  // CV_32F the depth the map integrates (hole margin and range guard applied)
};

/// The largest depth of `depth_m` (CV_32F metres) within [min_depth_m, max_depth_m]; 0 when
/// there is none.
float maxDepthInRange(const cv::Mat& depth_m, const PreprocessOptions& options);
/// The range guard's limit on the filtered depth (PreprocessOptions::range_guard_per_m2): with
/// L = min(max_depth_m, frame_max_m), L - range_guard_per_m2 * L^2; INFINITY when the guard is
/// off.
float rangeGuardMaxDepth(const PreprocessOptions& options, float frame_max_m);

/// CPU reference of the drop_hole_margin kernel: `depth_m` (CV_32F) with every pixel within
/// `radius` (Chebyshev) of a pixel without depth (NaN or <= 0) set to NaN.
cv::Mat dropHoleMarginReference(const cv::Mat& depth_m, int radius);

/// CPU reference of the preprocessing (hole margin, then the preprocess_depth kernel with the
/// range guard from the largest depth of `depth_m`).
/// `depth_m`: CV_32F metres, NaN or 0 = invalid.
PreprocessedFrame preprocessReference(const cv::Mat& depth_m, const core::Intrinsics& intrinsics,
                                      const PreprocessOptions& options);

/// Checks the options once (ranges are checked by the config loader; this checks relations).
/// Throws ConfigError naming the keys.
void validatePreprocessOptions(const PreprocessOptions& options);

/// Device preprocessing for one image size. Buffers are allocated once at construction; run()
/// only enqueues work (nothing is allocated per frame).
///
/// `sample_stride` s > 1: only the pixels (u, v) with u and v multiples of s get a filtered depth
/// and a vertex (the same to the bit as at stride 1); the others stay invalid (NaN; vertex w 0).
/// For a reader that samples no other pixel, such as the camera tracker at its pixel_stride: at
/// s = 2 a quarter of the filtering. What the map integrates (inputDepth) is decided at every
/// pixel as at stride 1.
class Preprocessor {
 public:
  /// Throws InvalidArgument when the intrinsics are invalid or sample_stride < 1, ConfigError for
  /// bad options.
  Preprocessor(cl::Context& ctx, const PreprocessOptions& options,
               const core::Intrinsics& intrinsics, int sample_stride = 1);

  /// Copies `depth_m` (CV_32F metres, intrinsics' size) into the input buffer and runs the
  /// kernel (the range guard's frame limit from the largest depth of `depth_m`). Throws
  /// InvalidArgument naming the expected size/type on mismatch.
  void process(const cv::Mat& depth_m);
  /// The same with the range guard's frame limit given: `frame_max_m` = maxDepthInRange of
  /// `depth_m` (a caller that preprocesses one frame twice computes it once).
  void process(const cv::Mat& depth_m, float frame_max_m);
  /// Runs the hole margin and the filter on a device buffer of width * height floats (metres)
  /// already filled (read, not modified). `frame_max_m`: the largest valid depth in it, for
  /// the range guard (INFINITY: unknown, the guard uses max_depth_m).
  void process(cl_mem depth_m, float frame_max_m = std::numeric_limits<float>::infinity());

  /// float4 per pixel (camera frame, metres; w = 0 invalid), width * height, row-major.
  const cl::MemHandle& vertexMap() const { return vertex_; }
  /// float per pixel, filtered depth in metres (NaN invalid).
  const cl::MemHandle& filteredDepth() const { return filtered_; }
  /// What the map integrates: the input with the hole margin and the pixels the range guard
  /// dropped set to NaN, metres. With neither it is the input buffer of process(const cv::Mat&).
  const cl::MemHandle& inputDepth() const {
    return options_.range_guard_per_m2 > 0 ? guarded_ : filterInput();
  }

  /// Blocking read-back of the results (tests, debugging, exporters).
  PreprocessedFrame download() const;

  const core::Intrinsics& intrinsics() const { return intrinsics_; }
  int sampleStride() const { return stride_; }

 private:
  cl::Context& ctx_;
  PreprocessOptions options_;
  core::Intrinsics intrinsics_;
  int stride_;
  cl::KernelHandle kernel_;
  // Stride > 1 with the range guard: the guard at every pixel, in two separable passes.
  cl::KernelHandle guard_rows_kernel_, guard_kernel_;
  cl::MemHandle row_max_;  // the first pass's per-row window maxima and holes
  cl::KernelHandle margin_kernel_;
  cl::MemHandle input_;
  /// The depth the filter reads: the input, or without its hole margin.
  const cl::MemHandle& filterInput() const {
    return options_.hole_margin_px > 0 ? margin_ : input_;
  }

  cl::MemHandle margin_;   // the input without its hole margin (hole_margin_px > 0)
  cl::MemHandle guarded_;  // the filter's input without the guard's pixels (range guard on)
  cl::MemHandle filtered_;
  cl::MemHandle vertex_;
};

}  // namespace emf::track
