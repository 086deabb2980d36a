#include "pipeline/object_settings.h"

#include <algorithm>
#include <cmath>

namespace emf::pipeline {

track::TrackOptions objectTrackOptions(const Config& config, int image_width) {
  track::TrackOptions o = config.track;
  o.huber_truncation_factor = config.objects.huber_truncation_factor;
  o.early_exit_step = config.objects.track_early_exit_step;
  // The data term grows with the pixel count: the prior, given for 640x480, with the area.
  const double area_scale = (image_width / 640.0) * (image_width / 640.0);
  o.prior_rotation_weight = config.objects.motion_prior_rotation * area_scale;
  // An object volume is mostly unobserved space around the object, and every pixel inside it
  // has some association q > 0: the fraction of pixels landing on observed map says nothing
  // about the object. Its loss is judged by inliers, conditioning, motion and convergence.
  o.min_valid_fraction = 0.0;
  // A small object's inliers are fewer and its silhouette pixels land off the model more
  // often than the background's: the camera's stricter inlier rules would drop good frames.
  o.min_inlier_ratio = std::min(o.min_inlier_ratio, 0.5);
  o.recovery_min_inlier_ratio = o.min_inlier_ratio;
  // A lost object is tried again from its prediction or its last place while it keeps moving
  // (a tumble, a spin): within the camera's recovery bound of that start it stayed lost until
  // retired. Its motion is judged by the bound of every call (docs/method.md#object-tracking).
  o.recovery_max_motion_m = o.max_motion_m;
  o.recovery_max_motion_deg = o.max_motion_deg;
  // Objects cover few pixels: all of them are used at the finest level.
  o.pixel_stride = 1;
  // Rotations about the object's own points: the camera is metres away from a small object, and
  // rotations about a far centre couple rotation and translation
  // (docs/method.md#object-tracking).
  o.rotation_centre = track::RotationCentre::kStiffness;
  // The map-confidence weight W(p) varies strongly across a small, partly observed model:
  // accepting steps by the cost change made LM crawl and stall at the prediction
  // (TrackOptions::step_acceptance).
  o.step_acceptance = track::StepAcceptance::kFixedWeights;
  return o;
}

track::TrackOptions reidTrackOptions(const Config& config, int image_width) {
  track::TrackOptions o = objectTrackOptions(config, image_width);
  // A fit starts from a guess (a heading step, the detection's centroid): how far it moves says
  // nothing; the fit is judged by its inliers and overlap (object_reid.cpp). The motion prior
  // would pull towards the guess.
  o.max_motion_m = 100.0;
  o.max_motion_deg = 180.0;
  o.prior_rotation_weight = 0.0;
  return o;
}

track::PreprocessOptions objectPreprocessOptions(const Config& config) {
  track::PreprocessOptions o = config.preprocess;
  if (!config.objects.filter_depth) {
    o.bilateral_radius_px = config.objects.depth_filter_radius_px;
    o.sigma_depth_m = config.objects.depth_filter_sigma_m;
    // The objects' range sigma stays fixed: growing it with depth as the camera's blends
    // silhouettes at low resolution (docs/method.md#preprocessing).
    o.sigma_depth_per_m2 = 0.0;
    o.hole_margin_px = config.objects.depth_hole_margin_px;
  }
  return o;
}

em::ObjectOptions scaledPixelThresholds(em::ObjectOptions o, double scale) {
  o.min_detection_px = static_cast<int>(std::lround(o.min_detection_px * scale));
  o.visibility_border_px = static_cast<int>(std::lround(o.visibility_border_px * scale));
  o.invisible_min_px = static_cast<int>(std::lround(o.invisible_min_px * scale * scale));
  return o;
}

ObjectSettings deriveObjectSettings(const Config& config, const core::Intrinsics& intrinsics) {
  ObjectSettings s;
  s.rules = scaledPixelThresholds(config.objects, intrinsics.width / 640.0);
  s.track = objectTrackOptions(config, intrinsics.width);
  s.reid_track = reidTrackOptions(config, intrinsics.width);
  s.preprocess = objectPreprocessOptions(config);
  const int frame_width = intrinsics.width;
  const int vis_width = config.objects.visibility_width > 0
                            ? std::min(config.objects.visibility_width, frame_width)
                            : frame_width;
  const int vis_height =
      std::max(1, static_cast<int>(std::lround(static_cast<double>(intrinsics.height) * vis_width /
                                               frame_width)));
  s.visibility_k = vis_width == frame_width ? intrinsics : intrinsics.scaled(vis_width, vis_height);
  s.visibility_rules = scaledPixelThresholds(config.objects, vis_width / 640.0);
  const int inner_w = std::max(1, intrinsics.width / 2),
            inner_h = std::max(1, intrinsics.height / 2);
  s.wide_frame = cv::Rect((intrinsics.width - inner_w) / 2, (intrinsics.height - inner_h) / 2,
                          inner_w, inner_h);
  s.wide_k = intrinsics.scaled(inner_w, inner_h);
  s.wide_k.cx += s.wide_frame.x;
  s.wide_k.cy += s.wide_frame.y;
  s.wide_k.width = intrinsics.width;
  s.wide_k.height = intrinsics.height;
  return s;
}

}  // namespace emf::pipeline
