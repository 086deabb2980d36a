// Block allocation in the voxel-block pool (ARCHITECTURE.md "Memory: one fixed pool").
//
// Per frame and volume:
//   mark_blocks          one work-item per pixel: marks every block that the pixel's ray crosses
//                        within +-truncation of the measured depth (3-D DDA over blocks; plain
//                        stores of 1, no atomics).
//   assign_blocks        one work-item per grid block: a marked block without a slot takes one
//                        from the top of the device free list (one atomic per new block); when
//                        the free list cannot serve it, the block is counted as dropped and stays
//                        unallocated. Marked (or, with integrate_all, every) allocated block is
//                        appended to the volume's block list for integration. Clears the marks.
//   finalize_allocation  one work-item: pops the granted slots off the free list, publishes the
//                        frame's report and resets the per-frame counters.
// Volume life cycle:
//   release_blocks       one work-item per grid block: pushes the block's slots back on the free
//                        list and zeroes their voxels (so a slot is always clean when taken).
//   reindex_blocks       one work-item per block of a grown grid: copies the old slot entry
//                        shifted by whole blocks (voxels are not copied).
#include "map_common.clh"

// Pool state (int[4]).
#define EMF_POOL_FREE 0     // slots on the free list
#define EMF_POOL_TAKEN 1    // free-list positions handed out in this allocation (scratch)
#define EMF_POOL_GRANTED 2  // slots actually taken in this allocation (scratch)
#define EMF_POOL_DROPPED 3  // blocks that found no slot in this allocation (scratch)

// Volume state (int[8]): counters, then the report of the last allocation.
#define EMF_VOL_LIST 0       // blocks in the integration list
#define EMF_VOL_ALLOCATED 1  // blocks with a slot
#define EMF_VOL_DROPPED 2    // marked blocks that found no slot (this allocation)
#define EMF_VOL_NEW 3        // blocks that got a slot (this allocation)
#define EMF_VOL_REPORT 4     // report: list, allocated, dropped, new (4 ints from here)

// Depths beyond this (metres) are ignored: keeps block coordinates far inside int range.
#define EMF_MAX_MARK_DEPTH 1000.0f

__kernel void mark_blocks(__global const float* depth, const int width, const int height,
                          const float fx, const float fy, const float cx, const float cy,
                          const float4 r0, const float4 r1, const float4 r2, const float block_size,
                          const float truncation, const int4 dims, __global uchar* needed) {
  const int x = get_global_id(0);
  const int y = get_global_id(1);
  if (x >= width || y >= height) return;
  const float d = depth[y * width + x];
  if (!emf_is_valid(d) || d <= 0.0f || d > EMF_MAX_MARK_DEPTH) return;
  const float3 ray = emf_pixel_ray(x, y, fx, fy, cx, cy);
  const float z0 = fmax(d - truncation, 0.0f);
  const float z1 = d + truncation;
  // Segment ends in block units of the volume frame.
  const float3 a = emf_transform(r0, r1, r2, ray * z0) / block_size;
  const float3 b = emf_transform(r0, r1, r2, ray * z1) / block_size;
  const float3 dir = b - a;
  int4 cell = (int4)((int)floor(a.x), (int)floor(a.y), (int)floor(a.z), 0);
  const int4 end = (int4)((int)floor(b.x), (int)floor(b.y), (int)floor(b.z), 0);
  const int4 step =
      (int4)(dir.x > 0.0f ? 1 : (dir.x < 0.0f ? -1 : 0), dir.y > 0.0f ? 1 : (dir.y < 0.0f ? -1 : 0),
             dir.z > 0.0f ? 1 : (dir.z < 0.0f ? -1 : 0), 0);
  // Ray parameter (0..1 along the segment) of the next block face per axis, and per block.
  float3 t_max = (float3)(INFINITY, INFINITY, INFINITY);
  float3 t_delta = (float3)(INFINITY, INFINITY, INFINITY);
  if (step.x != 0) {
    t_max.x = ((float)(cell.x + (step.x > 0 ? 1 : 0)) - a.x) / dir.x;
    t_delta.x = (float)step.x / dir.x;
  }
  if (step.y != 0) {
    t_max.y = ((float)(cell.y + (step.y > 0 ? 1 : 0)) - a.y) / dir.y;
    t_delta.y = (float)step.y / dir.y;
  }
  if (step.z != 0) {
    t_max.z = ((float)(cell.z + (step.z > 0 ? 1 : 0)) - a.z) / dir.z;
    t_delta.z = (float)step.z / dir.z;
  }
  const int max_cells = abs(end.x - cell.x) + abs(end.y - cell.y) + abs(end.z - cell.z) + 1;
  for (int n = 0; n < max_cells; ++n) {
    if (cell.x >= 0 && cell.y >= 0 && cell.z >= 0 && cell.x < dims.x && cell.y < dims.y &&
        cell.z < dims.z) {
      needed[emf_block_linear(dims, cell)] = 1;
    }
    if (t_max.x <= t_max.y && t_max.x <= t_max.z) {
      if (t_max.x > 1.0f) break;
      cell.x += step.x;
      t_max.x += t_delta.x;
    } else if (t_max.y <= t_max.z) {
      if (t_max.y > 1.0f) break;
      cell.y += step.y;
      t_max.y += t_delta.y;
    } else {
      if (t_max.z > 1.0f) break;
      cell.z += step.z;
      t_max.z += t_delta.z;
    }
  }
}

__kernel void assign_blocks(__global uchar* needed, __global int* index, __global int* count_index,
                            const int has_counts, const int block_count, const int integrate_all,
                            __global const int* free_list, __global int* pool_state,
                            __global int* volume_state, __global int* block_list) {
  const int i = get_global_id(0);
  if (i >= block_count) return;
  const int need = needed[i];
  if (need) needed[i] = 0;
  int slot = index[i];
  if (need && slot < 0) {
    const int k = has_counts ? 2 : 1;
    const int t = atomic_add(&pool_state[EMF_POOL_TAKEN], k);
    const int free_count = pool_state[EMF_POOL_FREE];  // constant during this kernel
    if (t + k <= free_count) {
      slot = free_list[free_count - 1 - t];
      index[i] = slot;
      if (has_counts) count_index[i] = free_list[free_count - 2 - t];
      atomic_add(&pool_state[EMF_POOL_GRANTED], k);
      atomic_inc(&volume_state[EMF_VOL_NEW]);
    } else {
      atomic_inc(&pool_state[EMF_POOL_DROPPED]);
      atomic_inc(&volume_state[EMF_VOL_DROPPED]);
    }
  }
  if (slot >= 0 && (need || integrate_all)) {
    block_list[atomic_inc(&volume_state[EMF_VOL_LIST])] = i;
  }
}

__kernel void finalize_allocation(__global int* pool_state, __global int* volume_state) {
  if (get_global_id(0) != 0) return;
  // Granted free-list positions are exactly [0, granted): ranges are handed out in increasing
  // order and only the first that does not fit (and all after it) fail.
  pool_state[EMF_POOL_FREE] -= pool_state[EMF_POOL_GRANTED];
  pool_state[EMF_POOL_TAKEN] = 0;
  pool_state[EMF_POOL_GRANTED] = 0;
  pool_state[EMF_POOL_DROPPED] = 0;
  volume_state[EMF_VOL_ALLOCATED] += volume_state[EMF_VOL_NEW];
  volume_state[EMF_VOL_REPORT + 0] = volume_state[EMF_VOL_LIST];
  volume_state[EMF_VOL_REPORT + 1] = volume_state[EMF_VOL_ALLOCATED];
  volume_state[EMF_VOL_REPORT + 2] = volume_state[EMF_VOL_DROPPED];
  volume_state[EMF_VOL_REPORT + 3] = volume_state[EMF_VOL_NEW];
  volume_state[EMF_VOL_LIST] = 0;
  volume_state[EMF_VOL_DROPPED] = 0;
  volume_state[EMF_VOL_NEW] = 0;
}

inline void emf_release_slot(__global int* free_list, __global int* pool_state,
                             __global short2* voxels, int slot) {
  free_list[atomic_inc(&pool_state[EMF_POOL_FREE])] = slot;
  __global short2* v = voxels + slot * EMF_BLOCK_VOXELS;
  for (int k = 0; k < EMF_BLOCK_VOXELS; ++k) v[k] = (short2)(0, 0);
}

__kernel void release_blocks(__global int* index, __global int* count_index, const int has_counts,
                             const int block_count, __global int* free_list,
                             __global int* pool_state, __global short2* voxels) {
  const int i = get_global_id(0);
  if (i >= block_count) return;
  const int slot = index[i];
  if (slot >= 0) {
    emf_release_slot(free_list, pool_state, voxels, slot);
    index[i] = -1;
  }
  if (has_counts) {
    const int cslot = count_index[i];
    if (cslot >= 0) {
      emf_release_slot(free_list, pool_state, voxels, cslot);
      count_index[i] = -1;
    }
  }
}

__kernel void reindex_blocks(__global const int* old_index, const int4 old_dims,
                             __global int* new_index, const int4 new_dims, const int4 offset) {
  const int i = get_global_id(0);
  if (i >= new_dims.x * new_dims.y * new_dims.z) return;
  const int4 b = emf_block_coords(new_dims, i) - offset;
  int slot = -1;
  if (b.x >= 0 && b.y >= 0 && b.z >= 0 && b.x < old_dims.x && b.y < old_dims.y &&
      b.z < old_dims.z) {
    slot = old_index[emf_block_linear(old_dims, b)];
  }
  new_index[i] = slot;
}
