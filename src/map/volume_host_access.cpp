#include "map/volume_host_access.h"

#include "cl/context.h"
#include "cl/mapped_read.h"
#include "map/voxel_pool.h"

namespace emf::map {

VolumeHostAccess::VolumeHostAccess(const Volume& volume, const Volume::BlockFilter& keep)
    : VolumeHostAccess(volume, true, keep) {}

VolumeHostAccess VolumeHostAccess::downloaded(const Volume& volume,
                                              const Volume::BlockFilter& keep) {
  return VolumeHostAccess(volume, false, keep);
}

VolumeHostAccess::VolumeHostAccess(const Volume& volume, bool allow_mapping,
                                   const Volume::BlockFilter& keep)
    : T_world_volume_(volume.T_world_volume()), T_volume_initial_(volume.T_volume_initial()) {
  const VoxelPool& pool = volume.pool();
  const cl::Context& ctx = pool.context();
  // Mapped only on CPU devices, whose buffers are host memory: there a map costs nothing. An
  // integrated GPU may copy a buffer that was not allocated for host access on map, and the
  // pool would be copied whole; there the used blocks are downloaded instead.
  mapped_ = allow_mapping && ctx.device().type == "cpu" && ctx.device().host_unified_memory;
  if (!mapped_) {
    copy_ = std::make_unique<VolumeHostData>(volume.download(keep));
    view_ = copy_->view();
    return;
  }
  const VolumeSpec& spec = volume.spec();
  const size_t index_bytes = static_cast<size_t>(spec.blockCount()) * sizeof(int32_t);
  index_ = std::make_unique<cl::MappedRead>(ctx, volume.index(), index_bytes);
  if (spec.has_counts) {
    count_index_ = std::make_unique<cl::MappedRead>(ctx, volume.countIndex(), index_bytes);
  }
  const size_t pool_bytes = static_cast<size_t>(pool.capacitySlots()) * VoxelPool::kSlotBytes;
  voxels_ = std::make_unique<cl::MappedRead>(ctx, pool.voxels(), pool_bytes);
  view_.index = static_cast<const int32_t*>(index_->data());
  view_.count_index = count_index_ ? static_cast<const int32_t*>(count_index_->data()) : nullptr;
  view_.voxels = static_cast<const Voxel*>(voxels_->data());
  view_.dims_blocks = spec.dims_blocks;
  view_.voxel_size_m = spec.voxel_size_m;
  view_.truncation_m = spec.truncation_m;
}

VolumeHostAccess::~VolumeHostAccess() = default;
VolumeHostAccess::VolumeHostAccess(VolumeHostAccess&&) noexcept = default;

}  // namespace emf::map
