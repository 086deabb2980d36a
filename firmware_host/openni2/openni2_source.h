// OpenNI2 sensors and recordings as a FrameSource (`openni2:` URIs), through Debian's libOpenNI2:
// PrimeSense / Asus Xtion / Kinect-class devices (PS1080 driver), `.oni` recordings (OpenNI2's
// own file driver) and the emf virtual device (emf-virtual://, firmware_host/openni2/
// virtual_device/).
//
// URI: openni2:[<device uri> | <file.oni>][?registration=0|1&sync=0|1&color=0|1
//       &timeout_s=S&width=W&height=H&fps=F&fx=..&fy=..&cx=..&cy=..&max_frames=N]
//   ""            the first device OpenNI2 enumerates
//   registration  depth registered to colour when the device supports it (default 1)
//   sync          depth/colour frame sync when supported (default 1)
//   color         open the colour stream (default 1)
//   timeout_s     no depth frame for this long = disconnected (default 2 s)
//   width/height/fps  preferred depth mode (default 640x480 @ 30; the closest mode is used)
//   fx,fy,cx,cy   intrinsics overriding the device's (pixels)
// Frames: depth CV_32F metres (0 -> NaN) from DEPTH_1_MM / DEPTH_100_UM, colour BGR from RGB888;
// timestamps are OpenNI2's microsecond stamps in seconds.
// Intrinsics: from the field of view of the depth stream (of the colour stream when registration
// is on): fx = w / (2 tan(hfov / 2)), cx = w / 2 (OpenNI2's own depth-to-world model), unless
// overridden.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/frame_source.h"

namespace emf::fw {

/// One device OpenNI2 can open.
struct Openni2DeviceInfo {
  std::string uri;
  std::string vendor;
  std::string name;
  uint16_t usb_vendor_id = 0;
  uint16_t usb_product_id = 0;
};

/// Devices OpenNI2 enumerates now (initialises OpenNI2 for the call). Throws IoError when
/// OpenNI2 cannot be initialised (e.g. no drivers found), with its extended error.
std::vector<Openni2DeviceInfo> listOpenni2Devices();

/// Folder OpenNI2 loads drivers from in this process (beside libOpenNI2), for messages.
std::string openni2DriverFolder();

class Openni2Source : public core::FrameSource {
 public:
  /// Opens `uri` (openni2:...). Throws IoError naming the device and what to do when no device
  /// is found, the device cannot be opened, a stream cannot be created/started, a parameter is
  /// unknown or out of range.
  Openni2Source(const std::string& uri, const core::SourceOptions& options);
  ~Openni2Source() override;

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  /// Waits for the next depth frame (and the matching colour frame). Returns false after the
  /// last frame of a recording. Throws SensorDisconnected when the device is unplugged or sends
  /// no depth frame within timeout_s.
  bool next(core::Frame& frame) override;
  int64_t size() const override { return num_frames_; }
  bool isLive() const override { return live_; }
  /// Live devices (the virtual one included): gaps in OpenNI2's depth frame numbers, i.e.
  /// frames the device delivered while the caller was busy. Recordings play on demand: 0.
  int64_t droppedFrames() const override { return dropped_; }
  std::string describe() const override { return description_; }
  void close() override;

  /// True when depth is registered to the colour camera (device support + registration=1).
  bool registered() const { return registered_; }
  /// True when OpenNI2 frame sync is active.
  bool synced() const { return synced_; }
  /// The OpenNI2 URI of the opened device.
  const std::string& deviceUri() const { return device_uri_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  core::Intrinsics intrinsics_;
  std::string description_;
  std::string device_uri_;
  std::string uri_;
  int64_t num_frames_ = -1;
  int64_t delivered_ = 0;
  int64_t dropped_ = 0;
  int64_t max_frames_ = 0;
  int last_frame_index_ = 0;
  bool live_ = true;
  bool registered_ = false;
  bool synced_ = false;
  double timeout_s_ = 2.0;
};

}  // namespace emf::fw
