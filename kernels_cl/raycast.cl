// Ray casting of one or several volumes into a depth (camera z, metres), normal (camera frame,
// unit, pointing to the free side) and volume-id image. One pass per volume over the same
// outputs with a depth test: a pass writes a pixel only where its hit is nearer than what the
// previous passes wrote (plus depth_margin: objects rendered after the background win ties with
// the background's copy of the same surface), so after all passes every pixel shows the nearest
// surface of all volumes ("nothing nearer lies on the ray"). raycast_clear starts a render.
//
// Per pixel and volume: the ray (parameter t = camera z) is clipped to [near, far], to the
// volume box and to the depth already written. Unallocated blocks are skipped whole (jump to the
// block exit); in allocated blocks the nearest voxel's psi gives the step
// max(voxel, step_fraction * psi) in front of surfaces and one voxel elsewhere. A sign change
// + -> - of consecutive observed samples is a surface: refined by two secant steps on the
// trilinear SDF, normal = normalised SDF gradient there. A hit is dropped (no surface from this
// volume on this pixel) when the trilinear SDF is unavailable at it, or, for object volumes,
// when p_fg <= 0.5 there (the surface belongs to the background seen through the object box).
#include "map_common.clh"

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

/// Ray parameter where the ray leaves block b (block edge block_m metres).
inline float emf_block_exit(float3 o, float3 d, int4 b, float block_m) {
  float te = INFINITY;
  if (d.x > 0.0f) te = fmin(te, ((float)(b.x + 1) * block_m - o.x) / d.x);
  if (d.x < 0.0f) te = fmin(te, ((float)b.x * block_m - o.x) / d.x);
  if (d.y > 0.0f) te = fmin(te, ((float)(b.y + 1) * block_m - o.y) / d.y);
  if (d.y < 0.0f) te = fmin(te, ((float)b.y * block_m - o.y) / d.y);
  if (d.z > 0.0f) te = fmin(te, ((float)(b.z + 1) * block_m - o.z) / d.z);
  if (d.z < 0.0f) te = fmin(te, ((float)b.z * block_m - o.z) / d.z);
  return te;
}

__kernel void raycast_volume(__global const int* index, __global const int* count_index,
                             const int has_counts, const int4 dims,
                             __global const short2* voxels, const float voxel_size,
                             const float truncation, const float step_fraction, const float4 r0,
                             const float4 r1, const float4 r2, const int width, const int height,
                             const float fx, const float fy, const float cx, const float cy,
                             const float near_z, const float far_z, const int volume_id,
                             const float depth_margin,
                             __global float* depth_out, __global float4* normal_out,
                             __global int* id_out) {
  const int x = get_global_id(0);
  const int y = get_global_id(1);
  if (x >= width || y >= height) return;
  const int pixel = y * width + x;
  const float3 ray = emf_pixel_ray(x, y, fx, fy, cx, cy);
  const float3 o = (float3)(r0.w, r1.w, r2.w);
  const float3 d = emf_rotate(r0, r1, r2, ray);
  const float current = depth_out[pixel];
  float t0 = near_z;
  float t1 = emf_is_valid(current) ? fmin(far_z, current + depth_margin) : far_z;
  const float block_m = (float)EMF_BLOCK * voxel_size;
  if (!emf_clip_slab(o.x, d.x, (float)dims.x * block_m, &t0, &t1)) return;
  if (!emf_clip_slab(o.y, d.y, (float)dims.y * block_m, &t0, &t1)) return;
  if (!emf_clip_slab(o.z, d.z, (float)dims.z * block_m, &t0, &t1)) return;
  if (!(t0 < t1)) return;

  const float ray_len = sqrt(ray.x * ray.x + ray.y * ray.y + ray.z * ray.z);
  const float voxel_t = voxel_size / ray_len;  // ray parameter per voxel edge of distance
  int4 block = (int4)(-1, -1, -1, 0);
  int slot = -1;
  bool prev_ok = false;
  float prev_t = 0.0f;
  float prev_psi = 0.0f;
  float t = t0;
  while (t < t1) {
    const float3 p = o + d * t;
    const int4 v = (int4)((int)floor(p.x / voxel_size), (int)floor(p.y / voxel_size),
                          (int)floor(p.z / voxel_size), 0);
    if (v.x < 0 || v.y < 0 || v.z < 0) {  // on the box face by rounding
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const int4 b = (int4)(v.x / EMF_BLOCK, v.y / EMF_BLOCK, v.z / EMF_BLOCK, 0);
    if (b.x != block.x || b.y != block.y || b.z != block.z) {
      block = b;
      slot = emf_block_slot(index, dims, b);
    }
    if (slot < 0) {  // empty space: jump to the block exit
      const float te = emf_block_exit(o, d, b, block_m);
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
    const float psi = emf_voxel_tsdf(vox) * truncation;
    if (prev_ok && prev_psi > 0.0f && psi <= 0.0f) {
      // Surface between prev_t and t: secant steps on the trilinear SDF.
      float ta = prev_t;
      float tb = t;
      float fa = prev_psi;
      float fb = psi;
      float w_unused = 0.0f;
      float3 grad = (float3)(0.0f, 0.0f, 0.0f);
      const float sa = emf_sample_sdf(index, dims, voxels, voxel_size, truncation, o + d * ta,
                                      &w_unused, &grad);
      const float sb = emf_sample_sdf(index, dims, voxels, voxel_size, truncation, o + d * tb,
                                      &w_unused, &grad);
      if (emf_is_valid(sa) && emf_is_valid(sb) && sa > 0.0f && sb <= 0.0f) {
        fa = sa;
        fb = sb;
      }
      float th = ta + (tb - ta) * (fa / (fa - fb));
      const float sh = emf_sample_sdf(index, dims, voxels, voxel_size, truncation, o + d * th,
                                      &w_unused, &grad);
      if (emf_is_valid(sh) && fa != fb) {
        if (sh > 0.0f) {
          ta = th;
          fa = sh;
        } else {
          tb = th;
          fb = sh;
        }
        if (fa > 0.0f && fb <= 0.0f) th = ta + (tb - ta) * (fa / (fa - fb));
      }
      const float3 ph = o + d * th;
      const float s_hit =
          emf_sample_sdf(index, dims, voxels, voxel_size, truncation, ph, &w_unused, &grad);
      if (!emf_is_valid(s_hit)) return;
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
