// Read-only device view of one volume, as the kernels of other stages (tracking, E-step) take
// it: the buffers and geometry that kernels_cl/voxel_access.clh's emf_sample_sdf() needs.
// The map owns the buffers; a view only borrows them for the duration of a call.
#pragma once

#include <CL/cl.h>

#include <Eigen/Core>
#include <cstdint>

namespace emf::map {

struct VolumeDeviceView {
  /// int32 per block, dims_blocks.x * .y * .z entries (x fastest): pool slot or -1.
  cl_mem index = nullptr;
  /// Size of the index grid in blocks of kBlockSize^3 voxels.
  Eigen::Vector3i dims_blocks{0, 0, 0};
  /// The pool's voxel array (short2 per voxel, slot * kBlockVoxels + local index).
  cl_mem voxels = nullptr;
  /// Voxel edge length, metres. Voxel (i,j,k) has its centre at ((i,j,k) + 0.5) * voxel_size_m
  /// in the volume frame.
  float voxel_size_m = 0.01f;
  /// TSDF truncation distance, metres (stored TSDF values are psi / truncation_m).
  float truncation_m = 0.1f;
  /// The volume's Volume::key(): names it for state kept across frames (the tracker's
  /// recovery), unchanged when the volume grows and `index` is replaced. 0: not from a Volume.
  uint64_t volume_key = 0;
};

}  // namespace emf::map
