// Block allocation in the voxel-block pool (docs/memory.md#per-frame).
//
// Per frame and volume:
//   mark_blocks          per pixel (EMF_W per work item): marks every block that the pixel's ray
//                        crosses within +-truncation of the measured depth (3-D DDA over blocks;
//                        plain stores of 1, no atomics; the flag after the grid's is scratch).
//   assign_blocks        one work-item per EMF_ASSIGN_GROUP grid blocks (a group without a mark
//                        is skipped after one 16-byte read unless integrate_all; one atomic per
//                        group appends its listed blocks): a marked block without a slot takes one
//                        from the top of the device free list (one atomic per new block); when
//                        the free list cannot serve it, the block is counted as dropped and stays
//                        unallocated. Marked (or, with integrate_all, every) allocated block is
//                        appended to the volume's block list for integration; with phases > 1 a
//                        marked block only in its phase ((x + y + z) mod phases == phase) or when
//                        it got its slot now. Clears the marks.
//   finalize_allocation  one work-item: pops the granted slots off the free list, publishes the
//                        frame's report and resets the per-frame counters.
// Volume life cycle:
//   release_blocks       one work-item per grid block: pushes the block's slots back on the free
//                        list and zeroes their voxels (so a slot is always clean when taken).
//   reindex_blocks       one work-item per block of a grown or shifted grid: copies the old
//                        slot entry shifted by whole blocks (voxels are not copied).
//   evict_blocks         one work-item per grid block: releases the blocks a shift of the grid
//                        by whole blocks moves out of it (a background following the camera).
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
#define EMF_VOL_REPORT 4     // report: list, allocated, dropped, new, outside (5 ints from here)
#define EMF_VOL_OUTSIDE 9    // pixels whose measured surface lies outside the grid (this frame)

// Depths beyond this (metres) are ignored: keeps block coordinates far inside int range.
#define EMF_MAX_MARK_DEPTH 1000.0f

// mark_blocks runs EMF_W pixels of a row per work item, in the lanes of floatW vectors (PoCL
// keeps the one-pixel-per-item form scalar); the DDA steps all lanes together until the last
// one is done. Per lane the operations and the cell sequence are those of one pixel:
//   segment [max(d - truncation, 0), d + truncation] along the pixel's ray (z-depth), in block
//   units; visit the blocks it crosses (3-D DDA), marking those inside the grid. Pixels whose
//   measured surface (depth d) lies outside the grid are counted (a moving background follows
//   the camera only when it sees past the grid).
// Only the pixels of `rect` (x0, y0, width, height; inside the image) are visited: the whole
// image, or the rectangle an object's grid projects to (no other pixel's segment reaches it);
// of those, every `stride`-th pixel in x and y from the rectangle's corner.
// Only the blocks in [mark_lo, mark_hi) (block coordinates, inside the grid) are marked: the
// whole grid, or the part of an object's grid its E-step can give pixels to.
// Launch ceil(ceil(rect width / stride) / EMF_W) x ceil(rect height / stride) work items.
__kernel void mark_blocks(__global const float* depth, const int width, const int4 rect,
                          const int stride, const float fx, const float fy, const float cx,
                          const float cy, const float4 r0, const float4 r1, const float4 r2,
                          const float block_size, const float truncation, const int4 dims,
                          const int4 mark_lo, const int4 mark_hi, __global uchar* needed,
                          __global int* volume_state) {
  const int x0 = rect.x + get_global_id(0) * EMF_W * stride;
  const int y = rect.y + get_global_id(1) * stride;
  const int x_end = rect.x + rect.z;
  if (x0 >= x_end || y >= rect.y + rect.w) return;
  const intW xs = (intW)(x0) + EMF_LANE_IDS * stride;
  const intW in_row = xs < x_end;
  const intW xr = in_row ? xs : x0;  // lanes past the row end read their row's first pixel
  floatW d;
#define EMF_MARK_READ(l) d.s##l = depth[y * width + xr.s##l];
  EMF_LANES(EMF_MARK_READ)
#undef EMF_MARK_READ
  intW alive = in_row & !isnan(d) & (d > 0.0f) & (d <= EMF_MAX_MARK_DEPTH);
  if (!any(alive)) return;
  // emf_pixel_ray, emf_transform and the DDA set-up of the scalar form, per lane.
  const floatW rx = (convert_floatW(xs) - cx) / fx;
  const float ry = ((float)y - cy) / fy;
  const floatW z0 = alive ? fmax(d - truncation, 0.0f) : 0.0f;
  const floatW z1 = alive ? d + truncation : 0.0f;
  const floatW ax0 = rx * z0, ay0 = ry * z0, az0 = 1.0f * z0;
  const floatW ax1 = rx * z1, ay1 = ry * z1, az1 = 1.0f * z1;
  const floatW ax = (r0.x * ax0 + r0.y * ay0 + r0.z * az0 + r0.w) / block_size;
  const floatW ay = (r1.x * ax0 + r1.y * ay0 + r1.z * az0 + r1.w) / block_size;
  const floatW az = (r2.x * ax0 + r2.y * ay0 + r2.z * az0 + r2.w) / block_size;
  const floatW bx = (r0.x * ax1 + r0.y * ay1 + r0.z * az1 + r0.w) / block_size;
  const floatW by = (r1.x * ax1 + r1.y * ay1 + r1.z * az1 + r1.w) / block_size;
  const floatW bz = (r2.x * ax1 + r2.y * ay1 + r2.z * az1 + r2.w) / block_size;
  {
    const floatW sd = alive ? d : 0.0f;
    const floatW qx = (r0.x * (rx * sd) + r0.y * (ry * sd) + r0.z * sd + r0.w) / block_size;
    const floatW qy = (r1.x * (rx * sd) + r1.y * (ry * sd) + r1.z * sd + r1.w) / block_size;
    const floatW qz = (r2.x * (rx * sd) + r2.y * (ry * sd) + r2.z * sd + r2.w) / block_size;
    const intW outside = alive & ((qx < 0.0f) | (qy < 0.0f) | (qz < 0.0f) | (qx >= (float)dims.x) |
                                  (qy >= (float)dims.y) | (qz >= (float)dims.z));
    int n = 0;
#define EMF_MARK_OUTSIDE(l) n -= outside.s##l;
    EMF_LANES(EMF_MARK_OUTSIDE)
#undef EMF_MARK_OUTSIDE
    if (n > 0) atomic_add(&volume_state[EMF_VOL_OUTSIDE], n);
  }
  const floatW dx = bx - ax, dy = by - ay, dz = bz - az;
  intW cx_b = convert_intW(floor(ax)), cy_b = convert_intW(floor(ay));
  intW cz_b = convert_intW(floor(az));
  const intW ex = convert_intW(floor(bx)), ey = convert_intW(floor(by));
  const intW ez = convert_intW(floor(bz));
  const intW sx = dx > 0.0f ? 1 : (dx < 0.0f ? -1 : 0);
  const intW sy = dy > 0.0f ? 1 : (dy < 0.0f ? -1 : 0);
  const intW sz = dz > 0.0f ? 1 : (dz < 0.0f ? -1 : 0);
  floatW tx = sx != 0 ? (convert_floatW(cx_b + (sx > 0 ? 1 : 0)) - ax) / dx : INFINITY;
  floatW ty = sy != 0 ? (convert_floatW(cy_b + (sy > 0 ? 1 : 0)) - ay) / dy : INFINITY;
  floatW tz = sz != 0 ? (convert_floatW(cz_b + (sz > 0 ? 1 : 0)) - az) / dz : INFINITY;
  const floatW tdx = sx != 0 ? convert_floatW(sx) / dx : INFINITY;
  const floatW tdy = sy != 0 ? convert_floatW(sy) / dy : INFINITY;
  const floatW tdz = sz != 0 ? convert_floatW(sz) / dz : INFINITY;
  const intW max_cells = convert_intW(abs(ex - cx_b) + abs(ey - cy_b) + abs(ez - cz_b)) + 1;
  for (int n = 0; any(alive); ++n) {
    alive &= (intW)(n) < max_cells;
    const intW mark = alive & (cx_b >= mark_lo.x) & (cy_b >= mark_lo.y) & (cz_b >= mark_lo.z) &
                      (cx_b < mark_hi.x) & (cy_b < mark_hi.y) & (cz_b < mark_hi.z);
    // Every lane stores, without a branch per lane (the lanes leave their cells at random, and
    // mispredicted branches cost more than the stores): lanes that mark nothing write the flag
    // past the grid's (needed holds dims.x * dims.y * dims.z + 1 flags).
    const intW lin =
        mark ? cx_b + dims.x * (cy_b + dims.y * cz_b) : (intW)(dims.x * dims.y * dims.z);
#define EMF_MARK_STORE(l) needed[lin.s##l] = 1;
    EMF_LANES(EMF_MARK_STORE)
#undef EMF_MARK_STORE
    // Axis of the nearest block face (ties: x before y before z), as in the scalar form.
    const intW kx = (tx <= ty) & (tx <= tz);
    const intW ky = !kx & (ty <= tz);
    const intW kz = !kx & !ky;
    const floatW t_near = kx ? tx : (ky ? ty : tz);
    alive &= !(t_near > 1.0f);
    cx_b += (alive & kx) ? sx : 0;
    cy_b += (alive & ky) ? sy : 0;
    cz_b += (alive & kz) ? sz : 0;
    tx = (alive & kx) ? tx + tdx : tx;
    ty = (alive & ky) ? ty + tdy : ty;
    tz = (alive & kz) ? tz + tdz : tz;
  }
}

// Grid blocks per assign_blocks work item: their flags are one 16-byte word (needed holds whole
// groups, the scratch flag included).
#define EMF_ASSIGN_GROUP 16

__kernel void assign_blocks(__global uchar* needed, __global int* index, __global int* count_index,
                            const int has_counts, const int block_count, const int4 dims,
                            const int integrate_all, const int phases, const int phase,
                            __global const int* free_list, __global int* pool_state,
                            __global int* volume_state, __global int* block_list) {
  const int first = get_global_id(0) * EMF_ASSIGN_GROUP;
  if (first >= block_count) return;
  if (!integrate_all) {
    const uint4 flags = vload4(0, (__global const uint*)(needed + first));
    if ((flags.x | flags.y | flags.z | flags.w) == 0) return;  // no block of the group marked
  }
  int listed[EMF_ASSIGN_GROUP];
  int n_listed = 0;
  const int last = min(first + EMF_ASSIGN_GROUP, block_count);
  for (int i = first; i < last; ++i) {
    const int need = needed[i];
    if (need) needed[i] = 0;
    int slot = index[i];
    const int fresh = need && slot < 0;
    if (fresh) {
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
    int in_phase = 1;
    if (phases > 1 && !fresh) {
      const int4 b = emf_block_coords(dims, i);
      in_phase = (b.x + b.y + b.z) % phases == phase;
    }
    if (slot >= 0 && ((need && in_phase) || integrate_all)) listed[n_listed++] = i;
  }
  if (n_listed > 0) {
    const int at = atomic_add(&volume_state[EMF_VOL_LIST], n_listed);
    for (int k = 0; k < n_listed; ++k) block_list[at + k] = listed[k];
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
  volume_state[EMF_VOL_REPORT + 4] = volume_state[EMF_VOL_OUTSIDE];
  volume_state[EMF_VOL_OUTSIDE] = 0;
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

// Blocks b with b - shift outside [0, dims) leave the grid when its origin moves by `shift`
// blocks: their slots go back on the free list (zeroed) and the volume's allocated count drops.
__kernel void evict_blocks(__global int* index, const int4 dims, const int4 shift,
                           __global int* free_list, __global int* pool_state,
                           __global short2* voxels, __global int* volume_state) {
  const int i = get_global_id(0);
  if (i >= dims.x * dims.y * dims.z) return;
  const int slot = index[i];
  if (slot < 0) return;
  const int4 b = emf_block_coords(dims, i) - shift;
  if (b.x >= 0 && b.y >= 0 && b.z >= 0 && b.x < dims.x && b.y < dims.y && b.z < dims.z) return;
  emf_release_slot(free_list, pool_state, voxels, slot);
  index[i] = -1;
  atomic_dec(&volume_state[EMF_VOL_ALLOCATED]);
}
