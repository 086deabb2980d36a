// CPU references of the map kernels (kernels_cl/map_alloc.cl, tsdf_integrate.cl, raycast.cl),
// written against the host mirrors (map_math.h, voxel_layout.h) with the kernels' float
// operations in the same order. Slow and simple: for tests and for checking a device.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "map/map_math.h"
#include "map/map_options.h"
#include "map/volume.h"

namespace emf::map {

/// mark_blocks: 1 for every grid block within +-truncation_m of a valid depth along its pixel
/// ray, of every stride-th pixel in x and y. depth_m: CV_32F metres (NaN invalid).
std::vector<uint8_t> markBlocksReference(const cv::Mat& depth_m, const CameraF& cam,
                                         const PoseRows& T_volume_camera, float block_size_m,
                                         float truncation_m, const Eigen::Vector3i& dims_blocks,
                                         int stride = 1);

/// integrate_blocks on a host copy: integrates into the listed blocks (linear grid indices)
/// of `vol` in place. weights / fg_mask: CV_32F of the depth's size or empty (absent).
/// weight_scale multiplies every observation's weight (VolumeSpec::integrate_every).
void integrateReference(VolumeHostData& vol, const std::vector<int>& block_list,
                        const cv::Mat& depth_m, const cv::Mat& weights, const cv::Mat& fg_mask,
                        const CameraF& cam, const PoseRows& T_camera_volume, float max_weight,
                        bool free_space_full_weight, bool behind_dropoff = false,
                        float weight_scale = 1.0f);

/// The blocks integrate_blocks processes after an allocation: allocated in `vol` and marked
/// (or every allocated block when integrate_all), in grid order. With phases > 1 a marked block
/// only when (x + y + z) mod phases == phase or it had no slot before (`index_before`, the
/// volume's index before the allocation; VolumeSpec::integrate_every).
std::vector<int> blockListReference(const VolumeHostData& vol, const std::vector<uint8_t>& marked,
                                    bool integrate_all, int phases = 1, int phase = 0,
                                    const std::vector<int32_t>* index_before = nullptr);

/// One volume for raycastReference.
struct HostRenderItem {
  const VolumeHostData* volume = nullptr;
  int id = 0;
  float depth_margin_m = 0.0f;
};

/// Output of raycastReference (same conventions as RayCaster).
struct RaycastImages {
  cv::Mat depth;    // CV_32F, NaN = none
  cv::Mat normals;  // CV_32FC3, NaN = none
  cv::Mat ids;      // CV_32S, -1 = none
};

/// Per tile of kRayTile^2 pixels, the camera-z range [z_min, z_max] of the allocated blocks
/// whose projection covers it (z_min = inf, z_max = 0 where none does).
struct TileRanges {
  int tiles_x = 0;
  std::vector<float> z_min, z_max;
};

/// raycast_clear_bounds + raycast_bounds for one volume seen with T_camera_volume.
TileRanges tileRangesReference(const VolumeHostData& vol, const CameraF& cam,
                               const PoseRows& T_camera_volume, const MapOptions& options);

/// raycast_clear + raycast_bounds + raycast_volume_lanes for each item in order.
RaycastImages raycastReference(const std::vector<HostRenderItem>& volumes, const CameraF& cam,
                               const Eigen::Isometry3d& T_world_camera, const MapOptions& options);

}  // namespace emf::map
