// Read-only host access to a volume for mesh extraction and other whole-volume reads on the
// host. On a CPU device (PoCL; CL_DEVICE_HOST_UNIFIED_MEMORY) the index grids and the voxel pool
// are mapped, not copied: a 20000-block background is 41 MiB of voxels that Volume::download()
// would duplicate. On other devices (GPUs, integrated ones included: their map of a buffer not
// allocated for host access may copy the whole pool) the volume's used blocks are downloaded
// (VolumeHostData, compact).
//
// Hold it only between frames: the volume must not be changed while it lives (the mapped
// buffers are the live ones), and the queue is used from the calling thread.
#pragma once

#include <Eigen/Geometry>
#include <memory>

#include "map/volume.h"
#include "map/voxel_layout.h"

namespace emf::cl {
class MappedRead;
}

namespace emf::map {

class VolumeHostAccess {
 public:
  /// Maps (CPU device) or downloads `volume`; a download reads only the blocks `keep` accepts
  /// when it is given (a mapping shows them all). Throws ClError / ResourceError.
  explicit VolumeHostAccess(const Volume& volume, const Volume::BlockFilter& keep = {});
  /// Always downloads (tests compare both ways).
  static VolumeHostAccess downloaded(const Volume& volume, const Volume::BlockFilter& keep = {});
  ~VolumeHostAccess();
  VolumeHostAccess(VolumeHostAccess&&) noexcept;
  VolumeHostAccess& operator=(VolumeHostAccess&&) = delete;
  VolumeHostAccess(const VolumeHostAccess&) = delete;
  VolumeHostAccess& operator=(const VolumeHostAccess&) = delete;

  /// Index grids and voxels; valid while this object lives.
  const VolumeHostView& view() const { return view_; }
  const Eigen::Isometry3d& T_world_volume() const { return T_world_volume_; }
  /// See Volume::T_volume_initial().
  const Eigen::Isometry3d& T_volume_initial() const { return T_volume_initial_; }
  /// True when the device buffers are mapped, false when they were copied.
  bool mapped() const { return mapped_; }

 private:
  VolumeHostAccess(const Volume& volume, bool allow_mapping, const Volume::BlockFilter& keep);

  VolumeHostView view_;
  Eigen::Isometry3d T_world_volume_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_volume_initial_ = Eigen::Isometry3d::Identity();
  bool mapped_ = false;
  std::unique_ptr<cl::MappedRead> index_, count_index_, voxels_;  // when mapped
  std::unique_ptr<VolumeHostData> copy_;                          // when downloaded
};

/// A compact host copy of the blocks of `access` that `keep` accepts (the others read as
/// unallocated): what a worker thread meshes after the volume has changed. On a CPU device a
/// memcpy of those blocks from the mapped pool.
VolumeHostData copyBlocks(const VolumeHostAccess& access, const Volume::BlockFilter& keep);

}  // namespace emf::map
