// CPU ray caster of analytic scenes: exact depth (z along the optical axis, metres), shaded
// colour, instance ids and incidence angles for one camera pose. Primitives are culled to the
// image rectangle their projected bounding box covers, then intersected in closed form (rounded
// boxes sphere-traced) into a z-buffer; rows are split over std::threads. Deterministic: the
// output does not depend on the number of threads.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "core/frame.h"
#include "synth/scene.h"

namespace emf::synth {

/// The synthetic camera: fx = fy = 525, cx = 319.5, cy = 239.5 at 640x480 (Kinect-like), scaled
/// to width x height with Intrinsics::scaled.
core::Intrinsics defaultIntrinsics(int width, int height);

struct RenderOptions {
  int width = 640, height = 480;
  /// Pinhole camera; when not valid(), defaultIntrinsics(width, height).
  core::Intrinsics intrinsics;
  /// Worker threads (0 = hardware concurrency, at most 8).
  int threads = 0;
  /// Surfaces closer than this along the ray parameter (z-depth, metres) are ignored.
  double near_m = 0.01;
};

struct RenderOutput {
  cv::Mat depth;          // CV_32F z-depth in metres, NaN where no surface
  cv::Mat color;          // CV_8UC3 BGR: albedo x (ambient + key light + head light)
  cv::Mat instance_ids;   // CV_16U: 0 = static scene or nothing, k = SceneObject::id k
  cv::Mat cos_incidence;  // CV_32F |cos| of the angle between viewing ray and surface normal
};

class Renderer {
 public:
  explicit Renderer(const RenderOptions& options);
  const core::Intrinsics& intrinsics() const { return K_; }

  /// Renders `scene` seen from T_world_camera (camera-to-world) with the objects at
  /// T_world_objects (same order as scene.objects). Throws InvalidArgument on a size mismatch.
  void render(const Scene& scene, const Eigen::Isometry3d& T_world_camera,
              const std::vector<Eigen::Isometry3d>& T_world_objects, RenderOutput* out) const;

 private:
  RenderOptions options_;
  core::Intrinsics K_;
};

}  // namespace emf::synth
