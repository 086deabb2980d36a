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

VolumeHostData copyBlocks(const VolumeHostAccess& access, const Volume::BlockFilter& keep) {
  const VolumeHostView& v = access.view();
  VolumeHostData out;
  out.dims_blocks = v.dims_blocks;
  out.voxel_size_m = v.voxel_size_m;
  out.truncation_m = v.truncation_m;
  out.T_world_volume = access.T_world_volume();
  out.T_volume_initial = access.T_volume_initial();
  const int n = v.dims_blocks.x() * v.dims_blocks.y() * v.dims_blocks.z();
  out.index.assign(static_cast<size_t>(n), -1);
  if (v.count_index) out.count_index.assign(static_cast<size_t>(n), -1);
  const auto take = [&](int32_t slot) {
    const int32_t compact = static_cast<int32_t>(out.voxels.size() / kBlockVoxels);
    const Voxel* from = v.voxels + static_cast<int64_t>(slot) * kBlockVoxels;
    out.voxels.insert(out.voxels.end(), from, from + kBlockVoxels);
    out.pool_slots.push_back(-1);  // not known through a view
    return compact;
  };
  for (int i = 0; i < n; ++i) {
    const bool has = v.index[i] >= 0 || (v.count_index && v.count_index[i] >= 0);
    if (!has || !keep(blockCoords(v.dims_blocks, i))) continue;
    if (v.index[i] >= 0) out.index[static_cast<size_t>(i)] = take(v.index[i]);
    if (v.count_index && v.count_index[i] >= 0) {
      out.count_index[static_cast<size_t>(i)] = take(v.count_index[i]);
    }
  }
  return out;
}

VolumeHostAccess::~VolumeHostAccess() = default;
VolumeHostAccess::VolumeHostAccess(VolumeHostAccess&&) noexcept = default;

}  // namespace emf::map
