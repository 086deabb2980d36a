// Projective TSDF integration of one depth image into the listed blocks of one volume
// (METHOD.md step 4), with the per-pixel association weight q, the weight cap W_max, the
// authors' free-space rule, and the foreground/background count update of object volumes.
//
// One work-group of 64 work-items per listed block (from assign_blocks); work-item (x, y) walks
// the block's 8 voxels along z. Each voxel centre is projected to its nearest pixel u; with
// d = D(u) - z (projective distance along the camera axis):
//   d < -truncation                skipped (occluded / behind the surface)
//   -truncation <= d <= truncation band: observation tsdf = d / truncation with weight q(u)
//   d > truncation                 free space: tsdf = 1 with weight q(u), or 1 when
//                                  free_space_full_weight (the authors' code)
//   psi <- (W psi + w tsdf) / (W + w),  W <- min(W_max, W + w)   (skipped when w <= 0)
// Object volumes with a detection mask m (p_fg of the detection per pixel; NaN where the object
// is occluded or no update is wanted): voxels in the band get Fg += m(u), Bg += 1 - m(u).
#include "map_common.clh"

__kernel void integrate_blocks(
    __global const int* block_list, __global const int* index, __global const int* count_index,
    const int has_counts, const int4 dims, __global short2* voxels, __global const float* depth,
    __global const float* weights, const int has_weights, __global const float* fg_mask,
    const int has_mask, const int width, const int height, const float fx, const float fy,
    const float cx, const float cy, const float4 r0, const float4 r1, const float4 r2,
    const float voxel_size, const float truncation, const float max_weight,
    const int free_space_full_weight) {
  const int lin = block_list[get_group_id(0)];
  const int slot = index[lin];
  const int count_slot = has_counts ? count_index[lin] : -1;
  const int lid = get_local_id(0);
  const int lx = lid & 7;
  const int ly = lid >> 3;
  const int4 base = emf_block_coords(dims, lin) * EMF_BLOCK;
  for (int lz = 0; lz < EMF_BLOCK; ++lz) {
    const int4 v = base + (int4)(lx, ly, lz, 0);
    const float3 pc = emf_transform(r0, r1, r2, emf_voxel_centre(v, voxel_size));
    if (pc.z <= 0.0f) continue;
    const int2 px = emf_project(pc, fx, fy, cx, cy, width, height);
    if (px.x < 0) continue;
    const int pixel = px.y * width + px.x;
    const float d_meas = depth[pixel];
    if (!emf_is_valid(d_meas) || d_meas <= 0.0f) continue;
    const float sdf = d_meas - pc.z;
    if (sdf < -truncation) continue;
    const float q = has_weights ? weights[pixel] : 1.0f;
    const bool free_space = sdf > truncation;
    const float w = (free_space && free_space_full_weight) ? 1.0f : q;
    const int local_index = lx + EMF_BLOCK * (ly + EMF_BLOCK * lz);
    if (w > 0.0f) {
      const float tsdf = fmin(1.0f, sdf / truncation);
      const short2 old = voxels[slot * EMF_BLOCK_VOXELS + local_index];
      const float w_old = emf_voxel_weight(old);
      const float w_sum = w_old + w;
      const float tsdf_new = (w_old * emf_voxel_tsdf(old) + w * tsdf) / w_sum;
      voxels[slot * EMF_BLOCK_VOXELS + local_index] = emf_make_voxel(tsdf_new, fmin(max_weight, w_sum));
    }
    if (count_slot >= 0 && has_mask && !free_space) {
      const float m = fg_mask[pixel];
      if (emf_is_valid(m)) {
        const int ci = count_slot * EMF_BLOCK_VOXELS + local_index;
        voxels[ci] = emf_add_counts(voxels[ci], m);
      }
    }
  }
}
