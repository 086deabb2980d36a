// The virtual OpenNI2 device: an OpenNI2 driver (built against Debian's OniDriverAPI.h, loaded by
// libOpenNI2 from its driver folder) that serves a TUM-layout RGB-D folder as if it were a
// camera. This lets the whole OpenNI2 path (enumeration, device open, streams, timestamps,
// frame sync, intrinsics from the field of view, hot-plug events) run in CI without hardware.
//
// URI:  emf-virtual://<folder>[;speed=S][;loop=0|1][;control=<file>][;depth_scale=N]
//   (parameters are separated by ';' so that a '?' query stays free for the application, e.g.
//   emf's `openni2:emf-virtual:///data/x;speed=0?registration=0`)
//   speed        playback speed relative to the folder's timestamps (default 1 = real time, like
//                a camera: frames not read in time are lost). 0 = on demand: one frame per
//                OpenNI2 wait (lossless, deterministic; used by replay-style tests).
//   loop         1 = start again after the last frame (timestamps keep increasing); default 0,
//                which also makes the streams report ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES.
//   control      a file that simulates the USB cable: content "unplugged" = the device is
//                disconnected (no frames, OpenNI2 disconnect + error-state events); anything
//                else / no file = connected (connect event again after an unplug).
//   depth_scale  uint16 depth units per metre (default: the `depth scale N` note in depth.txt,
//                else 5000). Depth is served as DEPTH_1_MM when the scale is 1000, else as
//                DEPTH_100_UM (exact for 5000 and 10000, rounded otherwise).
// Devices are created when OpenNI2 tries a URI (openDevice), or announced at start-up from the
// environment variable EMF_VIRTUAL_DEVICES (URIs or folders separated by ','), so that
// enumeration and "open the default device" find them.
// Frames: frameIndex is 1-based (as in .oni playback), timestamps are the folder's timestamps in
// microseconds. The device clock is shared by all opens of a URI, so a device that is
// re-plugged and re-opened continues "live" rather than from the first frame.
#include <Driver/OniDriverAPI.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "firmware_host/openni2/virtual_device/tum_folder.h"
#include "firmware_host/openni2/virtual_device/virtual_properties.h"

namespace emf::fw::virtual_device {
namespace {

using Clock = std::chrono::steady_clock;
constexpr const char* kScheme = "emf-virtual://";
constexpr int kControlPollMs = 20;

struct Params {
  std::string folder;
  double speed = 1.0;
  bool loop = false;
  std::string control;
  double depth_scale = 0.0;
};

bool parseUri(const std::string& uri, Params* p, std::string* error) {
  const size_t scheme_len = std::strlen(kScheme);
  if (uri.compare(0, scheme_len, kScheme) != 0) {
    *error = "not an emf-virtual:// URI";
    return false;
  }
  std::string rest = uri.substr(scheme_len);
  std::string query;
  const size_t q = rest.find(';');
  if (q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  if (rest.empty()) {
    *error = "'" + uri + "': no folder (use emf-virtual://<TUM folder>)";
    return false;
  }
  p->folder = rest;
  size_t pos = 0;
  while (pos < query.size()) {
    size_t amp = query.find(';', pos);
    if (amp == std::string::npos) amp = query.size();
    const std::string kv = query.substr(pos, amp - pos);
    pos = amp + 1;
    if (kv.empty()) continue;
    const size_t eq = kv.find('=');
    const std::string key = kv.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : kv.substr(eq + 1);
    char* end = nullptr;
    if (key == "speed") {
      p->speed = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end || !(p->speed >= 0) || p->speed > 1000) {
        *error = "'" + uri + "': speed=" + value + " must be a number in [0, 1000]";
        return false;
      }
    } else if (key == "loop") {
      if (value != "0" && value != "1") {
        *error = "'" + uri + "': loop=" + value + " must be 0 or 1";
        return false;
      }
      p->loop = value == "1";
    } else if (key == "control") {
      p->control = value;
    } else if (key == "depth_scale") {
      p->depth_scale = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end || !(p->depth_scale > 0)) {
        *error = "'" + uri + "': depth_scale=" + value + " must be a positive number";
        return false;
      }
    } else {
      *error = "'" + uri + "': unknown parameter '" + key +
               "' (known: speed, loop, control, depth_scale)";
      return false;
    }
  }
  return true;
}

/// State of one virtual device URI, owned by the driver: it survives closing and re-opening
/// the device (like the camera itself survives its USB cable being pulled).
struct Entry {
  OniDeviceInfo info{};
  Params params;
  TumFolder folder;
  std::atomic<bool> plugged{true};
  std::mutex mutex;          // guards origin
  Clock::time_point origin;  // when frame 0 was due (first stream start)
  bool origin_set = false;
};

class VirtualDevice;

class VirtualStream : public oni::driver::StreamBase {
 public:
  VirtualStream(VirtualDevice& device, OniSensorType type, const OniVideoMode& mode, int frames,
                const PinholeProperty& pinhole)
      : device_(device),
        type_(type),
        mode_(mode),
        frames_(frames),
        pinhole_(pinhole),
        // The field of view that reproduces the calibrated focal lengths: fx = w / (2 tan(h/2)).
        hfov_rad_(static_cast<float>(2.0 * std::atan(mode.resolutionX / (2.0 * pinhole.fx)))),
        vfov_rad_(static_cast<float>(2.0 * std::atan(mode.resolutionY / (2.0 * pinhole.fy)))) {}

  OniStatus start() override;
  void stop() override;

  OniSensorType type() const { return type_; }
  bool started() const { return started_.load(); }
  const OniVideoMode& mode() const { return mode_; }

  int getRequiredFrameSize() override {
    return mode_.resolutionX * mode_.resolutionY * (type_ == ONI_SENSOR_DEPTH ? 2 : 3);
  }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case ONI_STREAM_PROPERTY_MIRRORING:
      case ONI_STREAM_PROPERTY_CROPPING:
      case ONI_STREAM_PROPERTY_STRIDE:
        return TRUE;
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return type_ == ONI_SENSOR_DEPTH;
      case ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES:
        return frames_ > 0;
      case kPinholeProperty:
        return TRUE;
      default:
        return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
        return put(mode_, data, size);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return put(hfov_rad_, data, size);
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return put(vfov_rad_, data, size);
      case ONI_STREAM_PROPERTY_MIRRORING:
        return put(OniBool(FALSE), data, size);
      case ONI_STREAM_PROPERTY_CROPPING: {
        OniCropping c{};
        c.enabled = FALSE;
        c.width = mode_.resolutionX;
        c.height = mode_.resolutionY;
        return put(c, data, size);
      }
      case ONI_STREAM_PROPERTY_STRIDE:
        return put(mode_.resolutionX * (type_ == ONI_SENSOR_DEPTH ? 2 : 3), data, size);
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        if (type_ != ONI_SENSOR_DEPTH) return ONI_STATUS_NOT_SUPPORTED;
        return put(65535, data, size);
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        if (type_ != ONI_SENSOR_DEPTH) return ONI_STATUS_NOT_SUPPORTED;
        return put(0, data, size);
      case ONI_STREAM_PROPERTY_NUMBER_OF_FRAMES:
        if (frames_ <= 0) return ONI_STATUS_NOT_SUPPORTED;
        return put(frames_, data, size);
      case kPinholeProperty:
        return put(pinhole_, data, size);
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE && size == static_cast<int>(sizeof(OniVideoMode))) {
      const OniVideoMode* m = static_cast<const OniVideoMode*>(data);
      // A recording has one mode; accepting it keeps generic camera code working.
      return (m->pixelFormat == mode_.pixelFormat && m->resolutionX == mode_.resolutionX &&
              m->resolutionY == mode_.resolutionY)
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    }
    if (id == ONI_STREAM_PROPERTY_MIRRORING && size == static_cast<int>(sizeof(OniBool))) {
      return *static_cast<const OniBool*>(data) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  /// Sends one frame (called by the device's clock with the device mutex held, so the stream
  /// cannot be stopped or destroyed meanwhile).
  void deliver(const void* pixels, int bytes, uint64_t timestamp_us, int frame_index) {
    OniFrame* frame = getServices().acquireFrame();
    if (frame == nullptr) return;
    const int n = std::min(bytes, frame->dataSize);
    std::memcpy(frame->data, pixels, static_cast<size_t>(n));
    frame->dataSize = n;
    frame->sensorType = type_;
    frame->timestamp = timestamp_us;
    frame->frameIndex = frame_index;
    frame->width = mode_.resolutionX;
    frame->height = mode_.resolutionY;
    frame->videoMode = mode_;
    frame->croppingEnabled = FALSE;
    frame->cropOriginX = 0;
    frame->cropOriginY = 0;
    frame->stride = mode_.resolutionX * (type_ == ONI_SENSOR_DEPTH ? 2 : 3);
    raiseNewFrame(frame);
    getServices().releaseFrame(frame);
  }

 private:
  template <typename T>
  static OniStatus put(const T& value, void* data, int* size) {
    if (*size < static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
    std::memcpy(data, &value, sizeof(T));
    *size = static_cast<int>(sizeof(T));
    return ONI_STATUS_OK;
  }

  VirtualDevice& device_;
  const OniSensorType type_;
  const OniVideoMode mode_;
  const int frames_;  // > 0 when the recording is finite (no loop)
  const PinholeProperty pinhole_;
  const float hfov_rad_, vfov_rad_;
  std::atomic<bool> started_{false};
};

class VirtualDevice : public oni::driver::DeviceBase {
 public:
  VirtualDevice(Entry& entry, oni::driver::DriverServices& services)
      : entry_(entry), services_(services) {
    const TumFolder& f = entry.folder;
    const bool mm = std::fabs(f.depth_scale - 1000.0) < 1e-9;
    depth_mode_ = {mm ? ONI_PIXEL_FORMAT_DEPTH_1_MM : ONI_PIXEL_FORMAT_DEPTH_100_UM, f.depth_width,
                   f.depth_height, f.fps};
    color_mode_ = {ONI_PIXEL_FORMAT_RGB888, f.color_width, f.color_height, f.fps};
    sensors_[0] = {ONI_SENSOR_DEPTH, 1, &depth_mode_};
    num_sensors_ = 1;
    if (!f.rgb_files.empty()) {
      sensors_[1] = {ONI_SENSOR_COLOR, 1, &color_mode_};
      num_sensors_ = 2;
    }
  }

  ~VirtualDevice() override { stopClock(); }

  OniStatus getSensorInfoList(OniSensorInfo** infos, int* count) override {
    *infos = sensors_;
    *count = num_sensors_;
    return ONI_STATUS_OK;
  }

  oni::driver::StreamBase* createStream(OniSensorType type) override {
    const TumFolder& f = entry_.folder;
    const int frames = entry_.params.loop ? 0 : static_cast<int>(f.depth_files.size());
    if (type == ONI_SENSOR_DEPTH) {
      return new VirtualStream(*this, type, depth_mode_, frames, {f.fx, f.fy, f.cx, f.cy});
    }
    if (type == ONI_SENSOR_COLOR && num_sensors_ == 2) {
      // Colour is not calibrated in a TUM folder; report the depth camera's calibration scaled to
      // the colour resolution (same optics assumed).
      const double sx = static_cast<double>(f.color_width) / std::max(1, f.depth_width);
      const double sy = static_cast<double>(f.color_height) / std::max(1, f.depth_height);
      return new VirtualStream(
          *this, type, color_mode_, frames,
          {f.fx * sx, f.fy * sy, (f.cx + 0.5) * sx - 0.5, (f.cy + 0.5) * sy - 0.5});
    }
    services_.errorLoggerAppend("emf-virtual: the device has no sensor of type %d",
                                static_cast<int>(type));
    return nullptr;
  }

  void destroyStream(oni::driver::StreamBase* stream) override {
    VirtualStream* s = static_cast<VirtualStream*>(stream);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      streams_.erase(std::remove(streams_.begin(), streams_.end(), s), streams_.end());
    }
    delete s;
  }

  OniBool isPropertySupported(int id) override {
    return id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || id == ONI_DEVICE_PROPERTY_SERIAL_NUMBER;
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION) {
      if (*size < static_cast<int>(sizeof(OniImageRegistrationMode))) {
        return ONI_STATUS_BAD_PARAMETER;
      }
      const OniImageRegistrationMode mode = ONI_IMAGE_REGISTRATION_OFF;
      std::memcpy(data, &mode, sizeof(mode));
      *size = sizeof(mode);
      return ONI_STATUS_OK;
    }
    if (id == ONI_DEVICE_PROPERTY_SERIAL_NUMBER) {
      const char serial[] = "emf-virtual";
      if (*size < static_cast<int>(sizeof(serial))) return ONI_STATUS_BAD_PARAMETER;
      std::memcpy(data, serial, sizeof(serial));
      *size = sizeof(serial);
      return ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION &&
        size == static_cast<int>(sizeof(OniImageRegistrationMode))) {
      // A TUM folder's colour is not registered to depth; only "off" is honest.
      return *static_cast<const OniImageRegistrationMode*>(data) == ONI_IMAGE_REGISTRATION_OFF
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

  /// speed = 0: OpenNI2 pokes the device while a reader waits; serve the next frame.
  OniStatus tryManualTrigger() override {
    if (entry_.params.speed > 0 || !entry_.plugged.load()) return ONI_STATUS_OK;
    std::lock_guard<std::mutex> lock(mutex_);
    if (streams_.empty()) return ONI_STATUS_OK;
    const int64_t n = static_cast<int64_t>(entry_.folder.depth_files.size());
    if (!entry_.params.loop && next_manual_frame_ >= n) return ONI_STATUS_OK;
    emitLocked(next_manual_frame_++);
    return ONI_STATUS_OK;
  }

  void streamStarted(VirtualStream* s) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (std::find(streams_.begin(), streams_.end(), s) == streams_.end()) streams_.push_back(s);
    }
    if (entry_.params.speed > 0) startClock();
  }

  void streamStopped(VirtualStream* s) {
    std::lock_guard<std::mutex> lock(mutex_);  // waits for a delivery in progress
    streams_.erase(std::remove(streams_.begin(), streams_.end(), s), streams_.end());
  }

 private:
  void startClock() {
    std::lock_guard<std::mutex> lock(clock_mutex_);
    if (clock_.joinable()) return;
    {
      std::lock_guard<std::mutex> e(entry_.mutex);
      if (!entry_.origin_set) {
        entry_.origin = Clock::now();
        entry_.origin_set = true;
      }
    }
    running_ = true;
    clock_ = std::thread([this] { clockLoop(); });
  }

  void stopClock() {
    std::lock_guard<std::mutex> lock(clock_mutex_);
    if (!clock_.joinable()) return;
    {
      std::lock_guard<std::mutex> l(wake_mutex_);
      running_ = false;
    }
    wake_.notify_all();
    clock_.join();
  }

  /// Time of frame k relative to the origin (speed-scaled), seconds.
  double frameTime(int64_t k) const {
    const TumFolder& f = entry_.folder;
    const int64_t n = static_cast<int64_t>(f.depth_timestamps_s.size());
    const double period = f.depth_timestamps_s.back() - f.depth_timestamps_s.front() + 1.0 / f.fps;
    const double t = f.depth_timestamps_s[static_cast<size_t>(k % n)] -
                     f.depth_timestamps_s.front() + static_cast<double>(k / n) * period;
    return t / entry_.params.speed;
  }

  void clockLoop() {
    const TumFolder& f = entry_.folder;
    const int64_t n = static_cast<int64_t>(f.depth_files.size());
    Clock::time_point origin;
    {
      std::lock_guard<std::mutex> e(entry_.mutex);
      origin = entry_.origin;
    }
    int64_t k = -1;  // last frame handled
    for (;;) {
      // The frame due now (frames missed while busy or unplugged are skipped, like a camera's).
      const double now_s = std::chrono::duration<double>(Clock::now() - origin).count();
      int64_t due = k;
      while ((entry_.params.loop || due + 1 < n) && frameTime(due + 1) <= now_s) ++due;
      if (due > k) {
        k = due;
        if (entry_.plugged.load()) {
          std::lock_guard<std::mutex> lock(mutex_);
          emitLocked(k);
        }
      }
      const bool finished = !entry_.params.loop && k + 1 >= n;
      const double next_s = finished ? now_s + 0.1 : frameTime(k + 1);
      const auto wake_at = origin + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(next_s));
      std::unique_lock<std::mutex> l(wake_mutex_);
      if (wake_.wait_until(l, wake_at, [this] { return !running_; })) return;
    }
  }

  /// A broken file is a dropped frame, as on a real sensor, but never a silent one: the OpenNI2
  /// log is off by default, so stderr gets the file and what to do too.
  void dropped(int64_t k, const char* stream, const std::string& why) {
    services_.errorLoggerAppend("emf-virtual: frame %lld: %s image dropped: %s",
                                static_cast<long long>(k), stream, why.c_str());
    std::fprintf(stderr, "emf-virtual: frame %lld: %s image dropped: %s\n",
                 static_cast<long long>(k), stream, why.c_str());
  }

  static std::string wrongSize(const std::string& file, int w, int h, const OniVideoMode& mode) {
    return file + " is " + std::to_string(w) + "x" + std::to_string(h) + ", the device streams " +
           std::to_string(mode.resolutionX) + "x" + std::to_string(mode.resolutionY) +
           " (every image of a stream must have the size of the folder's first one)";
  }

  /// Decodes frame k and hands it to every started stream. mutex_ must be held.
  void emitLocked(int64_t k) {
    const TumFolder& f = entry_.folder;
    const int64_t n = static_cast<int64_t>(f.depth_files.size());
    const size_t i = static_cast<size_t>(k % n);
    const double period = f.depth_timestamps_s.back() - f.depth_timestamps_s.front() + 1.0 / f.fps;
    const double offset_s = static_cast<double>(k / n) * period;
    const int frame_index = static_cast<int>(k + 1);
    std::string error;
    for (VirtualStream* s : streams_) {
      if (!s->started()) continue;
      if (s->type() == ONI_SENSOR_DEPTH) {
        int w = 0, h = 0;
        if (!readDepthPng(f.depth_files[i], &depth_, &w, &h, &error)) {
          dropped(k, "depth", error + " (fix or remove the file)");
          continue;
        }
        if (w != depth_mode_.resolutionX || h != depth_mode_.resolutionY) {
          dropped(k, "depth", wrongSize(f.depth_files[i], w, h, depth_mode_));
          continue;
        }
        if (depth_mode_.pixelFormat == ONI_PIXEL_FORMAT_DEPTH_100_UM) {
          // Units of 100 um: value * 10000 / scale (exact for TUM's 5000 and for 10000).
          const double k100 = 10000.0 / f.depth_scale;
          for (auto& v : depth_) {
            // Beyond 6.5535 m the format has no value: invalid (0), as a sensor reports it, not
            // a phantom wall at the largest value.
            const double units = std::round(v * k100);
            v = units > 65535.0 ? 0 : static_cast<uint16_t>(units);
          }
        }
        const uint64_t ts =
            static_cast<uint64_t>(std::llround((f.depth_timestamps_s[i] + offset_s) * 1e6));
        s->deliver(depth_.data(), static_cast<int>(depth_.size() * 2), ts, frame_index);
      } else if (s->type() == ONI_SENSOR_COLOR) {
        const int j = f.rgb_for_depth[i];
        if (j < 0) continue;
        int w = 0, h = 0;
        if (!readColorRgb(f.rgb_files[static_cast<size_t>(j)], &rgb_, &w, &h, &error)) {
          dropped(k, "colour", error + " (fix or remove the file)");
          continue;
        }
        if (w != color_mode_.resolutionX || h != color_mode_.resolutionY) {
          dropped(k, "colour", wrongSize(f.rgb_files[static_cast<size_t>(j)], w, h, color_mode_));
          continue;
        }
        const uint64_t ts = static_cast<uint64_t>(
            std::llround((f.rgb_timestamps_s[static_cast<size_t>(j)] + offset_s) * 1e6));
        s->deliver(rgb_.data(), static_cast<int>(rgb_.size()), ts, frame_index);
      }
    }
  }

  Entry& entry_;
  oni::driver::DriverServices& services_;
  OniVideoMode depth_mode_{}, color_mode_{};
  OniSensorInfo sensors_[2]{};
  int num_sensors_ = 0;

  std::mutex mutex_;                     // guards streams_, the decode buffers, deliveries
  std::vector<VirtualStream*> streams_;  // started streams
  std::vector<uint16_t> depth_;
  std::vector<uint8_t> rgb_;
  int64_t next_manual_frame_ = 0;

  std::mutex clock_mutex_;  // guards clock_ start/stop
  std::thread clock_;
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool running_ = false;  // guarded by wake_mutex_
};

OniStatus VirtualStream::start() {
  started_ = true;
  device_.streamStarted(this);
  return ONI_STATUS_OK;
}

void VirtualStream::stop() {
  started_ = false;
  device_.streamStopped(this);
}

class VirtualDriver : public oni::driver::DriverBase {
 public:
  explicit VirtualDriver(OniDriverServices* services) : DriverBase(services) {}
  ~VirtualDriver() override { shutdown(); }

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed,
                       void* cookie) override {
    DriverBase::initialize(connected, disconnected, state_changed, cookie);
    if (const char* env = std::getenv("EMF_VIRTUAL_DEVICES")) {
      std::string list = env;
      size_t pos = 0;
      while (pos <= list.size()) {
        size_t semi = list.find(',', pos);
        if (semi == std::string::npos) semi = list.size();
        std::string item = list.substr(pos, semi - pos);
        pos = semi + 1;
        if (item.empty()) continue;
        if (item.rfind(kScheme, 0) != 0) item = kScheme + item;
        std::string error;
        if (!addDevice(item, &error)) {
          getServices().errorLoggerAppend("emf-virtual: EMF_VIRTUAL_DEVICES: %s", error.c_str());
        }
      }
    }
    watcher_ = std::thread([this] { watchControlFiles(); });
    return ONI_STATUS_OK;
  }

  OniStatus tryDevice(const char* uri) override {
    if (uri == nullptr || std::strncmp(uri, kScheme, std::strlen(kScheme)) != 0) {
      return ONI_STATUS_ERROR;
    }
    std::string error;
    if (!addDevice(uri, &error)) {
      getServices().errorLoggerAppend("emf-virtual: %s", error.c_str());
      return ONI_STATUS_ERROR;
    }
    return ONI_STATUS_OK;
  }

  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    Entry* e = find(uri);
    if (e == nullptr) {
      getServices().errorLoggerAppend("emf-virtual: unknown device '%s'", uri);
      return nullptr;
    }
    if (!e->plugged.load()) {
      getServices().errorLoggerAppend("emf-virtual: device '%s' is unplugged", uri);
      return nullptr;
    }
    return new VirtualDevice(*e, getServices());
  }

  void deviceClose(oni::driver::DeviceBase* device) override { delete device; }

  void shutdown() override {
    {
      std::lock_guard<std::mutex> l(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (watcher_.joinable()) watcher_.join();
  }

  void* enableFrameSync(oni::driver::StreamBase** /*streams*/, int /*count*/) override {
    // Depth and colour of one frame are always emitted together with the same frameIndex;
    // OpenNI2's synced frame holder does the matching. A token is all that is needed.
    return new int(1);
  }
  void disableFrameSync(void* group) override { delete static_cast<int*>(group); }

 private:
  Entry* find(const std::string& uri) {
    std::lock_guard<std::mutex> l(mutex_);
    auto it = entries_.find(uri);
    return it == entries_.end() ? nullptr : it->second.get();
  }

  /// Creates the entry for `uri` (or finds it) and announces the device if it is plugged.
  bool addDevice(const std::string& uri, std::string* error) {
    if (uri.size() >= ONI_MAX_STR) {
      *error = "URI longer than " + std::to_string(ONI_MAX_STR - 1) + " characters: " + uri;
      return false;
    }
    if (Entry* e = find(uri)) {
      if (!e->plugged.load()) {
        *error = "device '" + uri + "' is unplugged";
        return false;
      }
      return true;
    }
    auto e = std::make_unique<Entry>();
    if (!parseUri(uri, &e->params, error)) return false;
    if (!TumFolder::load(e->params.folder, e->params.depth_scale, &e->folder, error)) {
      return false;
    }
    std::snprintf(e->info.uri, ONI_MAX_STR, "%s", uri.c_str());
    std::snprintf(e->info.vendor, ONI_MAX_STR, "emf");
    std::snprintf(e->info.name, ONI_MAX_STR, "virtual RGB-D device (TUM folder)");
    e->plugged = !controlSaysUnplugged(e->params.control);
    if (!e->plugged) {
      *error = "device '" + uri + "' is unplugged (control file " + e->params.control + ")";
    }
    Entry* raw = e.get();
    {
      std::lock_guard<std::mutex> l(mutex_);
      entries_[uri] = std::move(e);
    }
    if (!raw->plugged) return false;
    deviceConnected(&raw->info);
    return true;
  }

  static bool controlSaysUnplugged(const std::string& path) {
    if (path.empty()) return false;
    std::ifstream in(path);
    std::string word;
    return in && (in >> word) && word == "unplugged";
  }

  /// Simulated USB cable: follows each device's control file.
  void watchControlFiles() {
    std::unique_lock<std::mutex> l(mutex_);
    while (!stopping_) {
      std::vector<Entry*> entries;
      for (auto& kv : entries_) {
        if (!kv.second->params.control.empty()) entries.push_back(kv.second.get());
      }
      l.unlock();
      for (Entry* e : entries) {
        const bool plugged = !controlSaysUnplugged(e->params.control);
        if (plugged == e->plugged.load()) continue;
        e->plugged = plugged;
        if (plugged) {
          deviceConnected(&e->info);
          deviceStateChanged(&e->info, ONI_DEVICE_STATE_OK);
        } else {
          deviceStateChanged(&e->info, ONI_DEVICE_STATE_ERROR);
          deviceDisconnected(&e->info);
        }
      }
      l.lock();
      wake_.wait_for(l, std::chrono::milliseconds(kControlPollMs), [this] { return stopping_; });
    }
  }

  std::mutex mutex_;  // guards entries_ (the map; entries themselves are never removed)
  std::map<std::string, std::unique_ptr<Entry>> entries_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread watcher_;
};

VirtualDriver* g_driver = nullptr;

}  // namespace
}  // namespace emf::fw::virtual_device

// ---- the C entry points libOpenNI2 looks up in a driver (see OniDriverAPI.h) -------------------
using emf::fw::virtual_device::g_driver;
using emf::fw::virtual_device::VirtualDriver;
using oni::driver::DeviceBase;
using oni::driver::StreamBase;

ONI_C_API_EXPORT void oniDriverCreate(OniDriverServices* services) {
  g_driver = new VirtualDriver(services);
}
ONI_C_API_EXPORT void oniDriverDestroy() {
  if (g_driver) g_driver->shutdown();
  delete g_driver;
  g_driver = nullptr;
}
ONI_C_API_EXPORT OniStatus oniDriverInitialize(oni::driver::DeviceConnectedCallback connected,
                                               oni::driver::DeviceDisconnectedCallback disconnected,
                                               oni::driver::DeviceStateChangedCallback changed,
                                               void* cookie) {
  return g_driver->initialize(connected, disconnected, changed, cookie);
}
ONI_C_API_EXPORT OniStatus oniDriverTryDevice(const char* uri) { return g_driver->tryDevice(uri); }
ONI_C_API_EXPORT DeviceBase* oniDriverDeviceOpen(const char* uri, const char* mode) {
  return g_driver->deviceOpen(uri, mode);
}
ONI_C_API_EXPORT void oniDriverDeviceClose(DeviceBase* device) { g_driver->deviceClose(device); }
ONI_C_API_EXPORT OniStatus oniDriverDeviceGetSensorInfoList(DeviceBase* device,
                                                            OniSensorInfo** infos, int* count) {
  return device->getSensorInfoList(infos, count);
}
ONI_C_API_EXPORT StreamBase* oniDriverDeviceCreateStream(DeviceBase* device, OniSensorType type) {
  return device->createStream(type);
}
ONI_C_API_EXPORT void oniDriverDeviceDestroyStream(DeviceBase* device, StreamBase* stream) {
  device->destroyStream(stream);
}
ONI_C_API_EXPORT OniStatus oniDriverDeviceSetProperty(DeviceBase* device, int id, const void* data,
                                                      int size) {
  return device->setProperty(id, data, size);
}
ONI_C_API_EXPORT OniStatus oniDriverDeviceGetProperty(DeviceBase* device, int id, void* data,
                                                      int* size) {
  return device->getProperty(id, data, size);
}
ONI_C_API_EXPORT OniBool oniDriverDeviceIsPropertySupported(DeviceBase* device, int id) {
  return device->isPropertySupported(id);
}
ONI_C_API_EXPORT void oniDriverDeviceSetPropertyChangedCallback(
    DeviceBase* device, oni::driver::PropertyChangedCallback handler, void* cookie) {
  device->setPropertyChangedCallback(handler, cookie);
}
ONI_C_API_EXPORT void oniDriverDeviceNotifyAllProperties(DeviceBase* device) {
  device->notifyAllProperties();
}
ONI_C_API_EXPORT OniStatus oniDriverDeviceInvoke(DeviceBase* device, int command, void* data,
                                                 int size) {
  return device->invoke(command, data, size);
}
ONI_C_API_EXPORT OniBool oniDriverDeviceIsCommandSupported(DeviceBase* device, int command) {
  return device->isCommandSupported(command);
}
ONI_C_API_EXPORT OniStatus oniDriverDeviceTryManualTrigger(DeviceBase* device) {
  return device->tryManualTrigger();
}
ONI_C_API_EXPORT OniBool
oniDriverDeviceIsImageRegistrationModeSupported(DeviceBase* device, OniImageRegistrationMode mode) {
  return device->isImageRegistrationModeSupported(mode);
}
ONI_C_API_EXPORT void oniDriverStreamSetServices(StreamBase* stream, OniStreamServices* services) {
  // StreamServices adds only inline helpers to OniStreamServices (no data members), as in
  // OpenNI2's own ONI_EXPORT_DRIVER macro.
  stream->setServices(static_cast<oni::driver::StreamServices*>(services));
}
ONI_C_API_EXPORT OniStatus oniDriverStreamSetProperty(StreamBase* stream, int id, const void* data,
                                                      int size) {
  return stream->setProperty(id, data, size);
}
ONI_C_API_EXPORT OniStatus oniDriverStreamGetProperty(StreamBase* stream, int id, void* data,
                                                      int* size) {
  return stream->getProperty(id, data, size);
}
ONI_C_API_EXPORT OniBool oniDriverStreamIsPropertySupported(StreamBase* stream, int id) {
  return stream->isPropertySupported(id);
}
ONI_C_API_EXPORT void oniDriverStreamSetPropertyChangedCallback(
    StreamBase* stream, oni::driver::PropertyChangedCallback handler, void* cookie) {
  stream->setPropertyChangedCallback(handler, cookie);
}
ONI_C_API_EXPORT void oniDriverStreamNotifyAllProperties(StreamBase* stream) {
  stream->notifyAllProperties();
}
ONI_C_API_EXPORT OniStatus oniDriverStreamInvoke(StreamBase* stream, int command, void* data,
                                                 int size) {
  return stream->invoke(command, data, size);
}
ONI_C_API_EXPORT OniBool oniDriverStreamIsCommandSupported(StreamBase* stream, int command) {
  return stream->isCommandSupported(command);
}
ONI_C_API_EXPORT OniStatus oniDriverStreamStart(StreamBase* stream) { return stream->start(); }
ONI_C_API_EXPORT void oniDriverStreamStop(StreamBase* stream) { stream->stop(); }
ONI_C_API_EXPORT int oniDriverStreamGetRequiredFrameSize(StreamBase* stream) {
  return stream->getRequiredFrameSize();
}
ONI_C_API_EXPORT void oniDriverStreamSetNewFrameCallback(StreamBase* stream,
                                                         oni::driver::NewFrameCallback handler,
                                                         void* cookie) {
  stream->setNewFrameCallback(handler, cookie);
}
ONI_C_API_EXPORT OniStatus oniDriverStreamConvertDepthToColorCoordinates(StreamBase* depth,
                                                                         StreamBase* color, int x,
                                                                         int y, OniDepthPixel z,
                                                                         int* cx, int* cy) {
  return depth->convertDepthToColorCoordinates(color, x, y, z, cx, cy);
}
ONI_C_API_EXPORT void* oniDriverEnableFrameSync(StreamBase** streams, int count) {
  return g_driver->enableFrameSync(streams, count);
}
ONI_C_API_EXPORT void oniDriverDisableFrameSync(void* group) { g_driver->disableFrameSync(group); }
