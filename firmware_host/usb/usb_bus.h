// USB enumeration behind an interface, so discovery and hot-plug logic can be driven by a
// simulated bus in tests (FakeUsbBus in tests/firmware_host) and by libusb on a robot.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "firmware_host/usb/known_sensors.h"

namespace emf::fw {

/// One device on the bus.
struct UsbDevice {
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  int bus = 0;
  int address = 0;        // changes when a device is re-plugged
  std::string port_path;  // physical port, "1-2.3" (stable across re-plugs in the same port)

  /// Identity of the physical slot: the same sensor re-plugged into the same port keeps it.
  std::string key() const;
};

class UsbBus {
 public:
  virtual ~UsbBus() = default;
  /// The devices connected now. Throws IoError when the bus cannot be read.
  virtual std::vector<UsbDevice> list() = 0;
  /// "libusb", "fake" (for messages).
  virtual std::string name() const = 0;
};

/// The real bus through libusb-1.0. Throws IoError when libusb cannot be initialised (e.g. no
/// /dev/bus/usb in a container).
std::unique_ptr<UsbBus> openLibusbBus();

/// A connected device that is a known RGB-D sensor.
struct DetectedSensor {
  UsbDevice device;
  const KnownSensor* info = nullptr;
};

/// The known RGB-D sensors among `devices`.
std::vector<DetectedSensor> findSensors(const std::vector<UsbDevice>& devices);

}  // namespace emf::fw
