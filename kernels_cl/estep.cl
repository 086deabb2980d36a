// E-step of the EM loop (docs/method.md#e-step): per pixel u and volume i, the likelihood
//   p(u | i) = alpha / (2 sigma) * exp(-|psi_i(T_i p(u))| / sigma) * p_fg,i + (1 - alpha) p_U
// when T_i p(u) lies inside volume i's grid and its claim box (claim_lo <= p < claim_hi, volume
// frame; objects.claim_region), else 0; then q_i(u) = p(u | i) / sum_j p(u | j).
// Inside the grid but where the SDF is not observed (NaN sample, or an interpolated weight below
// min_weight), |psi| = truncation: the volume neither claims nor rejects the point (the
// authors' volumes start at +truncation). The weight floor keeps a voxel that was integrated
// only with a tiny association (e.g. a moving object's pixels in the background, q_0 ~ 0.05)
// from claiming the pixel fully in the next E-step.
// p_fg = 1 for volumes without counts (the background).
//
// Ablation (mode 1, em.association = pfg; the paper's "w/o assoc."): objects get q_i = p_fg,i
// at the point (0 outside the volume), the background q_0 = 1 - max_i q_i; no SDF residual
// term. `sum` then holds the largest object p_fg.
//
// Host sequence per E-step: estep_likelihood_lanes once per volume (first = 1 for the first volume,
// the background over the whole image, which initialises the running sum, the best likelihood
// and the residual), then estep_normalize once per volume. Where no object's rectangle reaches
// (`cover`), the background's q is 1 wherever its grid holds the point, whatever its SDF: unless
// the residual is wanted there (cover.count < 0), the background's SDF is not sampled there (the
// likelihood is set to 1 and the residual to NaN). When the objects' likelihoods are reused (see
// below), the rectangles are those of the pixels they claim (`claimed_rects` of their pass). An
// object's launches cover only the pixel rectangle its grid projects to (outside it the
// likelihood is 0 exactly); the host keeps its q at 0 outside that rectangle (estep_clear over
// the part a previous E-step wrote). When
// the objects and their poses are those of the previous E-step (the frame's second E-step moves
// only the background), their stored likelihoods are added with estep_accumulate instead. The
// camera's E-step wants only q_0 at the pixels the camera tracker reads: its background pass
// covers every `stride`-th pixel in x and y, and only the background is normalised. Pixels
// without a valid vertex get q = 0 for every volume and residual NaN; pixels no volume contains
// also get q = 0.
#include "map_common.clh"

/// The object rectangles (x0, y0, width, height) the background pass must evaluate exactly:
/// `count` of them (count < 0: the whole image). Matches em::EStep's host struct.
#define EMF_ESTEP_COVER_RECTS 8
#define EMF_ESTEP_EXACT_COLS 16  // a multiple of EMF_W
typedef struct {
  int4 rects[EMF_ESTEP_COVER_RECTS];
  int count;
  int pad[3];
} EStepCover;

/// The likelihood of one volume for EMF_W pixels of a row per work item, in floatW lanes
/// (explicit SIMD through emf_sample_sdf_lanes / emf_sample_pfg_lanes, like track_accumulate: PoCL
/// keeps a per-pixel kernel scalar). Per lane: the formula above, as em::associationLikelihood.
/// Lanes none of which falls in the volume skip the sampling. The work items cover the
/// grid `rect` (x0, y0, columns, rows) of every `stride`-th pixel of an image `width` pixels
/// wide: item (gx, gy) takes pixels x0 + stride (EMF_W gx + l), l = 0 .. EMF_W - 1, of row
/// y0 + stride gy (stride 1: a rectangle of the image).
__kernel void estep_likelihood_lanes(
    __global const float4* vertex, const int width, const int4 rect, const float4 r0,
    const float4 r1, const float4 r2, __global const int* index, __global const int* count_index,
    const int has_counts, const int4 dims, const float4 claim_lo, const float4 claim_hi,
    __global const short2* voxels, const float voxel_size, const float truncation,
    const float sigma, const float alpha, const float p_uniform, const float min_weight,
    const int pfg_mode, const int first, const EStepCover cover, const int stride,
    __global float* likelihood, __global float* sum, __global float* best, __global float* residual,
    __global int* claimed_rects, const int volume) {
  const int gx = get_global_id(0) * EMF_W;  // first lane's column of the grid
  const int gy = get_global_id(1);
  if (gx >= rect.z || gy >= rect.w) return;
  const int col = rect.x + stride * gx, row = rect.y + stride * gy;  // lane 0's pixel
  const int base = row * width + col;
  const int lanes = rect.z - gx;  // lanes l < lanes are inside the grid
  floatW px, py, pz, pw;
#define ESTEP_LOAD(l)                                               \
  {                                                                 \
    const float4 p = vertex[base + stride * min(0x##l, lanes - 1)]; \
    px.s##l = p.x;                                                  \
    py.s##l = p.y;                                                  \
    pz.s##l = p.z;                                                  \
    pw.s##l = p.w;                                                  \
  }
  EMF_LANES(ESTEP_LOAD)
#undef ESTEP_LOAD
  const floatW x = r0.x * px + r0.y * py + r0.z * pz + r0.w;
  const floatW y = r1.x * px + r1.y * py + r1.z * pz + r1.w;
  const floatW z = r2.x * px + r2.y * py + r2.z * pz + r2.w;
  const float3 extent = (float3)((float)(dims.x * EMF_BLOCK), (float)(dims.y * EMF_BLOCK),
                                 (float)(dims.z * EMF_BLOCK)) *
                        voxel_size;
  const intW inside = (pw != 0.0f) & (x >= 0.0f) & (y >= 0.0f) & (z >= 0.0f) & (x < extent.x) &
                      (y < extent.y) & (z < extent.z) & (x >= claim_lo.x) & (y >= claim_lo.y) &
                      (z >= claim_lo.z) & (x < claim_hi.x) & (y < claim_hi.y) & (z < claim_hi.z);
  // The first volume (background) outside every object rectangle: only "inside" matters.
  // Decided per EMF_ESTEP_EXACT_COLS grid columns whatever EMF_W is: the same pixels are exact
  // (and have a residual) at every lane width.
  const int group_col = rect.x + stride * (gx / EMF_ESTEP_EXACT_COLS * EMF_ESTEP_EXACT_COLS);
  int exact = !first || cover.count < 0;
  for (int r = 0; r < min(cover.count, EMF_ESTEP_COVER_RECTS) && !exact; ++r) {
    const int4 c = cover.rects[r];
    exact = row >= c.y && row < c.y + c.w && group_col < c.x + c.z &&
            group_col + (EMF_ESTEP_EXACT_COLS - 1) * stride >= c.x;
  }
  floatW lik = 0.0f;
  floatW abs_psi = NAN;
  if (!exact) {
    lik = select((floatW)0.0f, (floatW)1.0f, inside);
  } else if (any(inside)) {
    floatW weight, gx, gy, gz;
    const floatW psi = emf_sample_sdf_lanes(index, dims, voxels, voxel_size, truncation, x, y, z,
                                            &weight, &gx, &gy, &gz);
    const floatW abs_psi_in = (!isnan(psi) & (weight >= min_weight)) ? fabs(psi) : truncation;
    const floatW pfg =
        has_counts ? emf_sample_pfg_lanes(count_index, dims, voxels, voxel_size, x, y, z) : 1.0f;
    const floatW lik_in = pfg_mode ? (has_counts ? pfg : (floatW)1.0f)
                                   : alpha / (2.0f * sigma) * exp(-abs_psi_in / sigma) * pfg +
                                         (1.0f - alpha) * p_uniform;
    lik = inside ? lik_in : 0.0f;
    abs_psi = inside ? abs_psi_in : NAN;
  }
  // A later volume's likelihood of 0 leaves the sum and the best as they are (x + 0 = x for the
  // sum's x >= 0, fmax(x, 0) = x, and 0 > best never holds): an item without a positive lane
  // neither reads nor writes them.
  const int update = first || any(lik > 0.0f);
#define ESTEP_STORE(l)                            \
  if (0x##l < lanes) {                            \
    const int u = base + stride * 0x##l;          \
    const float lk = lik.s##l, ap = abs_psi.s##l; \
    likelihood[u] = lk;                           \
    if (!update) {                                \
    } else if (pfg_mode) {                        \
      if (first) {                                \
        sum[u] = 0.0f;                            \
        residual[u] = ap;                         \
      } else {                                    \
        sum[u] = fmax(sum[u], lk);                \
      }                                           \
    } else if (first) {                           \
      sum[u] = lk;                                \
      best[u] = lk;                               \
      residual[u] = lk > 0.0f ? ap : NAN;         \
    } else {                                      \
      sum[u] += lk;                               \
      if (lk > best[u]) {                         \
        best[u] = lk;                             \
        residual[u] = ap;                         \
      }                                           \
    }                                             \
  }
  EMF_LANES(ESTEP_STORE)
#undef ESTEP_STORE
  // An object's claimed pixels (likelihood > 0, hence q > 0): their bounding rectangle as
  // (min x, min y, -max x, -max y) in claimed_rects[4 volume ..], all kept by atomic_min (the
  // host fills them with INT_MAX before the pass). Read first: most items change
  // nothing, and atomics are costly on CPUs.
  const intW claims = (lik > 0.0f) & (EMF_LANE_IDS < lanes);
  if (!first && any(claims)) {
    // The first and the last claiming lane, by halving (no branch per lane).
    intW lo = select((intW)(EMF_W), EMF_LANE_IDS, claims);
    intW hi = select((intW)(-1), EMF_LANE_IDS, claims);
#if EMF_W == 16
    const int8 lo8 = min(lo.lo, lo.hi), hi8 = max(hi.lo, hi.hi);
#elif EMF_W == 8
    const int8 lo8 = lo, hi8 = hi;
#endif
#if EMF_W >= 8
    const int4 lo4 = min(lo8.lo, lo8.hi), hi4 = max(hi8.lo, hi8.hi);
#else
    const int4 lo4 = lo, hi4 = hi;
#endif
    const int2 lo2 = min(lo4.lo, lo4.hi), hi2 = max(hi4.lo, hi4.hi);
    const int x_lo = col + stride * min(lo2.x, lo2.y), x_hi = col + stride * max(hi2.x, hi2.y);
    __global int* claimed = claimed_rects + 4 * volume;
    if (claimed[0] > x_lo) atomic_min(&claimed[0], x_lo);
    if (claimed[1] > row) atomic_min(&claimed[1], row);
    if (claimed[2] > -x_hi) atomic_min(&claimed[2], -x_hi);
    if (claimed[3] > -row) atomic_min(&claimed[3], -row);
  }
}

/// q_i(u) = likelihood_i(u) / sum(u) (0 where the sum is 0) over the grid `rect` (x0, y0,
/// columns, rows) of every `stride`-th pixel, one work item per pixel (as estep_likelihood_lanes).
/// pfg_mode: objects keep their p_fg, the background (is_background) gets its own value times
/// 1 - max object p_fg.
__kernel void estep_normalize(__global float* q, __global const float* likelihood,
                              __global const float* sum, const int width, const int4 rect,
                              const int pfg_mode, const int is_background, const int stride) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= rect.z || y >= rect.w) return;
  const int u = (rect.y + stride * y) * width + rect.x + stride * x;
  const float s = sum[u];
  const float lk = likelihood[u];
  if (pfg_mode) {
    q[u] = is_background ? lk * (1.0f - s) : lk;
    return;
  }
  q[u] = s > 0.0f ? lk / s : 0.0f;
}

/// The running sum of an object whose likelihood is that of the previous E-step (same volume,
/// same pose; only the background moved): sum += likelihood (pfg_mode: the max) over `rect`,
/// as estep_likelihood_lanes does for a volume after the first.
__kernel void estep_accumulate(__global const float* likelihood, __global float* sum,
                               const int width, const int4 rect, const int pfg_mode) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= rect.z || y >= rect.w) return;
  const int u = (rect.y + y) * width + rect.x + x;
  sum[u] = pfg_mode ? fmax(sum[u], likelihood[u]) : sum[u] + likelihood[u];
}

/// q = 0 over the rectangle `rect` (x0, y0, width, height): the part of an object's q that a
/// previous E-step wrote outside this one's rectangle.
__kernel void estep_clear(__global float* q, const int width, const int4 rect) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= rect.z || y >= rect.w) return;
  q[(rect.y + y) * width + rect.x + x] = 0.0f;
}
