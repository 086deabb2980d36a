#include "core/frame.h"

#include <cmath>
#include <sstream>

#include "common/error.h"

namespace emf::core {

Intrinsics checkedIntrinsics(const Intrinsics& k) {
  std::ostringstream what;
  what << "camera intrinsics fx=" << k.fx << " fy=" << k.fy << " cx=" << k.cx << " cy=" << k.cy
       << " size " << k.width << "x" << k.height << ": ";
  auto fail = [&](const std::string& why) {
    throw InvalidArgument(what.str() + why + " (check the calibration: fx fy cx cy in pixels)");
  };
  if (k.width < 1 || k.height < 1 || k.width > kMaxImageSide || k.height > kMaxImageSide) {
    fail("the image size must be in [1, " + std::to_string(kMaxImageSide) + "] pixels per side");
  }
  if (!std::isfinite(k.fx) || !std::isfinite(k.fy) || k.fx < k.width / 20.0 ||
      k.fy < k.height / 20.0) {
    fail("focal lengths must be finite and at least 1/20 of the image side");
  }
  if (k.fx > kMaxFocalPerSide * k.width || k.fy > kMaxFocalPerSide * k.height) {
    fail("focal lengths must be at most " + std::to_string(static_cast<int>(kMaxFocalPerSide)) +
         " image sides (a field of view under 0.6 deg is not a depth camera)");
  }
  if (!std::isfinite(k.cx) || !std::isfinite(k.cy) || k.cx < -k.width || k.cx > 2.0 * k.width ||
      k.cy < -k.height || k.cy > 2.0 * k.height) {
    fail("the principal point must lie at most one image side outside the image");
  }
  return k;
}

}  // namespace emf::core
