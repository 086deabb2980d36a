// Preprocessing (METHOD.md step 1): depth range check, 7x7 bilateral filter of the depth image
// and back-projection to a camera-frame vertex map.
// CPU reference: track::preprocessReference (src/track/preprocess.cpp); keep them identical.
//
// Depth is float metres, NaN (or 0) = invalid. A pixel is valid when its depth lies in
// [min_depth, max_depth] (and > 0). Invalid pixels stay invalid and do not contribute to their
// neighbours. Output: filtered depth (NaN = invalid) and vertex (x, y, z, 1) in metres in the
// camera frame (x right, y down, z forward), (NaN, NaN, NaN, 0) when invalid.
#include "common.clh"

inline bool emf_depth_in_range(float d, float min_depth, float max_depth) {
  return emf_is_valid(d) && d > 0.0f && d >= min_depth && d <= max_depth;
}

#ifndef PRE_RADIUS
#define PRE_RADIUS 3
#endif

// Eight horizontally adjacent pixels per work item (float8 arithmetic, so CPU devices such as
// PoCL, which do not vectorise across work items here, use SIMD; GPUs see 8 independent
// lanes). The window radius is a build option (-DPRE_RADIUS=r, one cached program per radius).
// Invalid or out-of-image neighbours are masked out of the sums. Global size: (ceil(width / 8),
// height).
inline float8 emf_load8(__global const float* row, int u, int width) {
  if (u >= 0 && u + 7 < width) return vload8(0, row + u);
  float8 r;
  r.s0 = row[clamp(u + 0, 0, width - 1)];
  r.s1 = row[clamp(u + 1, 0, width - 1)];
  r.s2 = row[clamp(u + 2, 0, width - 1)];
  r.s3 = row[clamp(u + 3, 0, width - 1)];
  r.s4 = row[clamp(u + 4, 0, width - 1)];
  r.s5 = row[clamp(u + 5, 0, width - 1)];
  r.s6 = row[clamp(u + 6, 0, width - 1)];
  r.s7 = row[clamp(u + 7, 0, width - 1)];
  return r;
}

inline int8 emf_in_range8(float8 d, float min_depth, float max_depth) {
  // isnan(d) is false for valid depths; the comparisons are false for NaN anyway.
  return d > 0.0f && d >= min_depth && d <= max_depth;
}

__kernel void preprocess_depth(__global const float* depth_in, __global float* depth_out,
                               __global float4* vertex, const int width, const int height,
                               const float inv_two_sigma_space_sq,
                               const float inv_two_sigma_depth_sq, const float min_depth,
                               const float max_depth, const float fx, const float fy,
                               const float cx, const float cy) {
  const int u0 = get_global_id(0) * 8;
  const int v = get_global_id(1);
  if (u0 >= width || v >= height) return;
  const int8 lane = (int8)(0, 1, 2, 3, 4, 5, 6, 7);
  const float8 d0 = emf_load8(depth_in + v * width, u0, width);
  const int8 centre_valid = emf_in_range8(d0, min_depth, max_depth);
  float8 sum_w = 0.0f;
  float8 sum_wd = 0.0f;
  for (int dv = -PRE_RADIUS; dv <= PRE_RADIUS; ++dv) {
    const int vv = v + dv;
    if (vv < 0 || vv >= height) continue;
    __global const float* row = depth_in + vv * width;
    for (int du = -PRE_RADIUS; du <= PRE_RADIUS; ++du) {
      const float8 d = emf_load8(row, u0 + du, width);
      const int8 uu = u0 + du + lane;
      const int8 use = emf_in_range8(d, min_depth, max_depth) & (uu >= 0) & (uu < width);
      const float8 dd = d - d0;
      const float8 w = exp(-(float)(du * du + dv * dv) * inv_two_sigma_space_sq -
                           dd * dd * inv_two_sigma_depth_sq);
      sum_w += select((float8)0.0f, w, use);
      sum_wd += select((float8)0.0f, w * d, use);
    }
  }
  // The centre always contributes weight 1 when valid, so sum_w >= 1 there.
  const float8 z = select((float8)NAN, sum_wd / sum_w, centre_valid);
  const float8 x = (convert_float8(u0 + lane) - cx) / fx * z;
  const float y = ((float)v - cy) / fy;
  const float zs[8] = {z.s0, z.s1, z.s2, z.s3, z.s4, z.s5, z.s6, z.s7};
  const float xs[8] = {x.s0, x.s1, x.s2, x.s3, x.s4, x.s5, x.s6, x.s7};
  const int i0 = v * width + u0;
  if (u0 + 7 < width) {
    vstore8(z, 0, depth_out + i0);
    for (int l = 0; l < 8; ++l) {
      vertex[i0 + l] =
          isnan(zs[l]) ? (float4)(NAN, NAN, NAN, 0.0f) : (float4)(xs[l], y * zs[l], zs[l], 1.0f);
    }
  } else {
    for (int l = 0; l < 8 && u0 + l < width; ++l) {
      depth_out[i0 + l] = zs[l];
      vertex[i0 + l] =
          isnan(zs[l]) ? (float4)(NAN, NAN, NAN, 0.0f) : (float4)(xs[l], y * zs[l], zs[l], 1.0f);
    }
  }
}
