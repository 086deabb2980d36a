// Device discovery and hot-plug: the known-sensor table, the hot-plug monitor driven by a
// simulated USB bus (polled and on its own thread), the ReconnectingSource's documented error
// and recovery with a simulated sensor.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "common/error.h"
#include "firmware_host/reconnecting_source.h"
#include "firmware_host/sensor_error.h"
#include "firmware_host/usb/hotplug_monitor.h"
#include "firmware_host/usb/known_sensors.h"
#include "firmware_host/usb/usb_bus.h"

namespace emf::fw {
namespace {

/// A simulated USB bus: devices are plugged and unplugged by the test (thread-safe).
class FakeUsbBus : public UsbBus {
 public:
  void plug(const UsbDevice& d) {
    std::lock_guard<std::mutex> l(mutex_);
    devices_.push_back(d);
  }
  void unplug(const std::string& port_path) {
    std::lock_guard<std::mutex> l(mutex_);
    for (size_t i = 0; i < devices_.size(); ++i) {
      if (devices_[i].port_path == port_path) {
        devices_.erase(devices_.begin() + static_cast<long>(i));
        return;
      }
    }
  }
  void setBroken(bool broken) {
    std::lock_guard<std::mutex> l(mutex_);
    broken_ = broken;
  }
  std::vector<UsbDevice> list() override {
    std::lock_guard<std::mutex> l(mutex_);
    if (broken_) throw IoError("fake bus: cannot list devices");
    return devices_;
  }
  std::string name() const override { return "fake"; }

 private:
  std::mutex mutex_;
  std::vector<UsbDevice> devices_;
  bool broken_ = false;
};

UsbDevice device(uint16_t vid, uint16_t pid, int address, const std::string& port) {
  UsbDevice d;
  d.vendor_id = vid;
  d.product_id = pid;
  d.bus = 1;
  d.address = address;
  d.port_path = port;
  return d;
}

TEST(KnownSensors, ExactIdsVendorFallbackAndUnknown) {
  const KnownSensor* xtion = findKnownSensor(0x1d27, 0x0601);
  ASSERT_NE(xtion, nullptr);
  EXPECT_STREQ(xtion->backend, "openni2");
  const KnownSensor* d435 = findKnownSensor(0x8086, 0x0b07);
  ASSERT_NE(d435, nullptr);
  EXPECT_STREQ(d435->name, "Intel RealSense D435");
  EXPECT_STREQ(d435->backend, "v4l2");
  const KnownSensor* other_primesense = findKnownSensor(0x1d27, 0x1234);
  ASSERT_NE(other_primesense, nullptr);
  EXPECT_STREQ(other_primesense->name, "PrimeSense-based sensor");
  EXPECT_EQ(findKnownSensor(0x8086, 0x1234), nullptr);  // an Intel chipset is not a camera
  EXPECT_EQ(findKnownSensor(0x046d, 0xc077), nullptr);  // a mouse
  EXPECT_EQ(usbIdText(0x2bc5, 0x0401), "2bc5:0401");
  const auto found = findSensors({device(0x046d, 0xc077, 3, "1"), device(0x2bc5, 0x0401, 4, "2")});
  ASSERT_EQ(found.size(), 1u);
  EXPECT_STREQ(found[0].info->name, "Orbbec Astra");
}

TEST(HotplugMonitor, UnplugIsReportedAsErrorAndReplugRecovers) {
  FakeUsbBus bus;
  bus.plug(device(0x046d, 0xc077, 2, "1"));  // not a sensor: never reported
  bus.plug(device(0x1d27, 0x0601, 5, "3.1"));
  HotplugMonitor monitor(bus);

  auto ev = monitor.poll();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].type, SensorEvent::Type::kPlugged);
  EXPECT_NE(ev[0].message.find("1d27:0601 on bus 1 port 3.1"), std::string::npos) << ev[0].message;
  EXPECT_TRUE(monitor.poll().empty());

  bus.unplug("3.1");
  ev = monitor.poll();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].type, SensorEvent::Type::kUnplugged);
  EXPECT_NE(ev[0].message.find("was unplugged: its stream stops with an error"), std::string::npos)
      << ev[0].message;
  EXPECT_NE(ev[0].message.find("plug it back into the same port to resume"), std::string::npos);
  auto state = monitor.sensors();
  ASSERT_EQ(state.size(), 1u);
  EXPECT_EQ(state[0].presence, SensorPresence::kUnplugged);
  EXPECT_EQ(state[0].unplugs, 1);
  EXPECT_EQ(state[0].error, ev[0].message);
  EXPECT_TRUE(monitor.poll().empty());  // reported once, then it is a state

  bus.plug(device(0x1d27, 0x0601, 9, "3.1"));  // same port, new USB address
  ev = monitor.poll();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].type, SensorEvent::Type::kReplugged);
  state = monitor.sensors();
  ASSERT_EQ(state.size(), 1u);
  EXPECT_EQ(state[0].presence, SensorPresence::kConnected);
  EXPECT_EQ(state[0].sensor.device.address, 9);
  EXPECT_TRUE(state[0].error.empty());

  bus.plug(device(0x1d27, 0x0601, 10, "4"));  // a second camera of the same model
  ev = monitor.poll();
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].type, SensorEvent::Type::kPlugged);
  EXPECT_EQ(monitor.sensors().size(), 2u);
}

// The monitor on its own thread (also run under ThreadSanitizer): events arrive through the
// callback in order, and a broken bus is reported, not fatal.
TEST(HotplugMonitorThread, EventsFromBackgroundPolling) {
  FakeUsbBus bus;
  HotplugMonitor monitor(bus);
  std::mutex m;
  std::condition_variable cv;
  std::vector<std::string> seen;
  monitor.start(0.002, [&](const SensorEvent& e) {
    std::lock_guard<std::mutex> l(m);
    seen.push_back(std::string(sensorEventName(e.type)) + (e.sensor.info ? "" : ":bus-error"));
    cv.notify_all();
  });
  auto waitFor = [&](size_t n) {
    std::unique_lock<std::mutex> l(m);
    // A safety net against a hang, not a timing assertion: polling is every 2 ms.
    return cv.wait_for(l, std::chrono::seconds(30), [&] { return seen.size() >= n; });
  };
  bus.plug(device(0x8086, 0x0b07, 3, "2"));
  ASSERT_TRUE(waitFor(1));
  bus.unplug("2");
  ASSERT_TRUE(waitFor(2));
  bus.setBroken(true);
  ASSERT_TRUE(waitFor(3));
  bus.setBroken(false);
  bus.plug(device(0x8086, 0x0b07, 4, "2"));
  // The broken bus may be reported more than once before it recovers; wait for the replug.
  {
    std::unique_lock<std::mutex> l(m);
    ASSERT_TRUE(cv.wait_for(l, std::chrono::seconds(30),
                            [&] { return !seen.empty() && seen.back() == "replugged"; }));
  }
  monitor.stop();
  std::lock_guard<std::mutex> l(m);
  EXPECT_EQ(seen[0], "plugged");
  EXPECT_EQ(seen[1], "unplugged");
  EXPECT_EQ(seen[2], "unplugged:bus-error");
  EXPECT_EQ(seen.back(), "replugged");
}

/// A simulated sensor: frames while its cable is in; SensorDisconnected when pulled; opening it
/// fails while unplugged.
struct Cable {
  std::atomic<bool> plugged{true};
  int opens = 0;
};

class FakeSensor : public core::FrameSource {
 public:
  explicit FakeSensor(Cable& cable) : cable_(cable) {
    if (!cable.plugged) throw IoError("fake sensor: no device (unplugged)");
    ++cable.opens;
  }
  core::Intrinsics intrinsics() const override {
    core::Intrinsics k;
    k.fx = k.fy = 500;
    k.cx = 2;
    k.cy = 1.5;
    k.width = 4;
    k.height = 3;
    return k;
  }
  bool next(core::Frame& f) override {
    if (!cable_.plugged) throw SensorDisconnected("fake sensor: device gone");
    f.index = 1000 + n_;  // the wrapper renumbers
    f.timestamp = 0.1 * static_cast<double>(n_++);
    f.depth = cv::Mat(3, 4, CV_32F, cv::Scalar(1.0));
    return true;
  }
  bool isLive() const override { return true; }
  std::string describe() const override { return "fake sensor"; }

 private:
  Cable& cable_;
  int n_ = 0;
};

TEST(ReconnectingSource, DocumentedErrorStateAndRecovery) {
  Cable cable;
  ReconnectOptions o;
  o.retry_interval_s = 0.001;
  o.reconnect_wait_s = 0.005;
  ReconnectingSource src([&] { return std::make_unique<FakeSensor>(cable); }, "fake:cam", o);
  EXPECT_EQ(src.intrinsics().fx, 500);
  core::Frame f;
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(src.next(f));
    EXPECT_EQ(f.index, i);
  }
  cable.plugged = false;
  EXPECT_THROW(src.next(f), SensorDisconnected);
  EXPECT_EQ(src.state(), SensorState::kDisconnected);
  EXPECT_EQ(src.lastError(), "fake sensor: device gone");
  try {
    src.next(f);
    FAIL() << "expected SensorDisconnected while unplugged";
  } catch (const SensorDisconnected& e) {
    EXPECT_EQ(std::string(e.what()),
              "sensor 'fake:cam' is still disconnected (fake sensor: no device (unplugged)): "
              "re-plug it; frames resume automatically");
  }
  EXPECT_EQ(src.state(), SensorState::kDisconnected);
  EXPECT_NE(src.describe().find("[hot-plug: disconnected]"), std::string::npos);

  cable.plugged = true;
  ASSERT_TRUE(src.next(f));
  EXPECT_EQ(f.index, 3);        // indices continue across the outage
  EXPECT_EQ(f.timestamp, 0.0);  // a fresh stream from the re-opened sensor
  EXPECT_EQ(src.state(), SensorState::kStreaming);
  EXPECT_EQ(src.disconnects(), 1);
  EXPECT_EQ(src.reconnects(), 1);
  EXPECT_EQ(cable.opens, 2);
}

// Both halves of hot-plug on one simulated device: the USB monitor and the stream see the same
// cable pulled and plugged back.
TEST(Hotplug, MonitorAndStreamAgreeOnUnplugAndReplug) {
  FakeUsbBus bus;
  Cable cable;
  const UsbDevice cam = device(0x1d27, 0x0601, 7, "1.4");
  bus.plug(cam);
  HotplugMonitor monitor(bus);
  ASSERT_EQ(monitor.poll().size(), 1u);
  ReconnectOptions o;
  o.retry_interval_s = 0.001;
  o.reconnect_wait_s = 0.005;
  ReconnectingSource src([&] { return std::make_unique<FakeSensor>(cable); }, "openni2:", o);
  core::Frame f;
  ASSERT_TRUE(src.next(f));

  bus.unplug("1.4");
  cable.plugged = false;
  const auto down = monitor.poll();
  ASSERT_EQ(down.size(), 1u);
  EXPECT_EQ(down[0].type, SensorEvent::Type::kUnplugged);
  EXPECT_THROW(src.next(f), SensorDisconnected);
  EXPECT_EQ(src.state(), SensorState::kDisconnected);

  UsbDevice back = cam;
  back.address = 8;
  bus.plug(back);
  cable.plugged = true;
  const auto up = monitor.poll();
  ASSERT_EQ(up.size(), 1u);
  EXPECT_EQ(up[0].type, SensorEvent::Type::kReplugged);
  ASSERT_TRUE(src.next(f));
  EXPECT_EQ(f.index, 1);
  EXPECT_EQ(src.state(), SensorState::kStreaming);
}

}  // namespace
}  // namespace emf::fw
