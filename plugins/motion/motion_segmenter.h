// The `motion` detector's segmentation: regions of the depth image that the SLAM's current
// models explain badly (high background SDF residual, low background association), bounded by
// depth discontinuities and seen in consecutive calls. Needs no trained model.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace emf_motion {

struct MotionOptions {
  // Defaults measured on the synthetic `cars` preset (toy cars ~12 cm tall, 2.4 m away, every
  // 5th frame): both cars found by frame 30 and no lasting false region (bench/objects_bench.sh).
  double strong_residual_m = 0.03;  // seed pixels: residual above this
  double weak_residual_m = 0.01;    // growth pixels: above this (hysteresis)
  // Pixels whose background_association is above this are explained by the background. The
  // host sets 1 for disocclusions (points behind the background's surface: what stood there
  // moved away) and caps the rest by the background's inlier posterior, which is above 0.99
  // only for residuals under ~0.2 mm: this default excludes disocclusions and leaves the
  // residual thresholds above in charge.
  double max_association = 0.99;
  double depth_jump_m = 0.03;  // + depth_jump_rel * depth: a discontinuity between neighbours
  double depth_jump_rel = 0.03;
  // Pixel sizes are for 640x480 images and scale with the image (area with width x height,
  // radii with the width), as the host's object thresholds do.
  int min_area_px = 1600;          // smaller regions are noise (40 x 40 px at 640x480)
  double max_area_fraction = 0.4;  // a larger region means the camera tracking failed
  int min_consecutive = 2;         // calls a region must persist before it is reported
  double persist_iou = 0.2;        // overlap linking a region to the previous call's
  int open_radius_px = 2;          // morphological opening of the seed mask (0 = off)

  /// Parses "key=value,key=value" (keys as above). Returns false and sets *error on bad input.
  bool parse(const std::string& config, std::string* error);
};

struct MotionRegion {
  cv::Mat mask;  // CV_8U 0/1, image size
  cv::Rect box;
  float score = 0;  // fraction of strong-residual pixels in the region
  int age = 1;      // consecutive calls this region has been seen
};

/// min_area_px scaled to an image of w x h pixels (at least 1).
int scaledMinArea(const MotionOptions& o, int w, int h);
/// open_radius_px scaled to an image w pixels wide (0 stays 0, otherwise at least 1).
int scaledOpenRadius(const MotionOptions& o, int w);

class MotionSegmenter {
 public:
  explicit MotionSegmenter(const MotionOptions& options) : options_(options) {}

  /// One call: depth CV_32F metres (NaN/0 invalid), residual CV_32F |psi| metres (NaN = the map
  /// has no value), association CV_32F q_0 or empty. Returns the regions persistent for
  /// min_consecutive calls.
  std::vector<MotionRegion> update(const cv::Mat& depth, const cv::Mat& residual,
                                   const cv::Mat& association);

  /// Candidate regions of the last call (persistent or not), for tests and debugging.
  const std::vector<MotionRegion>& candidates() const { return previous_; }

 private:
  std::vector<MotionRegion> segment(const cv::Mat& depth, const cv::Mat& residual,
                                    const cv::Mat& association) const;
  MotionOptions options_;
  std::vector<MotionRegion> previous_;
};

}  // namespace emf_motion
