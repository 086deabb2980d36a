// Hot-plug monitoring of RGB-D sensors on the USB bus.
//
// Documented behaviour:
//  - A known sensor that appears is reported once (kPlugged) and is then kConnected.
//  - A sensor that disappears is reported as an error (kUnplugged, with a message saying that
//    its stream stops and what to do) and stays known in state kUnplugged: `emf devices --watch`
//    and the runtime report it as an error state instead of waiting for frames forever.
//  - The same sensor re-plugged into the same port (same vendor:product and port path; the USB
//    address changes) is reported as kReplugged and is kConnected again; sources wrapped in a
//    ReconnectingSource then resume on their own.
// The monitor polls a UsbBus (libusb in production, a simulated bus in tests): poll() can be
// called from the owner's loop, or start() runs it on a background thread with a callback.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "firmware_host/usb/usb_bus.h"

namespace emf::fw {

enum class SensorPresence { kConnected, kUnplugged };

struct SensorEvent {
  enum class Type { kPlugged, kUnplugged, kReplugged };
  Type type;
  DetectedSensor sensor;
  std::string message;  // one line for logs / `emf devices --watch`
};

/// "plugged", "unplugged", "replugged".
const char* sensorEventName(SensorEvent::Type type);

class HotplugMonitor {
 public:
  /// `bus` must outlive the monitor.
  explicit HotplugMonitor(UsbBus& bus);
  ~HotplugMonitor();

  /// Reads the bus once and returns what changed since the last poll (the first poll reports
  /// every sensor present as kPlugged). Throws IoError when the bus cannot be read.
  std::vector<SensorEvent> poll();

  struct Entry {
    DetectedSensor sensor;
    SensorPresence presence = SensorPresence::kConnected;
    int unplugs = 0;
    std::string error;  // set while unplugged
  };
  /// Every sensor seen so far, by UsbDevice::key().
  std::vector<Entry> sensors() const;

  /// Polls every `interval_s` on a background thread and calls `on_event` (from that thread)
  /// for each event; bus errors are passed as an empty-sensor kUnplugged event with the message.
  void start(double interval_s, std::function<void(const SensorEvent&)> on_event);
  /// Stops the background thread (waits at most one poll). Also done by the destructor.
  void stop();

 private:
  UsbBus& bus_;
  mutable std::mutex mutex_;  // guards entries_ and bus_ access
  std::map<std::string, Entry> entries_;
  std::thread thread_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;  // guarded by wake_mutex_
};

}  // namespace emf::fw
