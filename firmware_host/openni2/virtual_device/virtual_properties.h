// Stream properties of the emf virtual OpenNI2 device beyond OpenNI2's standard ones, shared by
// the driver (which must not link libemf) and Openni2Source. OpenNI2 passes property ids it does
// not know through to the driver, as it does for vendors' own properties.
#pragma once

namespace emf::fw::virtual_device {

/// The stream's full pinhole calibration in pixels at its resolution (OpenNI2 itself has only
/// fields of view, which cannot carry a principal point off the image centre).
constexpr int kPinholeProperty = 0x2E4D0001;

struct PinholeProperty {
  double fx, fy, cx, cy;
};

}  // namespace emf::fw::virtual_device
