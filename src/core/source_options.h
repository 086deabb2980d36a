// Options of frame sources (section `source`). URI query parameters override them.
#pragma once

#include <string>

#include "common/option_binder.h"

namespace emf::core {

struct SourceOptions {
  /// Source URI used when none is given on the command line.
  std::string uri = "synth:room?frames=300";
  /// Depth units per metre for uint16 depth images (TUM 5000, 7-Scenes 1000).
  double depth_scale = 5000.0;
  /// Intrinsics when the source does not provide them (0 = use the source's own).
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  /// Maximum timestamp difference when associating rgb and depth lists.
  double max_time_diff_s = 0.02;
  /// Stop after this many frames (0 = all).
  int max_frames = 0;
  /// Largest depth image accepted (width x height), checked when the source opens: 2048 x 2048.
  int max_pixels = 4194304;

  void bind(OptionBinder& b) {
    b.text("uri", uri, "default source URI (tum:, cofusion:, klg:, synth:, openni2:, v4l2:)");
    b.real("depth_scale", depth_scale, 1.0, 1e6, "units/m", "uint16 depth units per metre");
    b.real("fx", fx, 0.0, 1e5, "px", "focal length x (0 = from source)");
    b.real("fy", fy, 0.0, 1e5, "px", "focal length y (0 = from source)");
    b.real("cx", cx, 0.0, 1e5, "px", "principal point x (0 = from source)");
    b.real("cy", cy, 0.0, 1e5, "px", "principal point y (0 = from source)");
    // Strictly less than it associates (as associate.py), so 0 would never match.
    b.real("max_time_diff_s", max_time_diff_s, 1e-6, 1.0, "s",
           "max rgb/depth timestamp difference when associating");
    b.integer("max_frames", max_frames, 0, 100000000, "frames", "stop after N frames (0 = all)");
    b.integer("max_pixels", max_pixels, 1, 268435456, "pixels",
              "largest depth image accepted (width x height)");
  }
};

}  // namespace emf::core
