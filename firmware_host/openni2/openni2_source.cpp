#include "firmware_host/openni2/openni2_source.h"

#include <OpenNI.h>
#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "common/log.h"
#include "firmware_host/openni2/virtual_device/virtual_properties.h"
#include "firmware_host/sensor_error.h"
#include "firmware_host/sensor_uri.h"

#if defined(__SANITIZE_THREAD__)
// ThreadSanitizer builds: libOpenNI2 (uninstrumented, from Debian) trips two report kinds on
// its own mutexes: "unlock of an unlocked mutex" while tearing down its context, and a
// lock-order inversion between its context and driver locks when a driver announces a device.
// Both stacks are inside libOpenNI2; suppress exactly those kinds for that library so the
// reports that remain are about emf. This object file is linked only into programs that use
// OpenNI2 (default visibility: the TSan runtime looks the hook up in the executable).
extern "C" __attribute__((visibility("default"))) const char* __tsan_default_suppressions() {
  return "mutex:libOpenNI2.so.0\n"
         "deadlock:libOpenNI2.so.0\n";
}
#endif

namespace emf::fw {
namespace {

constexpr int kWaitSliceMs = 50;  // granularity of waits, so disconnect events are seen quickly
constexpr double kRecordingEndWaitS = 1.0;

std::string extendedError() {
  std::string e = openni::OpenNI::getExtendedError();
  while (!e.empty() && (e.back() == '\n' || e.back() == ' ')) e.pop_back();
  for (auto& c : e) {
    if (c == '\n') c = ';';
    if (c == '\t') c = ' ';  // OpenNI2 indents its log lines with tabs
  }
  return e.empty() ? "no details from OpenNI2" : e;
}

/// RAII for OpenNI::initialize/shutdown (reference counted inside OpenNI2).
class OpenniRuntime {
 public:
  OpenniRuntime() {
    if (openni::OpenNI::initialize() != openni::STATUS_OK) {
      const std::string e = extendedError();
      openni::OpenNI::shutdown();
      throw IoError("openni2: cannot initialise OpenNI2 (" + e + "); drivers are loaded from " +
                    openni2DriverFolder() + ": check that libopenni2-0 is installed");
    }
  }
  ~OpenniRuntime() { openni::OpenNI::shutdown(); }
  OpenniRuntime(const OpenniRuntime&) = delete;
  OpenniRuntime& operator=(const OpenniRuntime&) = delete;
};

const char* pixelFormatName(openni::PixelFormat f) {
  switch (f) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM:
      return "DEPTH_1_MM";
    case openni::PIXEL_FORMAT_DEPTH_100_UM:
      return "DEPTH_100_UM";
    case openni::PIXEL_FORMAT_SHIFT_9_2:
      return "SHIFT_9_2";
    case openni::PIXEL_FORMAT_SHIFT_9_3:
      return "SHIFT_9_3";
    case openni::PIXEL_FORMAT_RGB888:
      return "RGB888";
    case openni::PIXEL_FORMAT_YUV422:
      return "YUV422";
    case openni::PIXEL_FORMAT_GRAY8:
      return "GRAY8";
    case openni::PIXEL_FORMAT_GRAY16:
      return "GRAY16";
    case openni::PIXEL_FORMAT_JPEG:
      return "JPEG";
    case openni::PIXEL_FORMAT_YUYV:
      return "YUYV";
  }
  return "unknown";
}

/// Picks the supported mode closest to the wanted size/rate among `formats` (in preference
/// order). Returns false when the sensor offers none of the formats.
bool chooseMode(const openni::SensorInfo* info, const std::vector<openni::PixelFormat>& formats,
                int width, int height, int fps, openni::VideoMode* out) {
  if (info == nullptr) return false;
  const auto& modes = info->getSupportedVideoModes();
  double best = std::numeric_limits<double>::max();
  for (int i = 0; i < modes.getSize(); ++i) {
    const auto& m = modes[i];
    for (size_t rank = 0; rank < formats.size(); ++rank) {
      if (m.getPixelFormat() != formats[rank]) continue;
      const double cost = std::abs(m.getResolutionX() - width) * 10.0 +
                          std::abs(m.getResolutionY() - height) * 10.0 +
                          std::abs(m.getFps() - fps) + static_cast<double>(rank) * 1e6;
      if (cost < best) {
        best = cost;
        *out = m;
      }
    }
  }
  return best < std::numeric_limits<double>::max();
}

}  // namespace

struct Openni2Source::Impl : openni::OpenNI::DeviceDisconnectedListener,
                             openni::OpenNI::DeviceStateChangedListener {
  OpenniRuntime runtime;
  openni::Device device;
  openni::VideoStream depth;
  openni::VideoStream color;
  bool has_color = false;
  bool listening = false;
  std::string uri;
  std::atomic<bool> disconnected{false};
  std::atomic<int> error_state{0};

  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info != nullptr && uri == info->getUri()) disconnected = true;
  }
  void onDeviceStateChanged(const openni::DeviceInfo* info, openni::DeviceState state) override {
    if (info != nullptr && uri == info->getUri()) error_state = static_cast<int>(state);
  }

  // Also runs when the constructor of Openni2Source throws half-way (listeners must not outlive
  // this object).
  ~Impl() override { shutdown(); }

  void shutdown() {
    if (listening) {
      openni::OpenNI::removeDeviceDisconnectedListener(this);
      openni::OpenNI::removeDeviceStateChangedListener(this);
      listening = false;
    }
    if (has_color) {
      color.stop();
      color.destroy();
    }
    if (depth.isValid()) {
      depth.stop();
      depth.destroy();
    }
    if (device.isValid()) device.close();
  }
};

std::string openni2DriverFolder() {
  Dl_info info{};
  // Any OpenNI2 C API function lives in libOpenNI2; its folder + OpenNI2/Drivers is where
  // OpenNI2 looks for drivers (Debian keeps OpenNI.ini's Repository unset).
  if (dladdr(reinterpret_cast<void*>(&oniGetExtendedError), &info) && info.dli_fname) {
    return (std::filesystem::path(info.dli_fname).parent_path() / "OpenNI2" / "Drivers").string();
  }
  return "<libOpenNI2 folder>/OpenNI2/Drivers";
}

std::vector<Openni2DeviceInfo> listOpenni2Devices() {
  OpenniRuntime runtime;
  openni::Array<openni::DeviceInfo> devices;
  openni::OpenNI::enumerateDevices(&devices);
  std::vector<Openni2DeviceInfo> out;
  for (int i = 0; i < devices.getSize(); ++i) {
    Openni2DeviceInfo d;
    d.uri = devices[i].getUri();
    d.vendor = devices[i].getVendor();
    d.name = devices[i].getName();
    d.usb_vendor_id = devices[i].getUsbVendorId();
    d.usb_product_id = devices[i].getUsbProductId();
    out.push_back(d);
  }
  return out;
}

Openni2Source::Openni2Source(const std::string& uri, const core::SourceOptions& options)
    : impl_(std::make_unique<Impl>()), uri_(uri) {
  SensorUri u(uri);
  if (u.scheme() != "openni2") {
    throw IoError("'" + uri + "' is not an openni2: URI");
  }
  const bool want_registration = u.flag("registration", true);
  const bool want_sync = u.flag("sync", true);
  const bool want_color = u.flag("color", true);
  timeout_s_ = u.real("timeout_s", 2.0, 0.05, 3600.0);
  const int want_w = u.integer("width", 640, 1, 16384);
  const int want_h = u.integer("height", 480, 1, 16384);
  const int want_fps = u.integer("fps", 30, 1, 1000);
  const double fx = u.real("fx", options.fx, 0.0, 1e5);
  const double fy = u.real("fy", options.fy, 0.0, 1e5);
  const double cx = u.real("cx", options.cx, 0.0, 1e5);
  const double cy = u.real("cy", options.cy, 0.0, 1e5);
  max_frames_ = u.integer("max_frames", options.max_frames, 0, 100000000);
  u.checkAllUsed();

  Impl& m = *impl_;
  std::string target = u.target();
  const bool is_file = target.size() > 4 && target.compare(target.size() - 4, 4, ".oni") == 0;
  if (is_file && !std::filesystem::exists(target)) {
    throw IoError("openni2: recording '" + target + "' does not exist");
  }
  if (target.empty()) {
    openni::Array<openni::DeviceInfo> devices;
    openni::OpenNI::enumerateDevices(&devices);
    if (devices.getSize() == 0) {
      throw IoError("openni2: no OpenNI2 device found (drivers in " + openni2DriverFolder() +
                    "): plug in a sensor and check its USB permissions (udev rules of "
                    "libopenni2-0), or name one: openni2:<device uri> / openni2:<file.oni>");
    }
    target = devices[0].getUri();
  }
  device_uri_ = target;
  m.uri = target;
  if (m.device.open(target.c_str()) != openni::STATUS_OK) {
    const bool virtual_device = target.rfind("emf-virtual://", 0) == 0;
    const std::string driver = openni2DriverFolder() + "/libEmfVirtualDevice.so.0";
    std::string advice = "check that it is plugged in and not used by another program";
    if (virtual_device) {
      std::error_code ec;
      advice = std::filesystem::exists(driver, ec)
                   ? "fix the folder as the message says"
                   : "the emf virtual driver is not in " + openni2DriverFolder() +
                         ", where the libOpenNI2 this program loaded looks for drivers";
    }
    throw IoError("openni2: cannot open device '" + target + "' (" + extendedError() +
                  "): " + advice + "; `emf devices` lists what OpenNI2 sees");
  }
  live_ = !m.device.isFile();
  if (!live_) {
    // Recordings: frame by frame as they are read (speed -1 = OpenNI2's manual trigger), every
    // frame. Repeat stays ON on purpose: without it, OpenNI2's .oni player (libOniFile) spins at
    // the end of the file iterating its stream list without a lock, which races with closing the
    // streams (a crash seen in tests). With repeat the player parks on the rewound first frame,
    // and next() detects the end as the frame index wrapping around.
    if (auto* pc = m.device.getPlaybackControl()) {
      pc->setSpeed(-1.0f);
      pc->setRepeatEnabled(true);
    }
  }

  openni::VideoMode depth_mode;
  const openni::SensorInfo* depth_info = m.device.getSensorInfo(openni::SENSOR_DEPTH);
  if (depth_info == nullptr) {
    throw IoError("openni2: device '" + target + "' has no depth sensor");
  }
  if (!chooseMode(depth_info, {openni::PIXEL_FORMAT_DEPTH_1_MM, openni::PIXEL_FORMAT_DEPTH_100_UM},
                  want_w, want_h, want_fps, &depth_mode)) {
    std::string offered;
    const auto& modes = depth_info->getSupportedVideoModes();
    for (int i = 0; i < modes.getSize(); ++i) {
      offered += std::string(i ? ", " : "") + pixelFormatName(modes[i].getPixelFormat());
    }
    throw IoError("openni2: device '" + target + "' offers no metric depth format (offers: " +
                  offered + "; need DEPTH_1_MM or DEPTH_100_UM)");
  }
  if (m.depth.create(m.device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    throw IoError("openni2: cannot create the depth stream of '" + target + "' (" +
                  extendedError() + ")");
  }
  if (live_ && m.depth.setVideoMode(depth_mode) != openni::STATUS_OK) {
    logWarning("openni2: device '", target, "' refused depth mode ", depth_mode.getResolutionX(),
               "x", depth_mode.getResolutionY(), "@", depth_mode.getFps(), " (", extendedError(),
               "); using its current mode");
  }

  const openni::SensorInfo* color_info =
      want_color ? m.device.getSensorInfo(openni::SENSOR_COLOR) : nullptr;
  if (color_info != nullptr) {
    openni::VideoMode color_mode;
    if (!chooseMode(color_info, {openni::PIXEL_FORMAT_RGB888}, want_w, want_h, want_fps,
                    &color_mode)) {
      logWarning("openni2: device '", target, "' offers no RGB888 colour mode; colour disabled");
    } else if (m.color.create(m.device, openni::SENSOR_COLOR) != openni::STATUS_OK) {
      logWarning("openni2: cannot create the colour stream of '", target, "' (", extendedError(),
                 "); colour disabled");
    } else {
      m.has_color = true;
      if (live_) m.color.setVideoMode(color_mode);
    }
  }

  if (m.has_color && want_registration) {
    if (m.device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR)) {
      registered_ = m.device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) ==
                    openni::STATUS_OK;
      if (!registered_) {
        logWarning("openni2: depth-to-colour registration failed on '", target, "' (",
                   extendedError(), ")");
      }
    } else {
      logInfo("openni2: device '", target, "' does not support depth-to-colour registration");
    }
  }
  if (m.has_color && want_sync) {
    synced_ = m.device.setDepthColorSyncEnabled(true) == openni::STATUS_OK;
    if (!synced_) logInfo("openni2: frame sync not supported by '", target, "'");
  }

  if (m.depth.start() != openni::STATUS_OK) {
    throw IoError("openni2: cannot start the depth stream of '" + target + "' (" + extendedError() +
                  ")");
  }
  if (m.has_color && m.color.start() != openni::STATUS_OK) {
    logWarning("openni2: cannot start the colour stream of '", target, "' (", extendedError(),
               "); colour disabled");
    m.color.destroy();
    m.has_color = false;
  }
  openni::OpenNI::addDeviceDisconnectedListener(&m);
  openni::OpenNI::addDeviceStateChangedListener(&m);
  m.listening = true;

  if (m.depth.isPropertySupported(openni::STREAM_PROPERTY_NUMBER_OF_FRAMES)) {
    int n = 0;
    if (m.depth.getProperty(openni::STREAM_PROPERTY_NUMBER_OF_FRAMES, &n) == openni::STATUS_OK &&
        n > 0) {
      num_frames_ = n;
    }
  }

  // Intrinsics from the field of view of the stream the depth image is expressed in.
  const openni::VideoStream& geometry = registered_ ? m.color : m.depth;
  const openni::VideoMode mode = m.depth.getVideoMode();
  intrinsics_.width = mode.getResolutionX();
  intrinsics_.height = mode.getResolutionY();
  const double hfov = geometry.getHorizontalFieldOfView();
  const double vfov = geometry.getVerticalFieldOfView();
  if (hfov > 0 && vfov > 0) {
    intrinsics_.fx = intrinsics_.width / (2.0 * std::tan(hfov / 2.0));
    intrinsics_.fy = intrinsics_.height / (2.0 * std::tan(vfov / 2.0));
  }
  intrinsics_.cx = intrinsics_.width / 2.0;
  intrinsics_.cy = intrinsics_.height / 2.0;
  // emf's virtual device also gives its full calibration (principal point included).
  virtual_device::PinholeProperty pinhole{};
  if (geometry.isPropertySupported(virtual_device::kPinholeProperty) &&
      geometry.getProperty(virtual_device::kPinholeProperty, &pinhole) == openni::STATUS_OK &&
      pinhole.fx > 0 && pinhole.fy > 0) {
    const double sx = registered_ ? static_cast<double>(intrinsics_.width) /
                                        std::max(1, m.color.getVideoMode().getResolutionX())
                                  : 1.0;
    const double sy = registered_ ? static_cast<double>(intrinsics_.height) /
                                        std::max(1, m.color.getVideoMode().getResolutionY())
                                  : 1.0;
    intrinsics_.fx = pinhole.fx * sx;
    intrinsics_.fy = pinhole.fy * sy;
    intrinsics_.cx = (pinhole.cx + 0.5) * sx - 0.5;
    intrinsics_.cy = (pinhole.cy + 0.5) * sy - 0.5;
  }
  if (fx > 0) intrinsics_.fx = fx;
  if (fy > 0) intrinsics_.fy = fy;
  if (cx > 0) intrinsics_.cx = cx;
  if (cy > 0) intrinsics_.cy = cy;
  if (!intrinsics_.valid()) {
    throw IoError("openni2: device '" + target +
                  "' reports no field of view: give the "
                  "intrinsics in the URI (?fx=..&fy=..&cx=..&cy=..) or source.fx/fy/cx/cy");
  }

  char text[512];
  std::snprintf(text, sizeof(text), "OpenNI2 %s '%s', depth %dx%d@%d %s%s%s%s",
                live_ ? "device" : "recording", target.c_str(), intrinsics_.width,
                intrinsics_.height, mode.getFps(), pixelFormatName(mode.getPixelFormat()),
                m.has_color ? ", colour" : ", no colour", registered_ ? ", registered" : "",
                synced_ ? ", synced" : "");
  description_ = text;
  if (num_frames_ > 0) description_ += ", " + std::to_string(num_frames_) + " frames";
}

Openni2Source::~Openni2Source() { close(); }

void Openni2Source::close() {
  if (impl_) {
    impl_->shutdown();
    impl_.reset();
  }
}

bool Openni2Source::next(core::Frame& frame) {
  if (!impl_) throw IoError("openni2: source '" + uri_ + "' is closed");
  Impl& m = *impl_;
  if (max_frames_ > 0 && delivered_ >= max_frames_) return false;
  if (num_frames_ > 0 && last_frame_index_ >= num_frames_) return false;

  // Wait for depth in short slices so an unplug event ends the wait at once.
  openni::VideoStream* streams[] = {&m.depth};
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    if (m.disconnected || m.error_state == openni::DEVICE_STATE_ERROR) {
      throw SensorDisconnected("openni2: device '" + device_uri_ + "' was disconnected (after " +
                               std::to_string(delivered_) +
                               " frames): reconnect it; a reconnecting source resumes by itself");
    }
    int ready = -1;
    const openni::Status st = openni::OpenNI::waitForAnyStream(streams, 1, &ready, kWaitSliceMs);
    if (st == openni::STATUS_OK) break;
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // A recording played frame by frame delivers on demand: a second without a frame is its
    // end (OpenNI2's .oni player reports no frame count for files made by its own recorder).
    if (!live_ && waited >= std::min(timeout_s_, kRecordingEndWaitS)) return false;
    if (waited >= timeout_s_) {
      if (num_frames_ > 0) {
        // A finite virtual device that ran out: the frames it served that were never read
        // (all of them when the SLAM started after it finished) were dropped.
        if (live_ && last_frame_index_ < num_frames_) {
          dropped_ += num_frames_ - last_frame_index_;
          last_frame_index_ = static_cast<int>(num_frames_);
        }
        return false;
      }
      throw SensorDisconnected("openni2: no depth frame from '" + device_uri_ + "' for " +
                               std::to_string(timeout_s_) + " s (after " +
                               std::to_string(delivered_) +
                               " frames): the sensor stalled or was unplugged; check the cable "
                               "and power");
    }
  }
  openni::VideoFrameRef depth;
  if (m.depth.readFrame(&depth) != openni::STATUS_OK || !depth.isValid()) {
    throw IoError("openni2: reading a depth frame from '" + device_uri_ + "' failed (" +
                  extendedError() + ")");
  }
  const int w = depth.getWidth(), h = depth.getHeight();
  const openni::PixelFormat fmt = depth.getVideoMode().getPixelFormat();
  double unit_m = 0.001;
  if (fmt == openni::PIXEL_FORMAT_DEPTH_100_UM) {
    unit_m = 0.0001;
  } else if (fmt != openni::PIXEL_FORMAT_DEPTH_1_MM) {
    throw IoError("openni2: depth frame of '" + device_uri_ + "' has format " +
                  pixelFormatName(fmt) + " (need DEPTH_1_MM or DEPTH_100_UM)");
  }
  const cv::Mat raw(h, w, CV_16UC1, const_cast<void*>(depth.getData()),
                    static_cast<size_t>(depth.getStrideInBytes()));
  frame.depth.create(h, w, CV_32FC1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < h; ++y) {
    const uint16_t* src = raw.ptr<uint16_t>(y);
    float* dst = frame.depth.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      dst[x] = src[x] == 0 ? nan : static_cast<float>(src[x] * unit_m);
    }
  }
  if (!live_ && delivered_ > 0 && depth.getFrameIndex() <= last_frame_index_) {
    return false;  // the recording rewound: its last frame was delivered before
  }
  if (live_) {
    // Numbered from 1 on a finite device: frames served before the first read count too.
    const int index = depth.getFrameIndex();
    const int expected = delivered_ > 0 ? last_frame_index_ + 1 : (num_frames_ > 0 ? 1 : index);
    if (index > expected) dropped_ += index - expected;
  }
  last_frame_index_ = depth.getFrameIndex();
  // Recordings (and the finite virtual device) number frames from 1: index = position in the
  // recording. Live devices: frames delivered so far.
  frame.index =
      ((!live_ || num_frames_ > 0) && last_frame_index_ > 0) ? last_frame_index_ - 1 : delivered_;
  frame.timestamp = static_cast<double>(depth.getTimestamp()) * 1e-6;
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.6f", frame.timestamp);
  frame.timestamp_text = stamp;
  frame.rgb_timestamp = frame.timestamp;
  frame.color.release();

  if (m.has_color) {
    // Synced devices deliver the colour frame together with depth; otherwise take the newest
    // one within a frame period.
    openni::VideoStream* cs[] = {&m.color};
    int ready = -1;
    const int wait_ms = std::max(1, 2000 / std::max(1, m.color.getVideoMode().getFps()));
    if (openni::OpenNI::waitForAnyStream(cs, 1, &ready, wait_ms) == openni::STATUS_OK) {
      openni::VideoFrameRef color;
      if (m.color.readFrame(&color) == openni::STATUS_OK && color.isValid() &&
          color.getVideoMode().getPixelFormat() == openni::PIXEL_FORMAT_RGB888) {
        const cv::Mat rgb(color.getHeight(), color.getWidth(), CV_8UC3,
                          const_cast<void*>(color.getData()),
                          static_cast<size_t>(color.getStrideInBytes()));
        cv::cvtColor(rgb, frame.color, cv::COLOR_RGB2BGR);
        frame.rgb_timestamp = static_cast<double>(color.getTimestamp()) * 1e-6;
      }
    }
  }
  frame.detections.reset();
  frame.T_world_camera_gt.reset();
  frame.T_world_object_gt.clear();
  frame.instance_ids.release();
  ++delivered_;
  return true;
}

}  // namespace emf::fw
