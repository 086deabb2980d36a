// `emf devices`: lists the RGB-D sensors this machine can use, by backend, and optionally
// watches the USB bus for hot-plug events.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>

#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "common/error.h"
#include "firmware_host/usb/hotplug_monitor.h"
#include "firmware_host/usb/usb_bus.h"
#ifdef EMF_HAVE_OPENNI2
#include "firmware_host/openni2/openni2_source.h"
#endif
#ifdef EMF_HAVE_V4L2
#include <linux/videodev2.h>

#include "firmware_host/v4l2/pixel_formats.h"
#include "firmware_host/v4l2/v4l2_device.h"
#endif

namespace emf::cli {
namespace {

double parseSeconds(const std::string& text, const char* option) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(v >= 0) || v > 1e6) {
    throw InvalidArgument(std::string("--") + option + " " + text +
                          ": expected seconds in [0, 1e6]");
  }
  return v;
}

void listUsb(fw::UsbBus* bus, const std::string& bus_error) {
  std::printf("USB RGB-D sensors (libusb):\n");
  if (!bus) {
    std::printf("  (not available: %s)\n", bus_error.c_str());
    return;
  }
  const auto sensors = fw::findSensors(bus->list());
  if (sensors.empty()) std::printf("  (none found)\n");
  for (const auto& s : sensors) {
    std::printf("  %s  bus %03d port %-8s %-50s backend: %s\n",
                fw::usbIdText(s.device.vendor_id, s.device.product_id).c_str(), s.device.bus,
                s.device.port_path.empty() ? "?" : s.device.port_path.c_str(), s.info->name,
                s.info->backend);
  }
}

void listOpenni2() {
#ifdef EMF_HAVE_OPENNI2
  std::printf("OpenNI2 devices (drivers in %s):\n", fw::openni2DriverFolder().c_str());
  try {
    const auto devices = fw::listOpenni2Devices();
    if (devices.empty()) std::printf("  (none found)\n");
    for (const auto& d : devices) {
      std::printf("  openni2:%s  %s %s (usb %s)\n", d.uri.c_str(), d.vendor.c_str(), d.name.c_str(),
                  fw::usbIdText(d.usb_vendor_id, d.usb_product_id).c_str());
    }
  } catch (const Error& e) {
    std::printf("  (not available: %s)\n", e.what());
  }
#else
  std::printf("OpenNI2 devices: (backend not compiled in: EMF_WITH_OPENNI2=OFF)\n");
#endif
}

void listV4l2() {
#ifdef EMF_HAVE_V4L2
  std::printf("V4L2 video nodes:\n");
  int found = 0;
  std::error_code ec;
  std::vector<std::filesystem::path> nodes;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    if (entry.path().filename().string().rfind("video", 0) == 0) nodes.push_back(entry.path());
  }
  std::sort(nodes.begin(), nodes.end());
  for (const auto& node : nodes) {
    try {
      fw::V4l2Device dev(node.string());
      std::string formats;
      bool depth = false, color = false;
      for (uint32_t f : dev.formats()) {
        formats += (formats.empty() ? "" : ",") + fw::fourccName(f);
        depth = depth || f == V4L2_PIX_FMT_Z16 || f == V4L2_PIX_FMT_Y16;
        color = color || f == V4L2_PIX_FMT_YUYV || f == V4L2_PIX_FMT_MJPEG;
      }
      std::printf("  v4l2:%s  %-32s formats %s%s\n", node.c_str(), dev.card().c_str(),
                  formats.c_str(), depth ? "  (depth node)" : (color ? "  (colour node)" : ""));
      ++found;
    } catch (const Error&) {
      // metadata / output nodes, or no permission: not a capture candidate
    }
  }
  if (found == 0) std::printf("  (none found)\n");
#else
  std::printf("V4L2 video nodes: (backend not compiled in: EMF_WITH_V4L2=OFF)\n");
#endif
}

}  // namespace

int cmdDevices(const std::vector<std::string>& args) {
  std::string watch_text, interval_text = "0.5";
  ArgParser p("devices",
              "Lists the RGB-D sensors this machine can use: known USB sensors found with "
              "libusb (vendor:product, port, backend that serves them), the devices OpenNI2 "
              "enumerates (including emf virtual devices named in EMF_VIRTUAL_DEVICES) and the "
              "V4L2 capture nodes with their pixel formats. With --watch it then reports "
              "USB hot-plug events: an unplugged sensor is an error line, a re-plugged one a "
              "recovery line.");
  p.option("watch", &watch_text, "SECONDS", "after listing, watch the USB bus this long");
  p.option("interval", &interval_text, "SECONDS", "USB polling interval for --watch (0.5)");
  if (auto code = p.parse(args)) return *code;
  const double watch_s = watch_text.empty() ? 0.0 : parseSeconds(watch_text, "watch");
  const double interval_s = parseSeconds(interval_text, "interval");

  std::unique_ptr<fw::UsbBus> bus;
  std::string bus_error;
  try {
    bus = fw::openLibusbBus();
  } catch (const Error& e) {
    bus_error = e.what();
  }
  listUsb(bus.get(), bus_error);
  listOpenni2();
  listV4l2();
  if (watch_s <= 0) return kExitOk;
  if (!bus) {
    std::fprintf(stderr, "emf devices: cannot watch: %s\n", bus_error.c_str());
    return kExitFailure;
  }
  std::printf("watching USB for %.1f s (every %.2f s):\n", watch_s, interval_s);
  std::fflush(stdout);
  fw::HotplugMonitor monitor(*bus);
  monitor.poll();  // the sensors listed above are the baseline
  const auto t0 = std::chrono::steady_clock::now();
  const auto end = t0 + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(watch_s));
  while (std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.01, interval_s)));
    for (const auto& ev : monitor.poll()) {
      const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("  [%7.2f s] %s: %s\n", t, fw::sensorEventName(ev.type), ev.message.c_str());
      std::fflush(stdout);
    }
  }
  return kExitOk;
}

}  // namespace emf::cli
