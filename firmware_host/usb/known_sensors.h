// USB ids of RGB-D sensors and the emf backend that serves each.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace emf::fw {

struct KnownSensor {
  uint16_t vendor_id;
  uint16_t product_id;  // 0 = any product of this vendor (vendor-wide fallback)
  const char* name;
  const char* backend;  // "openni2", "v4l2" or a note on what is needed
};

/// The table (exact vendor:product entries first, then vendor-wide fallbacks).
const std::vector<KnownSensor>& knownSensors();

/// The entry for a USB id, or nullptr when it is not a known RGB-D sensor. Exact product ids
/// win over vendor-wide entries.
const KnownSensor* findKnownSensor(uint16_t vendor_id, uint16_t product_id);

/// "1d27:0601".
std::string usbIdText(uint16_t vendor_id, uint16_t product_id);

}  // namespace emf::fw
