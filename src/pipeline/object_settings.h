// Every option the objects derive from the configuration, stated in one place: which track.*
// and preprocess.* values object tracking takes from the camera's and which it replaces
// (docs/configuration.md#objects), the object rules' pixel thresholds at the frame's size, and
// the geometry of the visibility casts.
#pragma once

#include <opencv2/core.hpp>

#include "core/frame.h"
#include "em/em_options.h"
#include "pipeline/config.h"
#include "track/track_options.h"

namespace emf::pipeline {

/// The preprocessing of the depth the E-step and the objects use (objects.filter_depth).
track::PreprocessOptions objectPreprocessOptions(const Config& config);

/// The tracking options for object volumes: the camera's (track section) with the object rules
/// below, objects.huber_truncation_factor, objects.track_early_exit_step and the rotation prior
/// objects.motion_prior_rotation (scaled from 640x480 to an image `image_width` pixels wide).
track::TrackOptions objectTrackOptions(const Config& config, int image_width);

/// The tracking options of the re-identification fits: objectTrackOptions without the motion
/// rules and the rotation prior (a fit starts from a guess).
track::TrackOptions reidTrackOptions(const Config& config, int image_width);

/// `o` with its pixel thresholds (given for 640x480 images) scaled to an image `scale` times as
/// wide: lengths with the scale, areas with its square.
em::ObjectOptions scaledPixelThresholds(em::ObjectOptions o, double scale);

/// What ObjectLifecycle works with, derived once from the configuration and the camera.
struct ObjectSettings {
  em::ObjectOptions rules;              // objects.*, pixel thresholds at the frame's size
  em::ObjectOptions visibility_rules;   // the same at the visibility cast's size
  track::TrackOptions track;            // objectTrackOptions
  track::TrackOptions reid_track;       // reidTrackOptions
  track::PreprocessOptions preprocess;  // objectPreprocessOptions
  /// The visibility rule's cast: the camera at objects.visibility_width (at most the frame's).
  core::Intrinsics visibility_k;
  /// The leaving test's cast (objects.leaving_fraction): the frame at half its resolution in
  /// the middle of a cast of the frame's size, twice its field of view across; wide_frame is
  /// the frame's rectangle in it.
  core::Intrinsics wide_k;
  cv::Rect wide_frame;
};
ObjectSettings deriveObjectSettings(const Config& config, const core::Intrinsics& intrinsics);

}  // namespace emf::pipeline
