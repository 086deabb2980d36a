// Ray casting of one or several volumes into a depth (camera z, metres), normal (camera frame,
// unit, pointing to the free side) and volume-id image. One pass per volume over the same
// outputs with a depth test: a pass writes a pixel only where its hit is nearer than what the
// previous passes wrote (plus depth_margin: objects rendered after the background win ties with
// the background's copy of the same surface), so after all passes every pixel shows the nearest
// surface of all volumes ("nothing nearer lies on the ray"). raycast_clear starts a render.
//
// Empty space is skipped at two levels. raycast_bounds projects every allocated block of the
// volume into the image and keeps, per tile of EMF_RAY_TILE^2 pixels, the camera-z range
// [min, max] of the blocks covering it (block corners; z along a ray through a convex block
// lies between its corners' z). Per pixel the ray (parameter t = camera z) is clipped to
// [near, far], to its tile's range, to the volume box and to the depth already written; tiles
// without blocks cost nothing. Along the ray, unallocated blocks are skipped whole (jump to the
// block exit); in allocated blocks the nearest voxel's psi gives the step
// max(voxel, step_fraction * psi) in front of surfaces and one voxel elsewhere. A sign change
// + -> - of consecutive observed samples is a surface: refined by two secant steps on the
// trilinear SDF, normal = normalised SDF gradient there. A hit is dropped (no surface from this
// volume on this pixel) when the trilinear SDF is unavailable at it, or, for object volumes,
// when p_fg <= 0.5 there (the surface belongs to the background seen through the object box).
#include "map_common.clh"

#define EMF_RAY_TILE 16  // pixels per tile edge of the depth-range image

__kernel void raycast_clear(__global float* depth, __global float4* normals, __global int* ids,
                            const int count) {
  const int i = get_global_id(0);
  if (i >= count) return;
  depth[i] = NAN;
  normals[i] = (float4)(NAN, NAN, NAN, 0.0f);
  ids[i] = -1;
}

/// Clips [t0, t1] to the slab 0 <= o + t d <= hi of one axis; false when the ray misses it.
inline bool emf_clip_slab(float o, float d, float hi, float* t0, float* t1) {
  if (d == 0.0f) return o >= 0.0f && o <= hi;
  const float ta = (0.0f - o) / d;
  const float tb = (hi - o) / d;
  *t0 = fmax(*t0, fmin(ta, tb));
  *t1 = fmin(*t1, fmax(ta, tb));
  return true;
}

/// Ray parameter where the ray leaves block b (block edge block_m metres; inv_d = 1 / d, used
/// only where d != 0), considering only faces ahead of t: a ray running exactly along a block
/// face (the image centre ray at a block border) must not stall on it.
inline float emf_block_exit(float3 o, float3 d, float3 inv_d, int4 b, float block_m, float t) {
  float te = INFINITY;
  float c;
  if (d.x != 0.0f) {
    c = ((float)(d.x > 0.0f ? b.x + 1 : b.x) * block_m - o.x) * inv_d.x;
    if (c > t) te = fmin(te, c);
  }
  if (d.y != 0.0f) {
    c = ((float)(d.y > 0.0f ? b.y + 1 : b.y) * block_m - o.y) * inv_d.y;
    if (c > t) te = fmin(te, c);
  }
  if (d.z != 0.0f) {
    c = ((float)(d.z > 0.0f ? b.z + 1 : b.z) * block_m - o.z) * inv_d.z;
    if (c > t) te = fmin(te, c);
  }
  return te;
}

/// Resets the depth-range tiles: min = +inf, max = 0 (as int bits; positive floats order like
/// their bit patterns, so atomic_min / atomic_max on ints order them as floats).
__kernel void raycast_clear_bounds(__global int* tile_min, __global int* tile_max,
                                   const int count) {
  const int i = get_global_id(0);
  if (i >= count) return;
  tile_min[i] = as_int(INFINITY);
  tile_max[i] = 0;
}

/// One work-item per grid block: widens the z range of every tile its projection covers.
/// r0..r2: T_camera_volume.
__kernel void raycast_bounds(__global const int* index, const int4 dims, const float block_m,
                             const float4 r0, const float4 r1, const float4 r2, const int width,
                             const int height, const float fx, const float fy, const float cx,
                             const float cy, const float near_z, const float far_z,
                             const int tiles_x, __global int* tile_min, __global int* tile_max) {
  const int i = get_global_id(0);
  if (i >= dims.x * dims.y * dims.z) return;
  if (index[i] < 0) return;
  const int4 b = emf_block_coords(dims, i);
  float z_lo = INFINITY, z_hi = 0.0f;
  float u_lo = INFINITY, u_hi = -INFINITY, v_lo = INFINITY, v_hi = -INFINITY;
  bool straddles = false;
  for (int n = 0; n < 8; ++n) {
    const float3 corner =
        (float3)((float)(b.x + (n & 1)) * block_m, (float)(b.y + ((n >> 1) & 1)) * block_m,
                 (float)(b.z + ((n >> 2) & 1)) * block_m);
    const float3 pc = emf_transform(r0, r1, r2, corner);
    z_lo = fmin(z_lo, pc.z);
    z_hi = fmax(z_hi, pc.z);
    if (pc.z <= near_z) {
      straddles = true;
    } else {
      const float u = fx * (pc.x / pc.z) + cx;
      const float v = fy * (pc.y / pc.z) + cy;
      u_lo = fmin(u_lo, u);
      u_hi = fmax(u_hi, u);
      v_lo = fmin(v_lo, v);
      v_hi = fmax(v_hi, v);
    }
  }
  if (z_hi <= near_z || z_lo >= far_z) return;
  int x0 = 0, x1 = width - 1, y0 = 0, y1 = height - 1;
  if (straddles) {
    z_lo = near_z;  // the block reaches the near plane: it may cover any pixel
  } else {
    if (u_hi < 0.0f || v_hi < 0.0f || u_lo > (float)(width - 1) || v_lo > (float)(height - 1)) {
      return;
    }
    // Here u_hi >= 0 and u_lo <= width - 1: clamping first keeps the conversions in range.
    x0 = (int)floor(fmax(u_lo, 0.0f));
    x1 = (int)ceil(fmin(u_hi, (float)(width - 1)));
    y0 = (int)floor(fmax(v_lo, 0.0f));
    y1 = (int)ceil(fmin(v_hi, (float)(height - 1)));
  }
  const int lo_bits = as_int(z_lo);
  const int hi_bits = as_int(z_hi);
  for (int ty = y0 / EMF_RAY_TILE; ty <= y1 / EMF_RAY_TILE; ++ty) {
    for (int tx = x0 / EMF_RAY_TILE; tx <= x1 / EMF_RAY_TILE; ++tx) {
      const int t = ty * tiles_x + tx;
      // Read first: most blocks do not change a tile, and atomics are costly on CPUs.
      if (tile_min[t] > lo_bits) atomic_min(&tile_min[t], lo_bits);
      if (tile_max[t] < hi_bits) atomic_max(&tile_max[t], hi_bits);
    }
  }
}

/// One volume's pass (see the top of this file) for EMF_W consecutive pixels of a row per work
/// item (x0 = EMF_W * item: inside one ray tile, EMF_W <= EMF_RAY_TILE), in floatW lanes: PoCL runs
/// a one-pixel-per-item form, whose loop length depends on the data, one pixel at a time. The lanes
/// march together until the last one is done; per lane the operations and their order are those of
/// one pixel's ray (the one-pixel form gave the same images to the bit). Launch ceil(width / EMF_W)
/// x height work items.
__kernel void raycast_volume_lanes(
    __global const int* index, __global const int* count_index, const int has_counts,
    const int4 dims, __global const short2* voxels, const float voxel_size, const float truncation,
    const float step_fraction, const float4 r0, const float4 r1, const float4 r2, const int width,
    const int height, const float fx, const float fy, const float cx, const float cy,
    const float near_z, const float far_z, const int volume_id, const float depth_margin,
    const int tiles_x, __global const int* tile_min, __global const int* tile_max,
    __global float* depth_out, __global float4* normal_out, __global int* id_out) {
  const int x0 = get_global_id(0) * EMF_W;
  const int y = get_global_id(1);
  if (x0 >= width || y >= height) return;
  const int tile = (y / EMF_RAY_TILE) * tiles_x + x0 / EMF_RAY_TILE;
  const float tile_lo = as_float(tile_min[tile]);
  if (!(tile_lo < INFINITY)) return;  // no block of the volume covers this tile
  const intW xs = (intW)(x0) + EMF_LANE_IDS;
  const intW in_row = xs < width;
  const int row = y * width;
  floatW current;
#define RCW_READ(l) current.s##l = in_row.s##l ? depth_out[row + xs.s##l] : NAN;
  EMF_LANES(RCW_READ)
#undef RCW_READ
  // emf_pixel_ray and emf_rotate per lane (ray.z = 1).
  const floatW rx = (convert_floatW(xs) - cx) / fx;
  const float ry = ((float)y - cy) / fy;
  const float3 o = (float3)(r0.w, r1.w, r2.w);
  const floatW dx = r0.x * rx + r0.y * ry + r0.z * 1.0f;
  const floatW dy = r1.x * rx + r1.y * ry + r1.z * 1.0f;
  const floatW dz = r2.x * rx + r2.y * ry + r2.z * 1.0f;
  floatW t0 = (floatW)fmax(near_z, tile_lo);
  floatW t1 = (floatW)fmin(far_z, as_float(tile_max[tile]));
  t1 = isnan(current) ? t1 : fmin(t1, current + depth_margin);
  const float block_m = (float)EMF_BLOCK * voxel_size;
  intW active = in_row;
  // emf_clip_slab per axis and lane.
#define RCW_SLAB(oc, dc, hi)                         \
  {                                                  \
    const intW flat = dc == 0.0f;                    \
    active &= !flat | ((oc >= 0.0f) & (oc <= (hi))); \
    const floatW ta = (0.0f - oc) / dc;              \
    const floatW tb = ((hi)-oc) / dc;                \
    t0 = flat ? t0 : fmax(t0, fmin(ta, tb));         \
    t1 = flat ? t1 : fmin(t1, fmax(ta, tb));         \
  }
  RCW_SLAB(o.x, dx, (float)dims.x * block_m)
  RCW_SLAB(o.y, dy, (float)dims.y * block_m)
  RCW_SLAB(o.z, dz, (float)dims.z * block_m)
#undef RCW_SLAB
  active &= t0 < t1;
  if (!any(active)) return;

  const floatW ray_len = sqrt(rx * rx + ry * ry + 1.0f * 1.0f);
  const floatW voxel_t = voxel_size / ray_len;
  const float inv_voxel = 1.0f / voxel_size;
  const float psi_scale = truncation / EMF_TSDF_SCALE;
  const floatW inv_dx = 1.0f / dx, inv_dy = 1.0f / dy, inv_dz = 1.0f / dz;
  intW bx_c = -1, by_c = -1, bz_c = -1;  // the block of the cached slot
  intW slot = -1;
  intW prev_ok = 0, found = 0;
  floatW prev_t = 0.0f, prev_psi = 0.0f, psi_hit = 0.0f;
  floatW t = t0;
  while (true) {
    active &= t < t1;
    if (!any(active)) break;
    const floatW px = o.x + dx * t, py = o.y + dy * t, pz = o.z + dz * t;
    const floatW gx = px * inv_voxel, gy = py * inv_voxel, gz = pz * inv_voxel;
    const intW off_box = active & ((gx < 0.0f) | (gy < 0.0f) | (gz < 0.0f));
    const intW go = active & !off_box;
    // floor: g >= 0 on the lanes that use it.
    const intW vx = convert_intW(go ? gx : 0.0f), vy = convert_intW(go ? gy : 0.0f),
               vz = convert_intW(go ? gz : 0.0f);
    const intW bx = vx / EMF_BLOCK, by = vy / EMF_BLOCK, bz = vz / EMF_BLOCK;
    const intW changed = go & ((bx != bx_c) | (by != by_c) | (bz != bz_c));
    bx_c = changed ? bx : bx_c;
    by_c = changed ? by : by_c;
    bz_c = changed ? bz : bz_c;
    // emf_block_slot per lane, without a branch per lane (the lanes change blocks at random,
    // and mispredicted branches cost more than reading the index of every lane): all lanes
    // read an index entry (entry 0 outside the grid), the changed ones keep it.
    const intW in_grid =
        (bx >= 0) & (by >= 0) & (bz >= 0) & (bx < dims.x) & (by < dims.y) & (bz < dims.z);
    const intW entry = in_grid ? bx + dims.x * (by + dims.y * bz) : 0;
    intW fetched;
#define RCW_SLOT(l) fetched.s##l = index[entry.s##l];
    EMF_LANES(RCW_SLOT)
#undef RCW_SLOT
    slot = changed ? (in_grid ? fetched : -1) : slot;
    const intW empty = go & (slot < 0);
    const intW in_block = go & (slot >= 0);
    // Every lane reads a voxel word (word 0 where not in a block), without a branch per lane.
    const intW addr =
        in_block ? slot * EMF_BLOCK_VOXELS + (vx - bx * EMF_BLOCK) +
                       EMF_BLOCK * ((vy - by * EMF_BLOCK) + EMF_BLOCK * (vz - bz * EMF_BLOCK))
                 : 0;
    __global const int* words = (__global const int*)voxels;
    intW raw;
#define RCW_VOXEL(l) raw.s##l = words[addr.s##l];
    EMF_LANES(RCW_VOXEL)
#undef RCW_VOXEL
    raw = in_block ? raw : 0;
    const intW observed = in_block & (EMF_WORD_WEIGHT(raw) > 0);
    const intW unobserved = in_block & !observed;
    const floatW psi = convert_floatW(EMF_WORD_TSDF(raw)) * psi_scale;
    const intW crossing = observed & prev_ok & (prev_psi > 0.0f) & (psi <= 0.0f);
    const intW step = observed & !crossing;
    // The block exit of empty lanes (emf_block_exit per lane).
    floatW te = INFINITY;
#define RCW_EXIT(dc, inv, b, oc)                                                   \
  {                                                                                \
    const floatW c = (convert_floatW(dc > 0.0f ? b + 1 : b) * block_m - oc) * inv; \
    te = ((dc != 0.0f) & (c > t)) ? fmin(te, c) : te;                              \
  }
    RCW_EXIT(dx, inv_dx, bx, o.x)
    RCW_EXIT(dy, inv_dy, by, o.y)
    RCW_EXIT(dz, inv_dz, bz, o.z)
#undef RCW_EXIT
    const floatW t_step =
        t +
        (psi > 0.0f ? fmax((floatW)voxel_size, step_fraction * psi) : (floatW)voxel_size) / ray_len;
    const floatW t_next = (off_box | unobserved)
                              ? t + voxel_t
                              : (empty ? fmax(te, t) + 0.01f * voxel_t : (step ? t_step : t));
    prev_ok = (off_box | empty | unobserved) ? 0 : (step ? (intW)(-1) : prev_ok);
    prev_psi = step ? psi : prev_psi;
    prev_t = step ? t : prev_t;
    psi_hit = crossing ? psi : psi_hit;
    found |= crossing;
    active &= !crossing;
    t = active ? t_next : t;
  }
  if (!any(found)) return;
  // The surface between prev_t and t of the lanes that found one: the secant point, then one
  // Newton step along the ray on the trilinear SDF (its gradient gives d psi / dt).
  floatW th = prev_t + (t - prev_t) * (prev_psi / (prev_psi - psi_hit));
  floatW hx = o.x + dx * th, hy = o.y + dy * th, hz = o.z + dz * th;
  floatW w_unused, gxh, gyh, gzh;
  const floatW sh = emf_sample_sdf_lanes(index, dims, voxels, voxel_size, truncation, hx, hy, hz,
                                         &w_unused, &gxh, &gyh, &gzh);
  intW hit = found & !isnan(sh);
  const floatW slope = gxh * dx + gyh * dy + gzh * dz;
  const floatW tn = th - sh / slope;
  const intW newton = hit & (slope < 0.0f) & (tn > prev_t - voxel_t) & (tn < t + voxel_t);
  if (any(newton)) {
    const floatW nx = o.x + dx * tn, ny = o.y + dy * tn, nz = o.z + dz * tn;
    floatW gxn, gyn, gzn;
    const floatW sn = emf_sample_sdf_lanes(index, dims, voxels, voxel_size, truncation, nx, ny, nz,
                                           &w_unused, &gxn, &gyn, &gzn);
    const intW take = newton & !isnan(sn);
    th = take ? tn : th;
    hx = take ? nx : hx;
    hy = take ? ny : hy;
    hz = take ? nz : hz;
    gxh = take ? gxn : gxh;
    gyh = take ? gyn : gyh;
    gzh = take ? gzn : gzh;
  }
  const floatW grad_len = sqrt(gxh * gxh + gyh * gyh + gzh * gzh);
  hit &= grad_len > 0.0f;
  if (has_counts && any(hit)) {
    hit &= emf_sample_pfg_lanes(count_index, dims, voxels, voxel_size, hx, hy, hz) > 0.5f;
  }
  hit &= th < t1;
  const floatW ux = gxh / grad_len, uy = gyh / grad_len, uz = gzh / grad_len;
  // emf_rotate_inverse per lane.
  const floatW nx_c = r0.x * ux + r1.x * uy + r2.x * uz;
  const floatW ny_c = r0.y * ux + r1.y * uy + r2.y * uz;
  const floatW nz_c = r0.z * ux + r1.z * uy + r2.z * uz;
#define RCW_WRITE(l)                                                     \
  if (hit.s##l) {                                                        \
    const int pixel = row + xs.s##l;                                     \
    depth_out[pixel] = th.s##l;                                          \
    normal_out[pixel] = (float4)(nx_c.s##l, ny_c.s##l, nz_c.s##l, 0.0f); \
    id_out[pixel] = volume_id;                                           \
  }
  EMF_LANES(RCW_WRITE)
#undef RCW_WRITE
}
