// Projective TSDF integration of one depth image into the listed blocks of one volume
// (docs/method.md#integration), with the per-pixel association weight q, the weight cap W_max, the
// authors' free-space rule, and the foreground/background count update of object volumes.
//
// integrate_blocks: one work-group per listed block (from assign_blocks), 512 / EMF_W work items
// of EMF_W voxels each (explicit SIMD; an item's voxels are read and stored only when one of them
// is observed, which skips the parts of a block hidden behind the surface). Each voxel centre
// is projected to its nearest pixel u; with d = D(u) - z (projective distance along the camera
// axis):
//   d < -truncation                skipped (occluded / behind the surface)
//   -truncation <= d <= truncation band: observation tsdf = d / truncation with weight q(u),
//                                  with behind_dropoff x (truncation + d) / (truncation - voxel)
//                                  for d < -voxel (Voxblox's drop-off: a projective distance
//                                  behind the surface overestimates the true one, most of all
//                                  near edges seen from the side)
//   d > truncation                 free space: tsdf = 1 with weight q(u), or 1 when
//                                  free_space_full_weight (the authors' code)
//   psi <- (W psi + w tsdf) / (W + w),  W <- min(W_max, W + w)   (skipped when w <= 0)
//   w is scaled by weight_scale: n when the volume integrates each block on every n-th frame
//   (VolumeSpec::integrate_every), so that a voxel averages and forgets over as many frames.
// count_blocks (object volumes, detection frames): with the detection mask m (p_fg of the
// detection per pixel; NaN where the object is occluded or no update is wanted), voxels in the
// band (|d| <= truncation) get Fg += m(u), Bg += 1 - m(u). Same projection as integrate_blocks;
// one work-group of 512 work items (one per voxel) per block.
#include "map_common.clh"

/// rint for |x| < 2^22 without a builtin call (round half to even, the default FP mode):
/// adding and subtracting 1.5 * 2^23 drops the fraction bits with IEEE rounding.
inline float emf_round_even(float x) { return (x + 12582912.0f) - 12582912.0f; }
inline floatW emf_round_even_lanes(floatW x) { return (x + 12582912.0f) - 12582912.0f; }

/// Camera-frame centre of voxel `lid` (0..511, x fastest) of block `lin`: pc = (xc, yc, zc).
#define EMF_VOXEL_IN_CAMERA(lin, lid)                                                    \
  const int plane = dims.x * dims.y;                                                     \
  const int bz = (lin) / plane;                                                          \
  const int by = ((lin)-bz * plane) / dims.x;                                            \
  const int bx = (lin)-bz * plane - by * dims.x;                                         \
  const float px_v = ((float)(bx * EMF_BLOCK + ((lid)&7)) + 0.5f) * voxel_size;          \
  const float py_v = ((float)(by * EMF_BLOCK + (((lid) >> 3) & 7)) + 0.5f) * voxel_size; \
  const float pz_v = ((float)(bz * EMF_BLOCK + ((lid) >> 6)) + 0.5f) * voxel_size;       \
  const float xc = r0.x * px_v + r0.y * py_v + r0.z * pz_v + r0.w;                       \
  const float yc = r1.x * px_v + r1.y * py_v + r1.z * pz_v + r1.w;                       \
  const float zc = r2.x * px_v + r2.y * py_v + r2.z * pz_v + r2.w;                       \
  const float inv_z = 1.0f / zc;                                                         \
  const float u = fx * (xc * inv_z) + cx + 0.5f;                                         \
  const float v = fy * (yc * inv_z) + cy + 0.5f;                                         \
  const bool in_view =                                                                   \
      zc > 0.0f && u >= 0.0f && v >= 0.0f && u < (float)width && v < (float)height;      \
  const int pixel = in_view ? (int)v * width + (int)u : 0;                               \
  const float d_meas = depth[pixel];                                                     \
  const float sdf = d_meas - zc;                                                         \
  /* NaN depth fails every comparison. */                                                \
  const bool observed = in_view && d_meas > 0.0f && sdf >= -truncation;

// integrate_blocks runs EMF_BLOCK_VOXELS / EMF_W work items per block, each on EMF_W consecutive
// voxels held in the lanes of floatW vectors (common.clh): PoCL does not vectorise the
// one-voxel-per-item form (clang's front end packs pairs of its scalar operations into 2-wide
// vectors, which keeps the work-item loop scalar), so the SIMD is spelled out. Per lane the
// operations are those of one voxel above.
#define EMF_INTEGRATE_ITEMS (EMF_BLOCK_VOXELS / EMF_W)

/// A voxel word (see EMF_WORD_TSDF) from its quantised TSDF and weight (intW lanes).
#ifdef __ENDIAN_LITTLE__
#define EMF_MAKE_WORDS(t, w) (((t)&0xffff) | ((w) << 16))
#else
#define EMF_MAKE_WORDS(t, w) (((w)&0xffff) | ((t) << 16))
#endif

__kernel __attribute__((reqd_work_group_size(EMF_INTEGRATE_ITEMS, 1, 1))) void integrate_blocks(
    __global const int* block_list, __global const int* index, const int4 dims,
    __global short2* voxels, __global const float* depth, __global const float* weights,
    const int has_weights, const int width, const int height, const float fx, const float fy,
    const float cx, const float cy, const float4 r0, const float4 r1, const float4 r2,
    const float voxel_size, const float truncation, const float inv_truncation,
    const float max_weight, const int free_space_full_weight, const int behind_dropoff,
    const float weight_scale) {
  const int lin = block_list[get_group_id(0)];
  const int slot = index[lin];
  const int plane = dims.x * dims.y;
  const int bz = lin / plane;
  const int by = (lin - bz * plane) / dims.x;
  const int bx = lin - bz * plane - by * dims.x;
  // Voxels EMF_W * item .. EMF_W * item + EMF_W - 1 of the block (x fastest).
  const intW vid = (intW)(get_local_id(0) * EMF_W) + EMF_LANE_IDS;
  const floatW px_v = (convert_floatW(bx * EMF_BLOCK + (vid & 7)) + 0.5f) * voxel_size;
  const floatW py_v = (convert_floatW(by * EMF_BLOCK + ((vid >> 3) & 7)) + 0.5f) * voxel_size;
  const floatW pz_v = (convert_floatW(bz * EMF_BLOCK + (vid >> 6)) + 0.5f) * voxel_size;
  const floatW xc = r0.x * px_v + r0.y * py_v + r0.z * pz_v + r0.w;
  const floatW yc = r1.x * px_v + r1.y * py_v + r1.z * pz_v + r1.w;
  const floatW zc = r2.x * px_v + r2.y * py_v + r2.z * pz_v + r2.w;
  const floatW inv_z = 1.0f / zc;
  const floatW u = fx * (xc * inv_z) + cx + 0.5f;
  const floatW v = fy * (yc * inv_z) + cy + 0.5f;
  const intW in_view =
      (zc > 0.0f) & (u >= 0.0f) & (v >= 0.0f) & (u < (float)width) & (v < (float)height);
  // Lanes out of view read pixel 0 (converted from 0, never from NaN or out-of-range values).
  const intW pixel = convert_intW(in_view ? v : 0.0f) * width + convert_intW(in_view ? u : 0.0f);
  floatW d_meas;
#define EMF_INTEGRATE_READ_DEPTH(l) d_meas.s##l = depth[pixel.s##l];
  EMF_LANES(EMF_INTEGRATE_READ_DEPTH)
#undef EMF_INTEGRATE_READ_DEPTH
  const floatW sdf = d_meas - zc;
  // NaN depth fails every comparison.
  const intW observed = in_view & (d_meas > 0.0f) & (sdf >= -truncation);
  // Voxels out of view, without depth or hidden behind the surface keep their word: when none of
  // the item's lanes is observed, neither q nor the voxels are read.
  if (!any(observed)) return;
  floatW q = 1.0f;
  if (has_weights) {
#define EMF_INTEGRATE_READ_Q(l) q.s##l = weights[pixel.s##l];
    EMF_LANES(EMF_INTEGRATE_READ_Q)
#undef EMF_INTEGRATE_READ_Q
  }
  const intW free_space = sdf > truncation;
  floatW w = (free_space & (intW)(free_space_full_weight ? -1 : 0)) ? 1.0f : q;
  if (behind_dropoff) {
    const floatW drop = (truncation + sdf) / (truncation - voxel_size);
    w = sdf < -voxel_size ? w * (drop > 0.0f ? drop : 0.0f) : w;
  }
  w *= weight_scale;
  __global int* words = (__global int*)voxels + slot * EMF_BLOCK_VOXELS + get_local_id(0) * EMF_W;
  const intW raw = vloadW(0, words);
  const intW old_t = EMF_WORD_TSDF(raw);
  const intW old_w = EMF_WORD_WEIGHT(raw);
  const floatW w_old = convert_floatW(old_w) / EMF_WEIGHT_SCALE;
  const floatW w_sum = w_old + w;
  const floatW tsdf_obs = sdf * inv_truncation < 1.0f ? sdf * inv_truncation : 1.0f;
  floatW tsdf_new = (w_old * (convert_floatW(old_t) / EMF_TSDF_SCALE) + w * tsdf_obs) / w_sum;
  tsdf_new = tsdf_new < -1.0f ? -1.0f : (tsdf_new > 1.0f ? 1.0f : tsdf_new);
  floatW w_new = w_sum < max_weight ? w_sum : max_weight;
  w_new = w_new < 32767.0f / EMF_WEIGHT_SCALE ? w_new : 32767.0f / EMF_WEIGHT_SCALE;
  const intW update = observed & (w > 0.0f);
  // Converted only where updated (elsewhere tsdf_new may be NaN: 0 / 0).
  const intW new_t = convert_intW(emf_round_even_lanes(update ? tsdf_new * EMF_TSDF_SCALE : 0.0f));
  const intW new_w = convert_intW(emf_round_even_lanes(update ? w_new * EMF_WEIGHT_SCALE : 0.0f));
  vstoreW(update ? EMF_MAKE_WORDS(new_t, new_w) : raw, 0, words);
}

__kernel void count_blocks(__global const int* block_list, __global const int* count_index,
                           const int4 dims, __global short2* voxels, __global const float* depth,
                           __global const float* fg_mask, const int width, const int height,
                           const float fx, const float fy, const float cx, const float cy,
                           const float4 r0, const float4 r1, const float4 r2,
                           const float voxel_size, const float truncation) {
  const int lin = block_list[get_group_id(0)];
  const int count_slot = count_index[lin];
  const int lid = get_local_id(0);
  EMF_VOXEL_IN_CAMERA(lin, lid)
  if (count_slot < 0 || !observed || sdf > truncation) return;
  const float m = fg_mask[pixel];
  if (!emf_is_valid(m)) return;
  __global short2* c = voxels + count_slot * EMF_BLOCK_VOXELS + lid;
  *c = emf_add_counts(*c, m);
}
