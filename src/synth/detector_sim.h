// A simulated instance-segmentation detector (Mask R-CNN-like) driven by rendered instance ids:
// imperfect masks (random erosion/dilation of the boundary, a small shift, ragged edges), about
// 10 % of visible objects missed, occasional false positives (blobs with a plausible class),
// scores in [0.5, 1] and detection ids 1..n in shuffled order (never tied to object ids).
// Deterministic per (seed, frame).
#pragma once

#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/frame.h"

namespace emf::synth {

struct DetectorSimOptions {
  /// The detector runs on frames whose index is a multiple of this (0 = never).
  int every_n_frames = 30;
  /// Probability that a visible object is not detected.
  double miss_rate = 0.1;
  /// Probability of one false-positive blob on a detection frame.
  double false_positive_rate = 0.15;
  /// Boundary erosion/dilation radius drawn from [-max, max] pixels at 640 px width (scaled).
  int max_boundary_px = 3;
  /// Mask shift drawn from [-max, max] pixels per axis at 640 px width (scaled).
  int max_shift_px = 2;
  /// Fraction of boundary pixels flipped before a 3x3 median (ragged edges).
  double boundary_flip_prob = 0.3;
  /// Scores of true detections are uniform in [true_score_min, 1]; false positives in
  /// [0.5, false_score_max].
  double true_score_min = 0.7;
  double false_score_max = 0.75;
  /// Probability that a detection reports a confusable class instead of the object's own
  /// (confusedClass(): a car as a truck, a teddy bear as a dog, a chair as a couch, ...).
  double confusion_rate = 0.0;
  /// Probability that a mask spills grossly onto its surroundings: dilated by 6-12 % of its
  /// box's larger side.
  double spill_rate = 0.0;
  /// Probability that a mask covers only part of the object: cut by a random line through
  /// its box, keeping 50-80 % of it.
  double partial_rate = 0.0;
  /// Results this many frames late: the detections reported on a detection frame f describe
  /// frame f - late_frames (applied by the synthetic source; 0 = on time).
  int late_frames = 0;
  /// Classes false positives are drawn from.
  std::vector<std::string> false_positive_classes{"chair", "cup",          "bottle",
                                                  "book",  "potted plant", "tv"};
};

/// Detections for one frame from its instance-id image (CV_16U, 0 = background).
/// `class_by_object` maps object ids to class names (objects absent from it are ignored);
/// objects covering fewer than minVisiblePixels() pixels are not detected. When
/// `object_of_detection` is given it receives, per returned detection, the object id it came
/// from (0 for a false positive) — ground truth for tests.
std::vector<core::Detection> simulateDetections(const cv::Mat& instance_ids,
                                                const std::map<int, std::string>& class_by_object,
                                                uint64_t seed, int64_t frame_index,
                                                const DetectorSimOptions& options,
                                                std::vector<int>* object_of_detection = nullptr);

/// The class a detector may confuse `class_name` with (itself when none is listed).
std::string confusedClass(const std::string& class_name);

/// True when the detector runs on this frame.
inline bool isDetectionFrame(int64_t frame_index, const DetectorSimOptions& options) {
  return options.every_n_frames > 0 && frame_index % options.every_n_frames == 0;
}

}  // namespace emf::synth
