// The one fixed-memory voxel-block pool every volume draws from
// (docs/architecture.md#memory-one-fixed-pool; policy in docs/memory.md).
//
// At construction the pool makes ONE device allocation of `map.memory_mb` holding fixed-size
// slots of kBlockVoxels short2 voxels (2 KiB each), plus a device free list (one int per slot)
// and a 16-byte state. A slot holds either the TSDF block of a volume (short2 per voxel) or the
// foreground/background count block of an object volume (ushort2 (Fg, Bg) per voxel, bit-cast
// into the same short2 array). Slots are taken on the device by the allocation kernel
// (kernels_cl/map_alloc.cl) and returned when a volume is cleared or destroyed; a slot is zeroed
// when it is returned, so a taken slot is always clean. Nothing is allocated afterwards.
//
// Exhaustion: allocation takes what fits and counts the blocks that found no slot (per frame and
// in total); those blocks stay unmapped (their measurements are not integrated) and are tried
// again the next time they are needed. Nothing is evicted, nothing already mapped changes.
//
// Not thread-safe: one pool belongs to one SLAM thread (its context's in-order queue).
#pragma once

#include <cstddef>
#include <cstdint>

#include "cl/context.h"
#include "map/map_options.h"

namespace emf::map {

/// Occupancy and drop counters of the pool.
struct PoolStats {
  int capacity_slots = 0;      // slots in the pool
  int free_slots = 0;          // slots on the free list
  int used_slots = 0;          // capacity - free
  int64_t dropped_blocks = 0;  // blocks that found no slot, summed over all allocations
  int dropped_last = 0;        // blocks that found no slot in the last allocation
  size_t pool_bytes = 0;       // bytes of the voxel allocation
  double occupancy() const {
    return capacity_slots ? static_cast<double>(used_slots) / capacity_slots : 0.0;
  }
};

class VoxelPool {
 public:
  /// Bytes of one slot (one 8^3 block of 4-byte voxels).
  static constexpr size_t kSlotBytes = 2048;
  /// Largest slot count the 32-bit voxel index of voxel_access.clh can address.
  static constexpr int kMaxSlots = (2147483647 / 512) - 1;

  /// A pool of map.memory_mb MiB on ctx's device. Throws ConfigError (naming map.memory_mb)
  /// when the budget exceeds what the device can allocate in one buffer or what the 32-bit
  /// voxel index addresses, ResourceError when the allocation fails.
  VoxelPool(cl::Context& ctx, const MapOptions& options);
  /// A pool of exactly `capacity_slots` slots (tests, small budgets).
  VoxelPool(cl::Context& ctx, const MapOptions& options, int capacity_slots);
  VoxelPool(const VoxelPool&) = delete;
  VoxelPool& operator=(const VoxelPool&) = delete;

  cl::Context& context() const { return ctx_; }
  const MapOptions& options() const { return options_; }
  int capacitySlots() const { return capacity_; }
  /// Device voxel array: slot s holds voxels [s * kBlockVoxels, (s + 1) * kBlockVoxels).
  const cl::MemHandle& voxels() const { return voxels_; }
  const cl::MemHandle& freeList() const { return free_list_; }
  const cl::MemHandle& state() const { return state_; }
  /// A one-float device buffer bound where a kernel's optional image is absent.
  const cl::MemHandle& dummy() const { return dummy_; }

  /// Counters (the free count is read from the device: one 4-byte blocking read).
  PoolStats stats() const;

  /// Called by Volume after each allocation: accumulates the drop counters.
  void recordAllocation(int dropped);

 private:
  void init();

  cl::Context& ctx_;
  MapOptions options_;
  int capacity_ = 0;
  cl::MemHandle voxels_;     // capacity_ * kBlockVoxels short2
  cl::MemHandle free_list_;  // capacity_ int: the free slots are entries [0, free_count)
  cl::MemHandle state_;      // int[4]: free_count, and per-allocation scratch counters
  cl::MemHandle dummy_;
  int64_t dropped_total_ = 0;
  int dropped_last_ = 0;
};

}  // namespace emf::map
