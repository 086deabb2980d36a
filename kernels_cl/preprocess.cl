// Preprocessing (docs/method.md#preprocessing): depth range check, 7x7 bilateral filter of the
// depth image (its range sigma grows with depth^2: PreprocessOptions::sigma_depth_per_m2) and
// back-projection to a camera-frame vertex map.
// CPU reference: track::preprocessReference (src/track/preprocess.cpp); keep them identical.
//
// Depth is float metres, NaN (or 0) = invalid. A pixel is valid when its depth lies in
// [min_depth, max_depth] (and > 0). Invalid pixels stay invalid and do not contribute to their
// neighbours. A valid pixel whose filtered depth exceeds guard_max_depth (the range guard,
// PreprocessOptions::range_guard_per_m2; INFINITY = off) and whose window holds a pixel without
// usable depth (the image border does not count) becomes invalid. Output: filtered depth
// (NaN = invalid) and vertex (x, y, z, 1) in metres in the camera frame (x right, y down, z
// forward), (NaN, NaN, NaN, 0) when invalid; with write_guarded, `guarded` receives the input
// depth with NaN where the guard dropped a pixel: what the map integrates.
#include "common.clh"

// Hole margin (PreprocessOptions::hole_margin_px): a pixel keeps its depth only when no pixel
// within `radius` (Chebyshev distance) of it lacks depth (NaN or <= 0); pixels outside the image
// do not count. One work item per pixel.
__kernel void drop_hole_margin(__global const float* depth_in, __global float* depth_out,
                               const int width, const int height, const int radius) {
  const int u = get_global_id(0);
  const int v = get_global_id(1);
  if (u >= width || v >= height) return;
  float d = depth_in[v * width + u];
  for (int dv = -radius; dv <= radius; ++dv) {
    const int vv = v + dv;
    if (vv < 0 || vv >= height) continue;
    for (int du = -radius; du <= radius; ++du) {
      const int uu = u + du;
      if (uu < 0 || uu >= width) continue;
      // Not (x > 0): NaN and <= 0 are holes.
      if (!(depth_in[vv * width + uu] > 0.0f)) d = NAN;
    }
  }
  depth_out[v * width + u] = d;
}

inline bool emf_depth_in_range(float d, float min_depth, float max_depth) {
  return emf_is_valid(d) && d > 0.0f && d >= min_depth && d <= max_depth;
}

#ifndef PRE_RADIUS
#define PRE_RADIUS 3
#endif
#ifndef PRE_STRIDE
#define PRE_STRIDE 1
#endif

// EMF_W pixels of a row per work item (floatW arithmetic, common.clh: PoCL does not vectorise
// across work items here, so the SIMD is explicit; GPUs see EMF_W independent lanes).
// The window radius and the sample stride are build options (-DPRE_RADIUS=r -DPRE_STRIDE=s, one
// cached program per pair). Invalid or out-of-image neighbours (loaded as NaN) are masked out of
// the sums.
// The helpers are always inlined: a call in the tap loop makes every live vector spill.

/// Depths of EMF_W pixels of a row: lane l reads row[u + l * step]; lanes outside the row read NaN
/// (invalid: masked out of the sums like a missing depth).
__attribute__((always_inline)) inline floatW emf_load_lanes(__global const float* row, int u,
                                                            int step, int width) {
  if (step == 1 && u >= 0 && u + EMF_W - 1 < width) return vloadW(0, row + u);
  if (step == 2 && u >= 0 && u + 2 * EMF_W - 1 < width) {
    // The even lanes of two loads (swizzles: PoCL's shuffle2 runs lane by lane).
    const floatW a = vloadW(0, row + u), b = vloadW(0, row + u + EMF_W);
    return (floatW)(a.even, b.even);
  }
  floatW r;
#define EMF_PRE_LOAD(l) \
  r.s##l = (u + 0x##l * step >= 0 && u + 0x##l * step < width) ? row[u + 0x##l * step] : NAN;
  EMF_LANES(EMF_PRE_LOAD)
#undef EMF_PRE_LOAD
  return r;
}

__attribute__((always_inline)) inline intW emf_in_range_lanes(floatW d, float min_depth,
                                                              float max_depth) {
  // The comparisons are false for NaN.
  return (d > 0.0f) & (d >= min_depth) & (d <= max_depth);
}

/// d > 0 && d >= min_depth  <=>  d > this (floats: d >= m <=> d > the float below m), so a
/// neighbour's range check is two comparisons (both false for NaN).
inline float emf_above(float min_depth) { return fmax(0.0f, nextafter(min_depth, -INFINITY)); }

/// exp(x) for x <= 0 (the bilateral weights): 2^(x log2 e) split into 2^n (exponent bits) and
/// 2^f, |f| <= 1/2, by a degree-7 polynomial (relative error below 3e-7, a few float ulps of
/// the libm exp the CPU reference uses). Arguments below -87 give 0 instead of a subnormal.
__attribute__((always_inline)) inline floatW emf_exp_neg_lanes(floatW x) {
  const floatW y = fmax(x * 1.44269504f, -126.0f);
  // Round to nearest (even) by adding and subtracting 1.5 * 2^23 (|y| <= 126).
  const floatW n = (y + 12582912.0f) - 12582912.0f;
  const floatW f = y - n;
  // 2^f = e^(f ln 2), Taylor coefficients of e^t at t = f ln 2 folded into powers of f.
  floatW p = 1.5252734e-5f;
  p = p * f + 1.5403530e-4f;
  p = p * f + 1.3333558e-3f;
  p = p * f + 9.6181291e-3f;
  p = p * f + 5.5504109e-2f;
  p = p * f + 2.4022651e-1f;
  p = p * f + 6.9314718e-1f;
  p = p * f + 1.0f;
  const floatW scale = as_floatW((convert_intW(n) + 127) << 23);
  return y > -126.0f ? p * scale : 0.0f;
}

/// The bilateral filter at EMF_W pixels of row v, lane l at column u0 + l * step, with centre
/// depths d0: the weighted mean of the window's usable depths (NaN where the centre is not
/// usable), and in *hole the lanes whose window (inside the image) holds a pixel without usable
/// depth. Per lane the operations do not depend on `step`: a pixel's result is the same to the
/// bit whichever kernel computes it.
__attribute__((always_inline)) inline floatW emf_bilateral_lanes(
    __global const float* depth_in, int width, int height, int u0, int v, int step, floatW d0,
    float inv_two_sigma_space_sq, float sigma_depth, float sigma_depth_per_m2, float min_depth,
    float max_depth, intW* hole_out) {
  const intW lane = EMF_LANE_IDS;
  const intW centre_valid = emf_in_range_lanes(d0, min_depth, max_depth);
  const float above = emf_above(min_depth);
  // Range sigma at the centre's depth: sigma_depth + sigma_depth_per_m2 z^2.
  const floatW sigma_r = sigma_depth + sigma_depth_per_m2 * (centre_valid ? d0 * d0 : 0.0f);
  const floatW inv_two_sigma_r_sq = 0.5f / (sigma_r * sigma_r);
  floatW sum_w = 0.0f;
  floatW sum_wd = 0.0f;
  intW hole = 0;
  for (int dv = -PRE_RADIUS; dv <= PRE_RADIUS; ++dv) {
    const int vv = v + dv;
    if (vv < 0 || vv >= height) continue;
    __global const float* row = depth_in + vv * width;
    for (int du = -PRE_RADIUS; du <= PRE_RADIUS; ++du) {
      const floatW d = emf_load_lanes(row, u0 + du, step, width);
      const intW use = (d > above) & (d <= max_depth);
      const intW col = u0 + du + lane * step;
      hole |= (col >= 0) & (col < width) & !use;
      const floatW dd = d - d0;
      const floatW w = emf_exp_neg_lanes(-(float)(du * du + dv * dv) * inv_two_sigma_space_sq -
                                         dd * dd * inv_two_sigma_r_sq);
      sum_w += use ? w : 0.0f;
      sum_wd += use ? w * d : 0.0f;
    }
  }
  *hole_out = hole;
  // The centre always contributes weight 1 when valid, so sum_w >= 1 there.
  return centre_valid ? sum_wd / sum_w : NAN;
}

// preprocess_depth: the pixels (u, v) with u and v multiples of PRE_STRIDE (all of them at
// stride 1), EMF_W per work item: lane l of item (gx, gy) is pixel (PRE_STRIDE (EMF_W gx + l),
// PRE_STRIDE gy). Global size: (ceil(ceil(width / PRE_STRIDE) / EMF_W), ceil(height /
// PRE_STRIDE)).
// The other pixels' filtered depth and vertex are not written (the host keeps them invalid);
// with a stride the guarded depth (write_guarded) is preprocess_guard's, for every pixel.
// The range guard drops a valid pixel whose filtered depth is beyond guard_max_depth (INFINITY:
// off) and that has a hole in its window (a surface cut by a range limit is riddled with them).
__kernel void preprocess_depth(__global const float* depth_in, __global float* depth_out,
                               __global float4* vertex, const int width, const int height,
                               const float inv_two_sigma_space_sq, const float sigma_depth,
                               const float sigma_depth_per_m2, const float min_depth,
                               const float max_depth, const float fx, const float fy,
                               const float cx, const float cy, const float guard_max_depth,
                               __global float* guarded, const int write_guarded) {
  const int u0 = get_global_id(0) * EMF_W * PRE_STRIDE;
  const int v = get_global_id(1) * PRE_STRIDE;
  if (u0 >= width || v >= height) return;
  const intW lane = EMF_LANE_IDS;
  const floatW d0 = emf_load_lanes(depth_in + v * width, u0, PRE_STRIDE, width);
  intW hole;
  const floatW filtered =
      emf_bilateral_lanes(depth_in, width, height, u0, v, PRE_STRIDE, d0, inv_two_sigma_space_sq,
                          sigma_depth, sigma_depth_per_m2, min_depth, max_depth, &hole);
  const intW centre_valid = emf_in_range_lanes(d0, min_depth, max_depth);
  const intW guard_drop = centre_valid & hole & !(filtered <= guard_max_depth);
  const floatW z = (centre_valid & !guard_drop) ? filtered : NAN;
  const floatW x = (convert_floatW(u0 + lane * PRE_STRIDE) - cx) / fx * z;
  const float y = ((float)v - cy) / fy;
  const int i0 = v * width + u0;
#if PRE_STRIDE == 1
  if (u0 + EMF_W - 1 < width) vstoreW(z, 0, depth_out + i0);
  // The depth the map integrates: the input, without the pixels the guard dropped.
  const floatW kept = guard_drop ? NAN : d0;
  if (write_guarded && u0 + EMF_W - 1 < width) vstoreW(kept, 0, guarded + i0);
#define EMF_PRE_STORE(l)                                                             \
  if (u0 + 0x##l < width) {                                                          \
    if (u0 + EMF_W - 1 >= width) depth_out[i0 + 0x##l] = z.s##l;                     \
    if (write_guarded && u0 + EMF_W - 1 >= width) guarded[i0 + 0x##l] = kept.s##l;   \
    vertex[i0 + 0x##l] = isnan(z.s##l) ? (float4)(NAN, NAN, NAN, 0.0f)               \
                                       : (float4)(x.s##l, y * z.s##l, z.s##l, 1.0f); \
  }
#else
  (void)guarded;  // preprocess_guard writes it for every pixel
  (void)write_guarded;
#define EMF_PRE_STORE(l)                                                                          \
  if (u0 + 0x##l * PRE_STRIDE < width) {                                                          \
    depth_out[i0 + 0x##l * PRE_STRIDE] = z.s##l;                                                  \
    vertex[i0 + 0x##l * PRE_STRIDE] = isnan(z.s##l) ? (float4)(NAN, NAN, NAN, 0.0f)               \
                                                    : (float4)(x.s##l, y * z.s##l, z.s##l, 1.0f); \
  }
#endif
  EMF_LANES(EMF_PRE_STORE)
#undef EMF_PRE_STORE
}

/// Stores EMF_W values at row[u0 .. u0 + EMF_W - 1], the lanes inside the row.
__attribute__((always_inline)) inline void emf_store_lanes(floatW x, __global float* row, int u0,
                                                           int width) {
  if (u0 + EMF_W - 1 < width) {
    vstoreW(x, 0, row + u0);
    return;
  }
#define EMF_PRE_STORE(l) \
  if (u0 + 0x##l < width) row[u0 + 0x##l] = x.s##l;
  EMF_LANES(EMF_PRE_STORE)
#undef EMF_PRE_STORE
}

/// The range guard alone at every pixel, for preprocess_depth with a stride, in two separable
/// passes (EMF_W pixels per work item, global size (ceil(width / EMF_W), height) each).
/// preprocess_guard_rows: per pixel, over its window's row (the 2 PRE_RADIUS + 1 pixels around
/// it), the largest usable depth m (0 without any) and whether a pixel inside the image lacks
/// usable depth: row_max = m, or -1 - m with such a hole.
__kernel void preprocess_guard_rows(__global const float* depth_in, __global float* row_max,
                                    const int width, const int height, const float min_depth,
                                    const float max_depth) {
  const int u0 = get_global_id(0) * EMF_W;
  const int v = get_global_id(1);
  if (u0 >= width || v >= height) return;
  const intW lane = EMF_LANE_IDS;
  const float above = emf_above(min_depth);
  __global const float* row = depth_in + v * width;
  intW hole = 0;
  floatW largest = 0.0f;
  for (int du = -PRE_RADIUS; du <= PRE_RADIUS; ++du) {
    const floatW d = emf_load_lanes(row, u0 + du, 1, width);
    const intW use = (d > above) & (d <= max_depth);
    const intW col = u0 + du + lane;
    hole |= (col >= 0) & (col < width) & !use;
    largest = use ? fmax(largest, d) : largest;
  }
  emf_store_lanes(hole ? -1.0f - largest : largest, row_max + v * width, u0, width);
}

/// preprocess_guard: the window's hole and largest usable depth from the rows of row_max above
/// and below; `guarded` receives the input with NaN where the guard drops the pixel, as
/// preprocess_depth at stride 1 writes it. The filtered depth is a weighted mean of the window's
/// usable depths, so it cannot pass guard_max_depth unless their largest does (1e-4 allows for
/// the mean's rounding and row_max's encoding): the filter runs only on the items where a valid
/// lane with a hole in its window has such a neighbour.
__kernel void preprocess_guard(__global const float* depth_in, __global const float* row_max,
                               __global float* guarded, const int width, const int height,
                               const float inv_two_sigma_space_sq, const float sigma_depth,
                               const float sigma_depth_per_m2, const float min_depth,
                               const float max_depth, const float guard_max_depth) {
  const int u0 = get_global_id(0) * EMF_W;
  const int v = get_global_id(1);
  if (u0 >= width || v >= height) return;
  const floatW d0 = emf_load_lanes(depth_in + v * width, u0, 1, width);
  const intW centre_valid = emf_in_range_lanes(d0, min_depth, max_depth);
  intW hole = 0;
  floatW largest = 0.0f;
  for (int dv = -PRE_RADIUS; dv <= PRE_RADIUS; ++dv) {
    const int vv = v + dv;
    if (vv < 0 || vv >= height) continue;
    // Lanes beyond the row read NaN: no hole, no depth (their pixels are not stored).
    const floatW r = emf_load_lanes(row_max + vv * width, u0, 1, width);
    hole |= r < 0.0f;
    largest = fmax(largest, r < 0.0f ? -1.0f - r : r);
  }
  const intW maybe = centre_valid & hole & (largest * 1.0001f > guard_max_depth);
  intW guard_drop = 0;
  if (any(maybe)) {
    intW hole_again;
    const floatW filtered =
        emf_bilateral_lanes(depth_in, width, height, u0, v, 1, d0, inv_two_sigma_space_sq,
                            sigma_depth, sigma_depth_per_m2, min_depth, max_depth, &hole_again);
    guard_drop = maybe & !(filtered <= guard_max_depth);
  }
  emf_store_lanes(guard_drop ? NAN : d0, guarded + v * width, u0, width);
}
