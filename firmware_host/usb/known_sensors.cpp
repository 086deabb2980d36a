#include "firmware_host/usb/known_sensors.h"

#include <cstdio>

namespace emf::fw {

const std::vector<KnownSensor>& knownSensors() {
  // Structured-light PS1080 devices are served by Debian's OpenNI2 PS1080 driver; Intel
  // RealSense D400/SR300/L500 cameras expose Z16 depth and YUYV colour through uvcvideo.
  static const std::vector<KnownSensor> kTable = {
      {0x1d27, 0x0600, "PrimeSense PS1080 sensor / Asus Xtion PRO", "openni2"},
      {0x1d27, 0x0601, "PrimeSense Carmine 1.08/1.09 / Asus Xtion PRO LIVE", "openni2"},
      {0x1d27, 0x0609, "PrimeSense Carmine 1.09 (short range)", "openni2"},
      {0x045e, 0x02ae, "Microsoft Kinect v1 (Xbox 360) camera",
       "openni2 with a libfreenect OpenNI2 driver (not shipped by Debian's libopenni2)"},
      {0x045e, 0x02bf, "Microsoft Kinect for Windows v1 camera",
       "openni2 with a libfreenect OpenNI2 driver (not shipped by Debian's libopenni2)"},
      {0x045e, 0x02c4, "Microsoft Kinect v2 (Xbox One)",
       "none in emf (needs libfreenect2's OpenNI2 driver)"},
      {0x045e, 0x02d8, "Microsoft Kinect v2 for Windows",
       "none in emf (needs libfreenect2's OpenNI2 driver)"},
      {0x2bc5, 0x0401, "Orbbec Astra", "openni2 (Orbbec's OpenNI2 driver)"},
      {0x2bc5, 0x0402, "Orbbec Astra S", "openni2 (Orbbec's OpenNI2 driver)"},
      {0x2bc5, 0x0403, "Orbbec Astra Pro", "openni2 (Orbbec's OpenNI2 driver) + v4l2 colour"},
      {0x2bc5, 0x0404, "Orbbec Astra Mini", "openni2 (Orbbec's OpenNI2 driver)"},
      {0x8086, 0x0aa5, "Intel RealSense SR300", "v4l2"},
      {0x8086, 0x0ad3, "Intel RealSense D415", "v4l2"},
      {0x8086, 0x0b07, "Intel RealSense D435", "v4l2"},
      {0x8086, 0x0b3a, "Intel RealSense D435i", "v4l2"},
      {0x8086, 0x0b5b, "Intel RealSense D405", "v4l2"},
      {0x8086, 0x0b5c, "Intel RealSense D455", "v4l2"},
      {0x8086, 0x0b64, "Intel RealSense L515", "v4l2"},
      // Vendor-wide fallbacks (Intel's vendor id covers far more than cameras: no fallback).
      {0x1d27, 0, "PrimeSense-based sensor", "openni2"},
      {0x2bc5, 0, "Orbbec sensor", "openni2 (Orbbec's OpenNI2 driver) or v4l2, by model"},
  };
  return kTable;
}

const KnownSensor* findKnownSensor(uint16_t vendor_id, uint16_t product_id) {
  const KnownSensor* vendor_match = nullptr;
  for (const auto& s : knownSensors()) {
    if (s.vendor_id != vendor_id) continue;
    if (s.product_id == product_id) return &s;
    if (s.product_id == 0 && vendor_match == nullptr) vendor_match = &s;
  }
  return vendor_match;
}

std::string usbIdText(uint16_t vendor_id, uint16_t product_id) {
  char text[16];
  std::snprintf(text, sizeof(text), "%04x:%04x", vendor_id, product_id);
  return text;
}

}  // namespace emf::fw
