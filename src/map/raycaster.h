// Ray casting of several volumes into one depth / normal / volume-id image
// (kernels_cl/raycast.cl). Output buffers are allocated once for a maximum image size.
//
// Outputs (device, row-major, width x height of the intrinsics passed to render()):
//   depth    float, camera z in metres of the nearest surface of all volumes, NaN = none
//   normals  float4, unit normal in the camera frame pointing to the free side, NaN = none
//   ids      int, the id given with the volume that owns the pixel, -1 = none
// An object volume (with counts) renders a surface point only where p_fg > 0.5 there and
// nothing of any rendered volume is nearer on the ray (the masks used to match detections).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "map/map_options.h"
#include "map/volume.h"

namespace emf::map {

/// One volume to render and the id its pixels get.
struct RenderItem {
  const Volume* volume = nullptr;
  int id = 0;
  /// A hit of this volume replaces what earlier items rendered unless it is more than this far
  /// behind it (metres of camera z). Render the background first with 0, then objects with a
  /// margin (objects.render_margin_m), so an object wins against the background's copy of its
  /// surface.
  float depth_margin_m = 0.0f;
};

/// Tile edge (pixels) of the per-tile depth ranges that let rays skip empty space
/// (EMF_RAY_TILE in kernels_cl/raycast.cl).
constexpr int kRayTile = 16;

class RayCaster {
 public:
  RayCaster(cl::Context& ctx, const MapOptions& options, int max_width, int max_height);

  /// Renders `volumes` seen from T_world_camera with intrinsics k (<= the capacity).
  void render(const std::vector<RenderItem>& volumes, const core::Intrinsics& k,
              const Eigen::Isometry3d& T_world_camera);

  const cl::MemHandle& depth() const { return depth_; }
  const cl::MemHandle& normals() const { return normals_; }
  const cl::MemHandle& ids() const { return ids_; }
  /// Downloads the last render (CV_32F depth, CV_32FC3 normals, CV_32S ids); any may be null.
  void download(cv::Mat* depth, cv::Mat* normals, cv::Mat* ids) const;
  /// The per-tile camera-z ranges of the last volume rendered (tests; allocates).
  void downloadTileRanges(std::vector<float>* z_min, std::vector<float>* z_max) const;

 private:
  cl::Context& ctx_;
  MapOptions options_;
  int max_width_, max_height_;
  int width_ = 0, height_ = 0;
  int tiles_x_ = 0, tiles_y_ = 0;
  cl::MemHandle depth_, normals_, ids_, tile_min_, tile_max_;
  cl::KernelHandle clear_, clear_bounds_, bounds_, cast_;
};

/// Samples psi, weight, gradient and p_fg of a volume at N points (kernels_cl/sdf_sample.cl).
class SdfSampler {
 public:
  explicit SdfSampler(cl::Context& ctx);
  /// points: float4 (volume frame, metres), count entries. Outputs as in sdf_sample.cl.
  void sample(const Volume& volume, const cl::MemHandle& points, int count,
              const cl::MemHandle& psi, const cl::MemHandle& weight, const cl::MemHandle& gradient,
              const cl::MemHandle& pfg);

 private:
  cl::Context& ctx_;
  cl::KernelHandle kernel_;
};

}  // namespace emf::map
