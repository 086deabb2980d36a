// Direct SDF alignment (docs/method.md#tracking): per-pixel residual, Jacobian and Gauss-Newton
// terms of E = sum_u q_u c_u rho_delta(psi(T p_u)), reduced on the device.
// CPU reference: track::accumulateReference (src/track/tracker.cpp); keep them identical.
//
// T = T_volume_camera (rows r0, r1, r2: rotation | translation) maps camera points p_u (the
// vertex map, metres) into the volume frame. Residual r = psi(T p) (metres, trilinear), map
// confidence c = q_u * W(T p) (unnormalised: the host divides by max W, every term is linear
// in it), Huber weight h = min(1, delta / |r|), rho = Huber cost. Jacobian w.r.t. a
// left-multiplied increment (v, w), translation first: J = (grad, x cross grad), x = T p.
//
// One work item per 16 consecutive sampled pixels of a row, on a 2D range over the sampled grid
// (or a rectangle of it): no loops and no early exits. The item takes its pixels in 16 / EMF_W
// chunks of EMF_W lanes (floatW, common.clh). Lanes outside the grid or without a valid sample
// contribute zeros. Each item folds its 16 pixels per term to 8 (pixels l and l + 8 added), the
// work-group then adds up its 16 items' terms in local memory (then the 8 lanes) and writes one
// row of TRACK_TERMS partials. The order of every sum is the same at every EMF_W (only the
// compiler's fused multiply-adds round differently per width, docs/opencl.md):
//   [0, 21)  upper triangle of H = sum c h J J^T (row-major: 00 01 .. 05 11 12 .. 55)
//   [21, 27) g = sum c h J r
//   27 cost = sum c rho(r)      28 valid samples
//   29 inliers, each weighted by its q: |r| <= max(inlier_delta, inlier_noise * z^2), z the
//      pixel's camera-frame depth (the loss rules' share; the cost keeps the Huber delta)
//   30 input pixels (valid vertex and q > 0)          31 max W over valid samples (a max)
//   32 sum over pixels valid now and in `prev_cost` of (c' rho(r) - prev_cost), c' = c, or
//      with fixed_weights the previous pose's c (prev_weight)
//   33 number of those pixels
//   34 strict inliers (|r| <= inlier_delta), weighted by q    35 sum of q over valid samples
// Every sampled pixel's own cost c rho(r) (NaN when not valid) is written to pixel_cost, and
// with fixed_weights its weight c to pixel_weight, so that the next evaluation can compare
// costs over the pixels valid at both poses (points entering or leaving the observed map would
// otherwise make E jump between poses). compare = 0: prev_cost is not read (first evaluation
// of a level).
#include "common.clh"
#include "voxel_access.clh"

#define TRACK_TERMS 36
#define TRACK_MAX_TERM 31
// Work-group shape in work items; each item handles 16 consecutive sampled columns of a row.
#ifndef TRACK_LX
#define TRACK_LX 2
#endif
#ifndef TRACK_LY
#define TRACK_LY 8
#endif
#define TRACK_ITEMS (TRACK_LX * TRACK_LY)
#if TRACK_ITEMS != 16
#error "track_accumulate's final reduction is written for 16 work items per group"
#endif
#define TRACK_COLS 16  // sampled columns per work item

// Term k of chunk c (lanes = columns c EMF_W + l) into the item's 8 folded lanes `mine`: columns
// l and l + 8 added (the first step of the term's sum over the columns). sel(a, b) is fmax for
// the max term, + for the others.
#if EMF_W == 16
#define TRACK_FOLD(mine, k, c, value, sel) mine[TRACK_ITEMS * (k)] = sel((value).lo, (value).hi)
#else
#define TRACK_FOLD(mine, k, c, value, sel)                                                   \
  {                                                                                          \
    __local floatW* half_ = (__local floatW*)(mine + TRACK_ITEMS * (k)) + (c) % (8 / EMF_W); \
    *half_ = (c) < 8 / EMF_W ? (value) : sel(*half_, (value));                               \
  }
#endif
#define TRACK_ADD(a, b) ((a) + (b))

// Sum (max for TRACK_MAX_TERM) of term t over the 16 items' (folded) vectors of a group, then
// over the 8 lanes, written to row[t].
__attribute__((always_inline)) inline void track_reduce_term(__local const float8* shared, int t,
                                                             __global float* row) {
  __local const float8* col = shared + TRACK_ITEMS * t;
  if (t == TRACK_MAX_TERM) {
    float8 s = fmax(fmax(fmax(col[0], col[1]), fmax(col[2], col[3])),
                    fmax(fmax(col[4], col[5]), fmax(col[6], col[7])));
    s = fmax(s, fmax(fmax(fmax(col[8], col[9]), fmax(col[10], col[11])),
                     fmax(fmax(col[12], col[13]), fmax(col[14], col[15]))));
    const float4 s4 = fmax(s.lo, s.hi);
    row[t] = fmax(fmax(s4.x, s4.y), fmax(s4.z, s4.w));
  } else {
    float8 s = ((col[0] + col[1]) + (col[2] + col[3])) + ((col[4] + col[5]) + (col[6] + col[7]));
    s += ((col[8] + col[9]) + (col[10] + col[11])) + ((col[12] + col[13]) + (col[14] + col[15]));
    const float4 s4 = s.lo + s.hi;
    row[t] = (s4.x + s4.y) + (s4.z + s4.w);
  }
}

// Chunk `chunk` of a work item's TRACK_COLS columns (row sv): its pixels' costs and weights, and
// its terms folded into the item's slots `mine` (see TRACK_FOLD).
__attribute__((always_inline)) inline void track_chunk(
    const int chunk, __global const float4* vertex, __global const float* q, const int width,
    const int stride, const int su0, const int sv, const int su1, const int sv1, const float4 r0,
    const float4 r1, const float4 r2, __global const int* index, const int4 dims,
    __global const short2* voxels, const float voxel_size, const float truncation,
    const float huber_delta, const float inlier_delta, const float inlier_noise,
    __global const float* prev_cost, __global float* pixel_cost, __global const float* prev_weight,
    __global float* pixel_weight, const int compare, const int fixed_weights,
    __local float8* mine) {
  const intW su = (intW)(su0 + (int)get_global_id(0) * TRACK_COLS + chunk * EMF_W) + EMF_LANE_IDS;
  const intW in_grid = (su < su1) & (intW)(sv < sv1 ? -1 : 0);
  // Pixel of each lane (0 outside the sampled grid, so that every read stays valid).
  const intW pix = in_grid ? sv * stride * width + su * stride : 0;
  floatW px, py, pz, pw, qu, prev, prev_c = 0.0f;
#define TRACK_LOAD(l)                  \
  {                                    \
    const float4 p = vertex[pix.s##l]; \
    px.s##l = p.x;                     \
    py.s##l = p.y;                     \
    pz.s##l = p.z;                     \
    pw.s##l = p.w;                     \
    qu.s##l = q[pix.s##l];             \
    prev.s##l = prev_cost[pix.s##l];   \
  }
  EMF_LANES(TRACK_LOAD)
#undef TRACK_LOAD
  // The weights only with fixed_weights (the camera's evaluation keeps its memory traffic).
#define TRACK_LOAD_WEIGHT(l) prev_c.s##l = prev_weight[pix.s##l];
  if (fixed_weights) {
    EMF_LANES(TRACK_LOAD_WEIGHT)
  }
#undef TRACK_LOAD_WEIGHT
  const intW input = in_grid & (pw > 0.0f) & (qu > 0.0f);
  const floatW x = r0.x * px + r0.y * py + r0.z * pz + r0.w;
  const floatW y = r1.x * px + r1.y * py + r1.z * pz + r1.w;
  const floatW z = r2.x * px + r2.y * py + r2.z * pz + r2.w;
  // A chunk none of whose pixels is an input (an object's pixels behind its grid, q = 0) skips
  // the sampling: every term below is masked by `valid` there.
  floatW weight = 0.0f, gx = 0.0f, gy = 0.0f, gz = 0.0f;
  floatW r_raw = NAN;
  if (any(input)) {
    r_raw = emf_sample_sdf_lanes(index, dims, voxels, voxel_size, truncation, x, y, z, &weight, &gx,
                                 &gy, &gz);
  }
  const intW valid = input & !isnan(r_raw);
  // Lanes without a valid sample continue with zeros and are masked out of every term.
  const floatW r = valid ? r_raw : 0.0f;
  const floatW abs_r = fabs(r);
  const intW inlier = abs_r <= huber_delta;
  const floatW c = valid ? qu * weight : 0.0f;
  const floatW rho = inlier ? 0.5f * r * r : huber_delta * (abs_r - 0.5f * huber_delta);
  const floatW cost = c * rho;
  const floatW own_cost = valid ? cost : NAN;
#define TRACK_STORE(l) \
  if (in_grid.s##l) pixel_cost[pix.s##l] = own_cost.s##l;
  EMF_LANES(TRACK_STORE)
#undef TRACK_STORE
#define TRACK_STORE_WEIGHT(l) \
  if (in_grid.s##l) pixel_weight[pix.s##l] = c.s##l;
  if (fixed_weights) {
    EMF_LANES(TRACK_STORE_WEIGHT)
  }
#undef TRACK_STORE_WEIGHT
  const intW common = valid & (intW)(compare ? -1 : 0) & !isnan(prev);
  const floatW hw = c * (inlier ? 1.0f : huber_delta / abs_r);
  const floatW j0 = valid ? gx : 0.0f, j1 = valid ? gy : 0.0f, j2 = valid ? gz : 0.0f;
  // x cross grad (x may be NaN where the vertex is invalid).
  const floatW j3 = valid ? y * j2 - z * j1 : 0.0f;
  const floatW j4 = valid ? z * j0 - x * j2 : 0.0f;
  const floatW j5 = valid ? x * j1 - y * j0 : 0.0f;
#define TRACK_PUT(k, value) TRACK_FOLD(mine, k, chunk, value, TRACK_ADD)
  const floatW w0 = hw * j0, w1 = hw * j1, w2 = hw * j2, w3 = hw * j3, w4 = hw * j4, w5 = hw * j5;
  TRACK_PUT(0, w0 * j0);
  TRACK_PUT(1, w0 * j1);
  TRACK_PUT(2, w0 * j2);
  TRACK_PUT(3, w0 * j3);
  TRACK_PUT(4, w0 * j4);
  TRACK_PUT(5, w0 * j5);
  TRACK_PUT(6, w1 * j1);
  TRACK_PUT(7, w1 * j2);
  TRACK_PUT(8, w1 * j3);
  TRACK_PUT(9, w1 * j4);
  TRACK_PUT(10, w1 * j5);
  TRACK_PUT(11, w2 * j2);
  TRACK_PUT(12, w2 * j3);
  TRACK_PUT(13, w2 * j4);
  TRACK_PUT(14, w2 * j5);
  TRACK_PUT(15, w3 * j3);
  TRACK_PUT(16, w3 * j4);
  TRACK_PUT(17, w3 * j5);
  TRACK_PUT(18, w4 * j4);
  TRACK_PUT(19, w4 * j5);
  TRACK_PUT(20, w5 * j5);
  TRACK_PUT(21, w0 * r);
  TRACK_PUT(22, w1 * r);
  TRACK_PUT(23, w2 * r);
  TRACK_PUT(24, w3 * r);
  TRACK_PUT(25, w4 * r);
  TRACK_PUT(26, w5 * r);
  TRACK_PUT(27, cost);
  TRACK_PUT(28, valid ? 1.0f : 0.0f);
  TRACK_PUT(29, (valid & (abs_r <= fmax(inlier_delta, inlier_noise * pz * pz))) ? qu : 0.0f);
  TRACK_PUT(30, input ? 1.0f : 0.0f);
  const floatW max_w = valid ? weight : 0.0f;
  TRACK_FOLD(mine, TRACK_MAX_TERM, chunk, max_w, fmax);
  const floatW change = (fixed_weights ? prev_c * rho : cost) - prev;
  TRACK_PUT(32, common ? change : 0.0f);
  TRACK_PUT(33, common ? 1.0f : 0.0f);
  TRACK_PUT(34, (valid & (abs_r <= inlier_delta)) ? qu : 0.0f);
  TRACK_PUT(35, valid ? qu : 0.0f);
#undef TRACK_PUT
}

__kernel __attribute__((reqd_work_group_size(TRACK_LX, TRACK_LY, 1))) void track_accumulate(
    __global const float4* vertex, __global const float* q, const int width, const int height,
    const int stride, const int su0, const int sv0, const int su1, const int sv1, const float4 r0,
    const float4 r1, const float4 r2, __global const int* index, const int4 dims,
    __global const short2* voxels, const float voxel_size, const float truncation,
    const float huber_delta, const float inlier_delta, const float inlier_noise,
    __global const float* prev_cost, __global float* pixel_cost, __global const float* prev_weight,
    __global float* pixel_weight, const int compare, const int fixed_weights,
    __global float* partials) {
  // Term t of item k, its 16 pixels folded to 8 (pixels l and l + 8 added):
  // shared[t * TRACK_ITEMS + k]. 36 x 16 float8 = 18 KiB of local memory (OpenCL 1.2
  // guarantees 32 KiB; unfolded float16, 35 KiB, did not fit there).
  __local float8 shared[TRACK_TERMS * TRACK_ITEMS];
  (void)height;  // the host's sampled-grid bounds (sv1) already keep rows inside the image
  const int lid = get_local_id(0) + TRACK_LX * get_local_id(1);
  // The launch covers the sampled grid cells [su0, su1) x [sv0, sv1) (within the
  // ceil(width / stride) x ceil(height / stride) grid; the host's region of interest).
  const int sv = sv0 + (int)get_global_id(1);
  __local float8* mine = shared + lid;
#define TRACK_CHUNK(c)                                                                         \
  track_chunk(c, vertex, q, width, stride, su0, sv, su1, sv1, r0, r1, r2, index, dims, voxels, \
              voxel_size, truncation, huber_delta, inlier_delta, inlier_noise, prev_cost,      \
              pixel_cost, prev_weight, pixel_weight, compare, fixed_weights, mine);
  TRACK_CHUNK(0)
#if EMF_W <= 8
  TRACK_CHUNK(1)
#endif
#if EMF_W == 4
  TRACK_CHUNK(2)
  TRACK_CHUNK(3)
#endif
#undef TRACK_CHUNK
  barrier(CLK_LOCAL_MEM_FENCE);
  // Work item k adds up terms k, k + 16 and k + 32 (written out, no loops: see above).
  __global float* row =
      partials + (get_group_id(0) + get_num_groups(0) * get_group_id(1)) * TRACK_TERMS;
  track_reduce_term(shared, lid, row);
  track_reduce_term(shared, lid + TRACK_ITEMS, row);
  if (lid + 2 * TRACK_ITEMS < TRACK_TERMS) track_reduce_term(shared, lid + 2 * TRACK_ITEMS, row);
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
