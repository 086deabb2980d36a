// V4L2 depth cameras as a FrameSource (`v4l2:` URIs): one node with 16-bit depth (Z16 / Y16),
// optionally a second node with colour (YUYV or MJPEG), paired by timestamp (FramePairer).
//
// URI: v4l2:/dev/videoN[,/dev/videoM][?width=W&height=H&fps=F&depth_scale=S&timeout_s=T
//       &max_time_diff_s=D&fx=..&fy=..&cx=..&cy=..&max_frames=N]
//   width/height/fps  requested mode of both nodes (default 640x480 @ 30)
//   depth_scale       16-bit depth units per metre (default 1000: RealSense / Orbbec UVC Z16)
//   timeout_s         no frame for this long = disconnected (default 2 s)
//   max_time_diff_s   depth/colour pairing window (default source.max_time_diff_s)
//   fx,fy,cx,cy       intrinsics (V4L2 does not report them: fx and fy are required, here or in
//                     source.fx / source.fy; cx, cy default to the image centre)
// Frames: depth CV_32F metres (0 -> NaN), colour BGR, timestamps = driver buffer timestamps
// (CLOCK_MONOTONIC), seconds.
#pragma once

#include <memory>
#include <string>

#include "core/frame_source.h"
#include "firmware_host/v4l2/frame_pairer.h"
#include "firmware_host/v4l2/v4l2_device.h"

namespace emf::fw {

class V4l2Source : public core::FrameSource {
 public:
  /// Opens and starts the node(s). Throws IoError naming the node and what to do (missing node,
  /// permissions, no depth format, missing intrinsics, bad parameter).
  V4l2Source(const std::string& uri, const core::SourceOptions& options);
  ~V4l2Source() override;

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  /// Next paired frame. Throws SensorDisconnected when the camera is gone or sends nothing for
  /// timeout_s.
  bool next(core::Frame& frame) override;
  bool isLive() const override { return true; }
  /// Gaps in the driver's depth frame sequence numbers since the first frame.
  int64_t droppedFrames() const override { return dropped_; }
  std::string describe() const override { return description_; }
  void close() override;

  const PairerStats& pairing() const { return pairer_.stats(); }

 private:
  std::unique_ptr<V4l2Device> depth_;
  std::unique_ptr<V4l2Device> color_;
  FramePairer pairer_;
  core::Intrinsics intrinsics_;
  std::string description_;
  double depth_unit_m_ = 0.001;
  double timeout_s_ = 2.0;
  int64_t delivered_ = 0;
  int64_t dropped_ = 0;
  int64_t last_sequence_ = 0;
  int64_t max_frames_ = 0;
};

}  // namespace emf::fw
