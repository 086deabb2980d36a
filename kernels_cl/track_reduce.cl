// Direct SDF alignment (METHOD.md step 3): per-pixel residual, Jacobian and Gauss-Newton terms
// of E = sum_u q_u c_u rho_delta(psi(T p_u)), reduced on the device.
// CPU reference: track::accumulateReference (src/track/tracker.cpp); keep them identical.
//
// T = T_volume_camera (rows r0, r1, r2: rotation | translation) maps camera points p_u (the
// vertex map, metres) into the volume frame. Residual r = psi(T p) (metres, trilinear), map
// confidence c = q_u * W(T p) (unnormalised: the host divides by max W, every term is linear
// in it), Huber weight h = min(1, delta / |r|), rho = Huber cost. Jacobian w.r.t. a
// left-multiplied increment (v, w), translation first: J = (grad, x cross grad), x = T p.
//
// One work item accumulates chunks of 8 consecutive samples privately (chunks strided by the
// global size); the work-group then sums its items in local memory and writes one row of
// TRACK_TERMS partials:
//   [0, 21)  upper triangle of H = sum c h J J^T (row-major: 00 01 .. 05 11 12 .. 55)
//   [21, 27) g = sum c h J r
//   27 cost = sum c rho(r)      28 valid samples      29 inliers (|r| <= delta)
//   30 input pixels (valid vertex and q > 0)          31 max W over valid samples (a max)
//   32 sum over pixels valid now and in `prev_cost` of (c rho(r) - prev_cost)
//   33 number of those pixels
// Every sampled pixel's own cost c rho(r) (NaN when not valid) is written to pixel_cost, so
// that the next evaluation can compare costs over the pixels valid at both poses (points
// entering or leaving the observed map would otherwise make E jump between poses).
// compare = 0: prev_cost is not read (first evaluation of a level).
#include "common.clh"
#include "voxel_access.clh"

#define TRACK_TERMS 34
#define TRACK_MAX_TERM 31
#ifndef TRACK_LOCAL
#define TRACK_LOCAL 64
#endif

__kernel __attribute__((reqd_work_group_size(TRACK_LOCAL, 1, 1))) void track_accumulate(
    __global const float4* vertex, __global const float* q, const int width, const int height,
    const int stride, const float4 r0, const float4 r1, const float4 r2, __global const int* index,
    const int4 dims, __global const short2* voxels, const float voxel_size, const float truncation,
    const float huber_delta, __global const float* prev_cost, __global float* pixel_cost,
    const int compare, __global float* partials) {
  __local float shared[TRACK_TERMS * TRACK_LOCAL];
  const int lid = get_local_id(0);
  const int sw = (width + stride - 1) / stride;
  const int sh = (height + stride - 1) / stride;
  const int n = sw * sh;
  // The 27 Gauss-Newton terms are accumulated for 8 samples at once (float8), the sampling
  // itself is scalar; the other terms are cheap scalars.
  float8 hg[27];
  for (int k = 0; k < 27; ++k) hg[k] = 0.0f;
  float cost_sum = 0.0f, valid = 0.0f, inliers = 0.0f, input = 0.0f, max_w = 0.0f;
  float cost_change = 0.0f, common = 0.0f;
  for (int s0 = get_global_id(0) * 8; s0 < n; s0 += get_global_size(0) * 8) {
    float lw[8], lr[8], lj[6][8];
    for (int l = 0; l < 8; ++l) {
      lw[l] = 0.0f;
      lr[l] = 0.0f;
      for (int a = 0; a < 6; ++a) lj[a][l] = 0.0f;
      const int s = s0 + l;
      if (s >= n) continue;
      const int i = (s / sw) * stride * width + (s % sw) * stride;
      const float4 p = vertex[i];
      const float qu = q[i];
      pixel_cost[i] = NAN;
      if (!(p.w > 0.0f) || !(qu > 0.0f)) continue;
      input += 1.0f;
      const float3 x =
          (float3)(dot(r0.xyz, p.xyz) + r0.w, dot(r1.xyz, p.xyz) + r1.w, dot(r2.xyz, p.xyz) + r2.w);
      float weight;
      float3 grad;
      const float r =
          emf_sample_sdf(index, dims, voxels, voxel_size, truncation, x, &weight, &grad);
      if (!emf_is_valid(r)) continue;
      valid += 1.0f;
      const float abs_r = fabs(r);
      const bool inlier = abs_r <= huber_delta;
      const float c = qu * weight;
      inliers += inlier ? 1.0f : 0.0f;
      const float cost = c * (inlier ? 0.5f * r * r : huber_delta * (abs_r - 0.5f * huber_delta));
      cost_sum += cost;
      pixel_cost[i] = cost;
      if (compare) {
        const float prev = prev_cost[i];
        if (emf_is_valid(prev)) {
          cost_change += cost - prev;
          common += 1.0f;
        }
      }
      max_w = fmax(max_w, weight);
      const float3 jr = cross(x, grad);
      lw[l] = c * (inlier ? 1.0f : huber_delta / abs_r);
      lr[l] = r;
      lj[0][l] = grad.x;
      lj[1][l] = grad.y;
      lj[2][l] = grad.z;
      lj[3][l] = jr.x;
      lj[4][l] = jr.y;
      lj[5][l] = jr.z;
    }
    const float8 w8 = vload8(0, lw);
    const float8 r8 = vload8(0, lr);
    float8 j8[6];
    for (int a = 0; a < 6; ++a) j8[a] = vload8(0, lj[a]);
    int k = 0;
    for (int a = 0; a < 6; ++a) {
      const float8 wa = w8 * j8[a];
      for (int b = a; b < 6; ++b) hg[k++] += wa * j8[b];
    }
    for (int a = 0; a < 6; ++a) hg[21 + a] += w8 * j8[a] * r8;
  }
  for (int k = 0; k < 27; ++k) {
    const float8 h = hg[k];
    shared[k * TRACK_LOCAL + lid] =
        ((h.s0 + h.s1) + (h.s2 + h.s3)) + ((h.s4 + h.s5) + (h.s6 + h.s7));
  }
  shared[27 * TRACK_LOCAL + lid] = cost_sum;
  shared[28 * TRACK_LOCAL + lid] = valid;
  shared[29 * TRACK_LOCAL + lid] = inliers;
  shared[30 * TRACK_LOCAL + lid] = input;
  shared[31 * TRACK_LOCAL + lid] = max_w;
  shared[32 * TRACK_LOCAL + lid] = cost_change;
  shared[33 * TRACK_LOCAL + lid] = common;
  barrier(CLK_LOCAL_MEM_FENCE);
  if (lid < TRACK_TERMS) {
    __local const float* col = shared + lid * TRACK_LOCAL;
    float s = 0.0f;
    if (lid == TRACK_MAX_TERM) {
      for (int t = 0; t < TRACK_LOCAL; ++t) s = fmax(s, col[t]);
    } else {
      for (int t = 0; t < TRACK_LOCAL; ++t) s += col[t];
    }
    partials[get_group_id(0) * TRACK_TERMS + lid] = s;
  }
}

// Second stage of the device-side reduction: one work item per term sums the per-group
// partials (max for TRACK_MAX_TERM). Launch TRACK_TERMS work items.
__kernel void track_reduce_partials(__global const float* partials, const int num_groups,
                                    __global float* out) {
  const int k = get_global_id(0);
  if (k >= TRACK_TERMS) return;
  float s = 0.0f;
  if (k == TRACK_MAX_TERM) {
    for (int g = 0; g < num_groups; ++g) s = fmax(s, partials[g * TRACK_TERMS + k]);
  } else {
    for (int g = 0; g < num_groups; ++g) s += partials[g * TRACK_TERMS + k];
  }
  out[k] = s;
}
