#include "firmware_host/v4l2/v4l2_source.h"

#include <linux/videodev2.h>
#include <poll.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "common/error.h"
#include "firmware_host/sensor_error.h"
#include "firmware_host/sensor_uri.h"
#include "firmware_host/v4l2/pixel_formats.h"

namespace emf::fw {

V4l2Source::V4l2Source(const std::string& uri, const core::SourceOptions& options)
    : pairer_(options.max_time_diff_s) {
  SensorUri u(uri);
  if (u.scheme() != "v4l2") throw IoError("'" + uri + "' is not a v4l2: URI");
  const int width = u.integer("width", 640, 1, 16384);
  const int height = u.integer("height", 480, 1, 16384);
  const int fps = u.integer("fps", 30, 1, 1000);
  const double depth_scale = u.real("depth_scale", 1000.0, 1.0, 1e6);
  timeout_s_ = u.real("timeout_s", 2.0, 0.05, 3600.0);
  const double max_dt = u.real("max_time_diff_s", options.max_time_diff_s, 0.0, 1.0);
  const double fx = u.real("fx", options.fx, 0.0, 1e5);
  const double fy = u.real("fy", options.fy, 0.0, 1e5);
  const double cx = u.real("cx", options.cx, 0.0, 1e5);
  const double cy = u.real("cy", options.cy, 0.0, 1e5);
  max_frames_ = u.integer("max_frames", options.max_frames, 0, 100000000);
  u.checkAllUsed();
  pairer_ = FramePairer(max_dt);
  depth_unit_m_ = 1.0 / depth_scale;

  const std::string nodes = u.target();
  const size_t comma = nodes.find(',');
  const std::string depth_node = nodes.substr(0, comma);
  const std::string color_node = comma == std::string::npos ? "" : nodes.substr(comma + 1);
  if (depth_node.empty()) {
    throw IoError("'" + uri + "': no device node (use v4l2:/dev/videoN[,/dev/videoM])");
  }
  if (fx <= 0 || fy <= 0) {
    throw IoError("'" + uri +
                  "': V4L2 does not report intrinsics: give them in the URI "
                  "(?fx=..&fy=..[&cx=..&cy=..]) or set source.fx and source.fy");
  }
  depth_ = std::make_unique<V4l2Device>(depth_node);
  const V4l2Format df = depth_->negotiate({V4L2_PIX_FMT_Z16, V4L2_PIX_FMT_Y16}, width, height, fps);
  V4l2Format cf;
  if (!color_node.empty()) {
    color_ = std::make_unique<V4l2Device>(color_node);
    cf = color_->negotiate({V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_JPEG}, df.width,
                           df.height, fps);
  }
  intrinsics_.width = df.width;
  intrinsics_.height = df.height;
  intrinsics_.fx = fx;
  intrinsics_.fy = fy;
  intrinsics_.cx = cx > 0 ? cx : df.width / 2.0;
  intrinsics_.cy = cy > 0 ? cy : df.height / 2.0;
  depth_->start();
  if (color_) color_->start();
  char text[512];
  std::snprintf(text, sizeof(text), "V4L2 %s (%s) %s %dx%d%s%s%s%s", depth_node.c_str(),
                depth_->card().c_str(), fourccName(df.fourcc).c_str(), df.width, df.height,
                color_ ? ", colour " : "", color_ ? color_node.c_str() : "", color_ ? " " : "",
                color_ ? fourccName(cf.fourcc).c_str() : "");
  description_ = text;
}

V4l2Source::~V4l2Source() { close(); }

void V4l2Source::close() {
  color_.reset();
  depth_.reset();
}

bool V4l2Source::next(core::Frame& frame) {
  if (!depth_) throw IoError("v4l2: source is closed");
  if (max_frames_ > 0 && delivered_ >= max_frames_) return false;
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(timeout_s_));
  PairedFrame pair;
  while (!pairer_.pop(&pair)) {
    pollfd fds[2] = {{depth_->fd(), POLLIN, 0}, {color_ ? color_->fd() : -1, POLLIN, 0}};
    const auto left_ms =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    if (left_ms.count() <= 0) {
      throw SensorDisconnected("v4l2: no frame from " + depth_->path() + " for " +
                               std::to_string(timeout_s_) + " s (after " +
                               std::to_string(delivered_) +
                               " frames): the camera stalled or was unplugged");
    }
    const int n = ::poll(fds, color_ ? 2 : 1, static_cast<int>(left_ms.count()));
    if (n == -1) {
      if (errno == EINTR) continue;
      throw IoError("v4l2: poll failed: " + std::string(std::strerror(errno)));
    }
    for (int i = 0; i < (color_ ? 2 : 1); ++i) {
      if (fds[i].revents & (POLLERR | POLLHUP | POLLNVAL)) {
        throw SensorDisconnected("v4l2: " + (i == 0 ? depth_->path() : color_->path()) +
                                 " reported an error (unplugged?) after " +
                                 std::to_string(delivered_) + " frames: reconnect the camera");
      }
    }
    try {
      if (fds[0].revents & POLLIN) {
        const V4l2Format& f = depth_->format();
        depth_->dequeue([&](const uint8_t* data, size_t bytes, double t, uint32_t seq) {
          if (bytes < f.bytes_per_line * static_cast<size_t>(f.height)) return;  // short frame
          TimedImage img;
          img.timestamp_s = t;
          img.sequence = seq;
          depth16ToMetres(data, f.width, f.height, f.bytes_per_line, depth_unit_m_, img.image);
          if (color_) {
            pairer_.addDepth(std::move(img));
          } else {
            PairedFrame p;
            p.depth = std::move(img);
            pair = std::move(p);
          }
        });
        if (!color_ && !pair.depth.image.empty()) break;
      }
      if (color_ && (fds[1].revents & POLLIN)) {
        const V4l2Format& f = color_->format();
        color_->dequeue([&](const uint8_t* data, size_t bytes, double t, uint32_t seq) {
          TimedImage img;
          img.timestamp_s = t;
          img.sequence = seq;
          if (f.fourcc == V4L2_PIX_FMT_YUYV) {
            if (bytes < f.bytes_per_line * static_cast<size_t>(f.height)) return;
            yuyvToBgr(data, f.width, f.height, f.bytes_per_line, img.image);
          } else if (!decodeMjpeg(data, bytes, img.image)) {
            return;  // corrupt JPEG (happens on USB errors): skip the frame
          }
          pairer_.addColor(std::move(img));
        });
      }
    } catch (const IoError& e) {
      if (std::strstr(e.what(), "unplugged")) throw SensorDisconnected(e.what());
      throw;
    }
  }
  // The driver numbers every captured frame: a gap is frames lost while the caller was busy
  // (the driver's queue was full) or depth frames the pairer dropped.
  if (delivered_ > 0 && pair.depth.sequence > last_sequence_ + 1) {
    dropped_ += pair.depth.sequence - last_sequence_ - 1;
  }
  last_sequence_ = pair.depth.sequence;
  frame.index = delivered_++;
  frame.timestamp = pair.depth.timestamp_s;
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.6f", frame.timestamp);
  frame.timestamp_text = stamp;
  frame.depth = pair.depth.image;
  frame.color = pair.color.image;
  frame.rgb_timestamp = pair.color.image.empty() ? frame.timestamp : pair.color.timestamp_s;
  frame.detections.reset();
  frame.T_world_camera_gt.reset();
  frame.T_world_object_gt.clear();
  frame.instance_ids.release();
  return true;
}

}  // namespace emf::fw
