// Trilinear SDF (psi, weight, gradient) and p_fg at N arbitrary points of one volume, through
// emf_sample_sdf / emf_sample_pfg of voxel_access.clh (the functions the tracking and E-step
// kernels call per pixel). Points are in the volume frame, metres (float4, .w ignored).
// Outputs: psi (metres, NaN where any of the 8 neighbours is unallocated or unobserved), weight,
// gradient (float4, .w = 0) and p_fg (0.5 without counts; 1 for volumes without counts).
#include "common.clh"
#include "voxel_access.clh"

#pragma OPENCL FP_CONTRACT OFF

__kernel void sample_sdf_points(__global const int* index, __global const int* count_index,
                                const int has_counts, const int4 dims,
                                __global const short2* voxels, const float voxel_size,
                                const float truncation, __global const float4* points,
                                const int count, __global float* psi_out,
                                __global float* weight_out, __global float4* gradient_out,
                                __global float* pfg_out) {
  const int i = get_global_id(0);
  if (i >= count) return;
  const float3 p = points[i].xyz;
  float weight = 0.0f;
  float3 gradient = (float3)(0.0f, 0.0f, 0.0f);
  const float psi =
      emf_sample_sdf(index, dims, voxels, voxel_size, truncation, p, &weight, &gradient);
  psi_out[i] = psi;
  weight_out[i] = emf_is_valid(psi) ? weight : 0.0f;
  gradient_out[i] = emf_is_valid(psi) ? (float4)(gradient, 0.0f) : (float4)(NAN, NAN, NAN, 0.0f);
  pfg_out[i] = has_counts ? emf_sample_pfg(count_index, dims, voxels, voxel_size, p) : 1.0f;
}

// The same through emf_sample_sdf_lanes and emf_sample_pfg_lanes (EMF_W points per work
// item, explicit SIMD; what track_accumulate and estep_likelihood_lanes use). Launch
// ceil(count / EMF_W) work items.
__kernel void sample_sdf_points_lanes(__global const int* index, __global const int* count_index,
                                      const int has_counts, const int4 dims,
                                      __global const short2* voxels, const float voxel_size,
                                      const float truncation, __global const float4* points,
                                      const int count, __global float* psi_out,
                                      __global float* weight_out, __global float4* gradient_out,
                                      __global float* pfg_out) {
  const int i0 = get_global_id(0) * EMF_W;
  if (i0 >= count) return;
  floatW px, py, pz;
#define SDFW_LOAD(l)                                     \
  {                                                      \
    const float4 p = points[min(i0 + 0x##l, count - 1)]; \
    px.s##l = p.x;                                       \
    py.s##l = p.y;                                       \
    pz.s##l = p.z;                                       \
  }
  EMF_LANES(SDFW_LOAD)
#undef SDFW_LOAD
  floatW weight, gx, gy, gz;
  const floatW psi = emf_sample_sdf_lanes(index, dims, voxels, voxel_size, truncation, px, py, pz,
                                          &weight, &gx, &gy, &gz);
  const floatW pfg =
      has_counts ? emf_sample_pfg_lanes(count_index, dims, voxels, voxel_size, px, py, pz) : 1.0f;
#define SDFW_STORE(l)                                                                   \
  if (i0 + 0x##l < count) {                                                             \
    const bool ok = emf_is_valid(psi.s##l);                                             \
    psi_out[i0 + 0x##l] = psi.s##l;                                                     \
    pfg_out[i0 + 0x##l] = pfg.s##l;                                                     \
    weight_out[i0 + 0x##l] = ok ? weight.s##l : 0.0f;                                   \
    gradient_out[i0 + 0x##l] =                                                          \
        ok ? (float4)(gx.s##l, gy.s##l, gz.s##l, 0.0f) : (float4)(NAN, NAN, NAN, 0.0f); \
  }
  EMF_LANES(SDFW_STORE)
#undef SDFW_STORE
}
