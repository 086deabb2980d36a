// Test helpers of the track module: host-built voxel-block volumes (from an analytic SDF or
// from a simple CPU TSDF fusion of depth images), their upload to the device, an analytic
// room-corner scene with boxes that is ray cast into depth images, and small pose helpers.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "map/volume_view.h"
#include "map/voxel_layout.h"

namespace emf::test {

/// A volume owning its index grid and its own voxel pool (host memory).
struct HostVolume {
  Eigen::Vector3i dims_blocks{0, 0, 0};
  float voxel_size_m = 0.01f;
  float truncation_m = 0.1f;
  std::vector<int32_t> index;      // -1 = unallocated
  std::vector<map::Voxel> voxels;  // slot * kBlockVoxels + local

  HostVolume(const Eigen::Vector3i& dims, float voxel_size, float truncation);
  map::VolumeHostView view() const;
  /// Allocates block b (block coordinates) if needed; returns its slot.
  int allocate(const Eigen::Vector3i& b);
  int allocatedBlocks() const { return static_cast<int>(voxels.size()) / map::kBlockVoxels; }
  Eigen::Vector3f extentM() const {
    return dims_blocks.cast<float>() * map::kBlockSize * voxel_size_m;
  }
};

/// Signed distance (metres, positive in free space) at a point of the volume frame.
using SdfFunction = std::function<float(const Eigen::Vector3f&)>;

/// Fills a volume from an analytic SDF: blocks whose centre lies within truncation + the block's
/// half diagonal of the surface are allocated; their voxels get tsdf = clamp(sdf / truncation)
/// and `weight`.
HostVolume volumeFromSdf(const SdfFunction& sdf, const Eigen::Vector3i& dims_blocks,
                         float voxel_size, float truncation, float weight);

/// Simple CPU reference TSDF fusion (projective distance, running average, weight cap) of one
/// depth image (CV_32F metres, NaN invalid) seen from T_volume_camera. Allocates the blocks
/// within truncation of the observed surface along each pixel's ray.
void fuseDepth(HostVolume* volume, const cv::Mat& depth_m, const core::Intrinsics& intrinsics,
               const Eigen::Isometry3d& T_volume_camera, float max_weight);

/// The volume's buffers on the device and the view kernels take.
struct DeviceVolume {
  cl::MemHandle index;
  cl::MemHandle voxels;
  map::VolumeDeviceView view;
};
DeviceVolume upload(cl::Context& ctx, const HostVolume& volume);

/// An analytic scene: half-space walls and axis-aligned boxes, SDF and exact ray casting.
struct AnalyticScene {
  struct Plane {
    Eigen::Vector3f normal;  // unit, pointing into free space
    float offset;            // free space where normal . x - offset > 0
  };
  struct Box {
    Eigen::Vector3f center, half_extent;
  };
  std::vector<Plane> planes;  // free space is the intersection of their positive sides
  std::vector<Box> boxes;     // solid

  float sdf(const Eigen::Vector3f& x) const;
  /// Depth image (CV_32F metres, NaN where a ray hits nothing within max_depth) seen from
  /// T_volume_camera.
  cv::Mat render(const core::Intrinsics& intrinsics, const Eigen::Isometry3d& T_volume_camera,
                 float max_depth = 8.0f) const;
};

/// Room corner (left wall, floor, back wall) with three boxes inside a 2.56 m cube: constrains
/// all 6 DoF.
AnalyticScene roomCornerScene();
/// Camera looking into roomCornerScene's corner (T_volume_camera).
Eigen::Isometry3d roomCornerCamera();
/// Camera pose at `eye` looking at `target` (y of the camera close to +y of the volume).
Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

/// 320x240 pinhole camera (fx = fy = 262.5).
core::Intrinsics smallCamera();
/// Kinect-like 640x480 camera (f 525 px, centre 319.5, 239.5), as the TUM RGB-D frames.
core::Intrinsics kinectCamera();

/// Random unit vector.
Eigen::Vector3d randomUnit(std::mt19937& rng);

/// Reads a TUM-style uint16 depth PNG into CV_32F metres (0 -> NaN).
cv::Mat readDepthPng(const std::string& path, double depth_scale);
/// Reads `tx ty tz qx qy qz qw` (camera-to-world) from a text file.
Eigen::Isometry3d readPoseTxt(const std::string& path);

}  // namespace emf::test
