#include "firmware_host/usb/usb_bus.h"

#include "common/error.h"

#ifdef EMF_HAVE_LIBUSB
#include <libusb.h>
#endif

namespace emf::fw {

std::string UsbDevice::key() const {
  return usbIdText(vendor_id, product_id) + "@" + std::to_string(bus) + "-" +
         (port_path.empty() ? "addr" + std::to_string(address) : port_path);
}

std::vector<DetectedSensor> findSensors(const std::vector<UsbDevice>& devices) {
  std::vector<DetectedSensor> out;
  for (const auto& d : devices) {
    if (const KnownSensor* k = findKnownSensor(d.vendor_id, d.product_id)) {
      out.push_back({d, k});
    }
  }
  return out;
}

#ifdef EMF_HAVE_LIBUSB
namespace {

class LibusbBus : public UsbBus {
 public:
  LibusbBus() {
    const int r = libusb_init(&ctx_);
    if (r != 0) {
      throw IoError(std::string("libusb: cannot initialise (") + libusb_error_name(r) +
                    "): is /dev/bus/usb available (containers need it mounted)?");
    }
  }
  ~LibusbBus() override { libusb_exit(ctx_); }

  std::string name() const override { return "libusb"; }

  std::vector<UsbDevice> list() override {
    libusb_device** devs = nullptr;
    const ssize_t n = libusb_get_device_list(ctx_, &devs);
    if (n < 0) {
      throw IoError(std::string("libusb: cannot list devices (") +
                    libusb_error_name(static_cast<int>(n)) + ")");
    }
    std::vector<UsbDevice> out;
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device_descriptor desc{};
      if (libusb_get_device_descriptor(devs[i], &desc) != 0) continue;
      UsbDevice d;
      d.vendor_id = desc.idVendor;
      d.product_id = desc.idProduct;
      d.bus = libusb_get_bus_number(devs[i]);
      d.address = libusb_get_device_address(devs[i]);
      uint8_t ports[8];
      const int depth = libusb_get_port_numbers(devs[i], ports, 8);
      for (int k = 0; k < depth; ++k) {
        d.port_path += (k ? "." : "") + std::to_string(ports[k]);
      }
      out.push_back(d);
    }
    libusb_free_device_list(devs, 1);
    return out;
  }

 private:
  libusb_context* ctx_ = nullptr;
};

}  // namespace

std::unique_ptr<UsbBus> openLibusbBus() { return std::make_unique<LibusbBus>(); }
#else
std::unique_ptr<UsbBus> openLibusbBus() {
  throw IoError("emf was built without libusb (CMake option EMF_WITH_LIBUSB)");
}
#endif

}  // namespace emf::fw
