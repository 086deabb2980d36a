// Affine scaling of a float image: out = a * in + b. Invalid (NaN) pixels stay invalid.
// Used to convert raw depth units to metres and as the smoke test of the kernel path.
#include "common.clh"

__kernel void scale_image(__global const float* in, __global float* out, const int count,
                          const float a, const float b) {
  const int i = get_global_id(0);
  if (i >= count) return;
  const float v = in[i];
  out[i] = emf_is_valid(v) ? a * v + b : v;
}
