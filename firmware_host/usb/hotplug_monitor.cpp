#include "firmware_host/usb/hotplug_monitor.h"

#include <chrono>
#include <set>

#include "common/error.h"

namespace emf::fw {
namespace {

std::string describe(const DetectedSensor& s) {
  return std::string(s.info ? s.info->name : "USB device") + " (" +
         usbIdText(s.device.vendor_id, s.device.product_id) + " on bus " +
         std::to_string(s.device.bus) + " port " +
         (s.device.port_path.empty() ? "?" : s.device.port_path) + ")";
}

}  // namespace

const char* sensorEventName(SensorEvent::Type type) {
  switch (type) {
    case SensorEvent::Type::kPlugged:
      return "plugged";
    case SensorEvent::Type::kUnplugged:
      return "unplugged";
    case SensorEvent::Type::kReplugged:
      return "replugged";
  }
  return "?";
}

HotplugMonitor::HotplugMonitor(UsbBus& bus) : bus_(bus) {}

HotplugMonitor::~HotplugMonitor() { stop(); }

std::vector<SensorEvent> HotplugMonitor::poll() {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::vector<DetectedSensor> now = findSensors(bus_.list());
  std::vector<SensorEvent> events;
  std::set<std::string> present;
  for (const auto& s : now) {
    const std::string key = s.device.key();
    present.insert(key);
    auto it = entries_.find(key);
    if (it == entries_.end()) {
      Entry e;
      e.sensor = s;
      entries_[key] = e;
      events.push_back({SensorEvent::Type::kPlugged, s,
                        describe(s) + " connected (backend: " + s.info->backend + ")"});
    } else if (it->second.presence == SensorPresence::kUnplugged) {
      it->second.presence = SensorPresence::kConnected;
      it->second.sensor = s;  // new USB address
      it->second.error.clear();
      events.push_back(
          {SensorEvent::Type::kReplugged, s, describe(s) + " is back: streams resume"});
    }
  }
  for (auto& kv : entries_) {
    Entry& e = kv.second;
    if (e.presence == SensorPresence::kConnected && !present.count(kv.first)) {
      e.presence = SensorPresence::kUnplugged;
      ++e.unplugs;
      e.error = describe(e.sensor) +
                " was unplugged: its stream stops with an error; plug it back into the same "
                "port to resume";
      events.push_back({SensorEvent::Type::kUnplugged, e.sensor, e.error});
    }
  }
  return events;
}

std::vector<HotplugMonitor::Entry> HotplugMonitor::sensors() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<Entry> out;
  for (const auto& kv : entries_) out.push_back(kv.second);
  return out;
}

void HotplugMonitor::start(double interval_s, std::function<void(const SensorEvent&)> on_event) {
  stop();
  {
    std::lock_guard<std::mutex> l(wake_mutex_);
    stopping_ = false;
  }
  thread_ = std::thread([this, interval_s, on_event = std::move(on_event)] {
    const auto interval = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(interval_s));
    for (;;) {
      std::vector<SensorEvent> events;
      try {
        events = poll();
      } catch (const Error& e) {
        events.push_back({SensorEvent::Type::kUnplugged, DetectedSensor{}, e.what()});
      }
      for (const auto& ev : events) on_event(ev);
      std::unique_lock<std::mutex> l(wake_mutex_);
      if (wake_.wait_for(l, interval, [this] { return stopping_; })) return;
    }
  });
}

void HotplugMonitor::stop() {
  {
    std::lock_guard<std::mutex> l(wake_mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

}  // namespace emf::fw
