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

__kernel void raycast_volume(__global const int* index, __global const int* count_index,
                             const int has_counts, const int4 dims, __global const short2* voxels,
                             const float voxel_size, const float truncation,
                             const float step_fraction, const float4 r0, const float4 r1,
                             const float4 r2, const int width, const int height, const float fx,
                             const float fy, const float cx, const float cy, const float near_z,
                             const float far_z, const int volume_id, const float depth_margin,
                             const int tiles_x, __global const int* tile_min,
                             __global const int* tile_max, __global float* depth_out,
                             __global float4* normal_out, __global int* id_out) {
  const int x = get_global_id(0);
  const int y = get_global_id(1);
  if (x >= width || y >= height) return;
  const int pixel = y * width + x;
  const float3 ray = emf_pixel_ray(x, y, fx, fy, cx, cy);
  const float3 o = (float3)(r0.w, r1.w, r2.w);
  const float3 d = emf_rotate(r0, r1, r2, ray);
  const float current = depth_out[pixel];
  const int tile = (y / EMF_RAY_TILE) * tiles_x + x / EMF_RAY_TILE;
  float t0 = fmax(near_z, as_float(tile_min[tile]));
  float t1 = fmin(far_z, as_float(tile_max[tile]));
  if (emf_is_valid(current)) t1 = fmin(t1, current + depth_margin);
  const float block_m = (float)EMF_BLOCK * voxel_size;
  if (!emf_clip_slab(o.x, d.x, (float)dims.x * block_m, &t0, &t1)) return;
  if (!emf_clip_slab(o.y, d.y, (float)dims.y * block_m, &t0, &t1)) return;
  if (!emf_clip_slab(o.z, d.z, (float)dims.z * block_m, &t0, &t1)) return;
  if (!(t0 < t1)) return;

  const float ray_len = sqrt(ray.x * ray.x + ray.y * ray.y + ray.z * ray.z);
  const float voxel_t = voxel_size / ray_len;  // ray parameter per voxel edge of distance
  const float inv_voxel = 1.0f / voxel_size;
  const float psi_scale = truncation / EMF_TSDF_SCALE;  // metres per quantisation step
  const float3 inv_d = (float3)(1.0f / d.x, 1.0f / d.y, 1.0f / d.z);
  int4 block = (int4)(-1, -1, -1, 0);
  int slot = -1;
  bool prev_ok = false;
  float prev_t = 0.0f;
  float prev_psi = 0.0f;
  float t = t0;
  while (t < t1) {
    const float3 p = o + d * t;
    const float gx = p.x * inv_voxel, gy = p.y * inv_voxel, gz = p.z * inv_voxel;
    if (gx < 0.0f || gy < 0.0f || gz < 0.0f) {  // on the box face by rounding
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const int4 v = (int4)((int)gx, (int)gy, (int)gz, 0);  // floor: g >= 0
    const int4 b = (int4)(v.x / EMF_BLOCK, v.y / EMF_BLOCK, v.z / EMF_BLOCK, 0);
    if (b.x != block.x || b.y != block.y || b.z != block.z) {
      block = b;
      slot = emf_block_slot(index, dims, b);
    }
    if (slot < 0) {  // empty space: jump to the block exit
      const float te = emf_block_exit(o, d, inv_d, b, block_m, t);
      t = fmax(te, t) + 0.01f * voxel_t;
      prev_ok = false;
      continue;
    }
    const int4 l = v - b * EMF_BLOCK;
    const short2 vox = voxels[slot * EMF_BLOCK_VOXELS + l.x + EMF_BLOCK * (l.y + EMF_BLOCK * l.z)];
    if (vox.y <= 0) {  // unobserved voxel
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const float psi = (float)vox.x * psi_scale;
    if (prev_ok && prev_psi > 0.0f && psi <= 0.0f) {
      // Surface between prev_t and t: interpolate the nearest-voxel values, then one Newton
      // step along the ray on the trilinear SDF (its gradient gives d psi / dt).
      float th = prev_t + (t - prev_t) * (prev_psi / (prev_psi - psi));
      float w_unused = 0.0f;
      float3 grad = (float3)(0.0f, 0.0f, 0.0f);
      float3 ph = o + d * th;
      const float sh =
          emf_sample_sdf(index, dims, voxels, voxel_size, truncation, ph, &w_unused, &grad);
      if (!emf_is_valid(sh)) return;
      const float slope = grad.x * d.x + grad.y * d.y + grad.z * d.z;
      if (slope < 0.0f) {
        const float tn = th - sh / slope;
        if (tn > prev_t - voxel_t && tn < t + voxel_t) {
          float3 gn = (float3)(0.0f, 0.0f, 0.0f);
          const float3 pn = o + d * tn;
          const float sn =
              emf_sample_sdf(index, dims, voxels, voxel_size, truncation, pn, &w_unused, &gn);
          if (emf_is_valid(sn)) {
            th = tn;
            ph = pn;
            grad = gn;
          }
        }
      }
      const float grad_len = sqrt(grad.x * grad.x + grad.y * grad.y + grad.z * grad.z);
      if (!(grad_len > 0.0f)) return;
      if (has_counts && emf_sample_pfg(count_index, dims, voxels, voxel_size, ph) <= 0.5f) return;
      if (!(th < t1)) return;
      const float3 n = emf_rotate_inverse(r0, r1, r2, grad / grad_len);
      depth_out[pixel] = th;
      normal_out[pixel] = (float4)(n, 0.0f);
      id_out[pixel] = volume_id;
      return;
    }
    prev_ok = true;
    prev_psi = psi;
    prev_t = t;
    t += (psi > 0.0f ? fmax(voxel_size, step_fraction * psi) : voxel_size) / ray_len;
  }
}
