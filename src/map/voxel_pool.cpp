#include "map/voxel_pool.h"

#include <numeric>
#include <string>
#include <vector>

#include "cl/cl_error.h"
#include "common/error.h"
#include "common/log.h"
#include "map/voxel_layout.h"

namespace emf::map {

static_assert(VoxelPool::kSlotBytes == kBlockVoxels * sizeof(Voxel), "slot = one voxel block");

namespace {

int slotsForBudget(const cl::Context& ctx, const MapOptions& options) {
  const uint64_t bytes = static_cast<uint64_t>(options.memory_mb) << 20;
  const uint64_t slots = bytes / VoxelPool::kSlotBytes;
  if (slots > static_cast<uint64_t>(VoxelPool::kMaxSlots)) {
    throw ConfigError(
        "map.memory_mb = " + std::to_string(options.memory_mb) +
        " MiB is more than the 32-bit voxel index of the pool can address (" +
        std::to_string((static_cast<uint64_t>(VoxelPool::kMaxSlots) * VoxelPool::kSlotBytes) >>
                       20) +
        " MiB); lower map.memory_mb");
  }
  const uint64_t max_alloc = ctx.device().max_alloc_bytes;
  if (max_alloc > 0 && bytes > max_alloc) {
    throw ConfigError("map.memory_mb = " + std::to_string(options.memory_mb) + " MiB exceeds the " +
                      std::to_string(max_alloc >> 20) + " MiB the OpenCL device '" +
                      ctx.device().device_name +
                      "' can allocate in one buffer; lower map.memory_mb");
  }
  return static_cast<int>(slots);
}

}  // namespace

VoxelPool::VoxelPool(cl::Context& ctx, const MapOptions& options)
    : VoxelPool(ctx, options, slotsForBudget(ctx, options)) {}

VoxelPool::VoxelPool(cl::Context& ctx, const MapOptions& options, int capacity_slots)
    : ctx_(ctx), options_(options), capacity_(capacity_slots) {
  if (capacity_ < 1 || capacity_ > kMaxSlots) {
    throw ConfigError("map.memory_mb gives a voxel pool of " + std::to_string(capacity_) +
                      " slots; it needs between 1 and " + std::to_string(kMaxSlots) +
                      " slots of 2 KiB");
  }
  init();
}

void VoxelPool::init() {
  const size_t bytes = static_cast<size_t>(capacity_) * kSlotBytes;
  try {
    voxels_ = ctx_.buffer(CL_MEM_READ_WRITE, bytes);
    // Fail now, not in the first frame, if the device cannot back the allocation.
    const cl_short2 zero = {{0, 0}};
    EMF_CL_CHECK(clEnqueueFillBuffer(ctx_.queue(), voxels_.get(), &zero, sizeof(zero), 0, bytes, 0,
                                     nullptr, nullptr));
    ctx_.finish();
  } catch (const cl::ClError& e) {
    throw ResourceError("cannot allocate the voxel pool of " + std::to_string(bytes >> 20) +
                        " MiB (map.memory_mb) on '" + ctx_.device().device_name + "': " + e.what() +
                        "; lower map.memory_mb");
  }
  // Free list: slot capacity-1 at the bottom, so the first allocations take 0, 1, 2, ...
  std::vector<int32_t> free_list(static_cast<size_t>(capacity_));
  for (int i = 0; i < capacity_; ++i) free_list[static_cast<size_t>(i)] = capacity_ - 1 - i;
  free_list_ = ctx_.buffer(CL_MEM_READ_WRITE, free_list.size() * sizeof(int32_t), free_list.data());
  const int32_t state[4] = {capacity_, 0, 0, 0};
  state_ = ctx_.buffer(CL_MEM_READ_WRITE, sizeof(state), state);
  const float one = 1.0f;
  dummy_ = ctx_.buffer(CL_MEM_READ_ONLY, sizeof(one), &one);
  logInfo("voxel pool: ", capacity_, " blocks of 8^3 voxels, ", bytes >> 20, " MiB on ",
          ctx_.device().device_name);
}

PoolStats VoxelPool::stats() const {
  PoolStats s;
  int32_t free_count = 0;
  ctx_.read(state_, &free_count, sizeof(free_count));
  s.capacity_slots = capacity_;
  s.free_slots = free_count;
  s.used_slots = capacity_ - free_count;
  s.dropped_blocks = dropped_total_;
  s.dropped_last = dropped_last_;
  s.pool_bytes = static_cast<size_t>(capacity_) * kSlotBytes;
  return s;
}

void VoxelPool::recordAllocation(int dropped) {
  dropped_last_ = dropped;
  dropped_total_ += dropped;
}

}  // namespace emf::map
