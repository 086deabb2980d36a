// Host wrapper of kernels_cl/image_scale.cl and its CPU reference.
#pragma once

#include <vector>

#include "cl/context.h"

namespace emf::cl {

/// out[i] = a * in[i] + b on the device; NaN stays NaN. `in` and `out` hold `count` floats.
void scaleImage(Context& ctx, const MemHandle& in, const MemHandle& out, int count, float a,
                float b);

/// CPU reference of scaleImage.
std::vector<float> scaleImageReference(const std::vector<float>& in, float a, float b);

}  // namespace emf::cl
