#include "cl/image_scale.h"

#include <cmath>

namespace emf::cl {

void scaleImage(Context& ctx, const MemHandle& in, const MemHandle& out, int count, float a,
                float b) {
  KernelHandle k = ctx.kernel("image_scale", "scale_image");
  setArgs(k, in, out, count, a, b);
  enqueue(ctx.queue(), k, static_cast<size_t>(count), 0, 0, 64);
}

std::vector<float> scaleImageReference(const std::vector<float>& in, float a, float b) {
  std::vector<float> out(in.size());
  for (size_t i = 0; i < in.size(); ++i) out[i] = std::isnan(in[i]) ? in[i] : a * in[i] + b;
  return out;
}

}  // namespace emf::cl
