// Projective TSDF integration of one depth image into the listed blocks of one volume
// (METHOD.md step 4), with the per-pixel association weight q, the weight cap W_max, the
// authors' free-space rule, and the foreground/background count update of object volumes.
//
// integrate_blocks: one work-group of 512 work-items per listed block (from assign_blocks), one
// work-item per voxel. Scalar, branch-free code with one unconditional store per voxel, so that
// CPU compilers (PoCL) can vectorise the work-item loop. Each voxel centre is projected to its
// nearest pixel u; with d = D(u) - z (projective distance along the camera axis):
//   d < -truncation                skipped (occluded / behind the surface)
//   -truncation <= d <= truncation band: observation tsdf = d / truncation with weight q(u)
//   d > truncation                 free space: tsdf = 1 with weight q(u), or 1 when
//                                  free_space_full_weight (the authors' code)
//   psi <- (W psi + w tsdf) / (W + w),  W <- min(W_max, W + w)   (skipped when w <= 0)
// count_blocks (object volumes, detection frames): with the detection mask m (p_fg of the
// detection per pixel; NaN where the object is occluded or no update is wanted), voxels in the
// band (|d| <= truncation) get Fg += m(u), Bg += 1 - m(u). Same projection as integrate_blocks.
#include "map_common.clh"

/// rint for |x| < 2^22 without a builtin call (round half to even, the default FP mode):
/// adding and subtracting 1.5 * 2^23 drops the fraction bits with IEEE rounding.
inline float emf_round_even(float x) { return (x + 12582912.0f) - 12582912.0f; }

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

__kernel void integrate_blocks(__global const int* block_list, __global const int* index,
                               const int4 dims, __global short2* voxels,
                               __global const float* depth, __global const float* weights,
                               const int has_weights, const int width, const int height,
                               const float fx, const float fy, const float cx, const float cy,
                               const float4 r0, const float4 r1, const float4 r2,
                               const float voxel_size, const float truncation,
                               const float inv_truncation, const float max_weight,
                               const int free_space_full_weight) {
  const int lin = block_list[get_group_id(0)];
  const int slot = index[lin];
  const int lid = get_local_id(0);
  EMF_VOXEL_IN_CAMERA(lin, lid)
  const float q = has_weights ? weights[pixel] : 1.0f;
  const bool free_space = sdf > truncation;
  const float w = (free_space && free_space_full_weight) ? 1.0f : q;
  __global short* raw = (__global short*)voxels + 2 * (slot * EMF_BLOCK_VOXELS + lid);
  const short old_t = raw[0];
  const short old_w = raw[1];
  const float w_old = (float)old_w / EMF_WEIGHT_SCALE;
  const float w_sum = w_old + w;
  const float tsdf_obs = sdf * inv_truncation < 1.0f ? sdf * inv_truncation : 1.0f;
  float tsdf_new = (w_old * ((float)old_t / EMF_TSDF_SCALE) + w * tsdf_obs) / w_sum;
  tsdf_new = tsdf_new < -1.0f ? -1.0f : (tsdf_new > 1.0f ? 1.0f : tsdf_new);
  float w_new = w_sum < max_weight ? w_sum : max_weight;
  w_new = w_new < 32767.0f / EMF_WEIGHT_SCALE ? w_new : 32767.0f / EMF_WEIGHT_SCALE;
  const bool update = observed && w > 0.0f;
  raw[0] = update ? (short)emf_round_even(tsdf_new * EMF_TSDF_SCALE) : old_t;
  raw[1] = update ? (short)emf_round_even(w_new * EMF_WEIGHT_SCALE) : old_w;
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
