// One V4L2 video capture node with memory-mapped streaming I/O, following the kernel's
// capture example: REQBUFS -> QUERYBUF -> mmap -> QBUF -> STREAMON -> poll -> DQBUF/QBUF, every
// ioctl retried on EINTR, driver-reported sizes checked defensively. Errors are IoError naming
// the device node, the step and what to do.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace emf::fw {

/// ioctl() retried while it fails with EINTR. Returns ioctl's result (errno set on -1).
int xioctl(int fd, unsigned long request, void* arg);

struct V4l2Format {
  uint32_t fourcc = 0;
  int width = 0;
  int height = 0;
  size_t bytes_per_line = 0;
  size_t size_image = 0;
};

/// Fixes a driver-reported format the way robust capture code must: bytes per line at least
/// width * bytes_per_pixel, image size at least bytes_per_line * height (compressed formats:
/// size_image as reported, at least 1). Exposed for tests.
V4l2Format fixUpFormat(V4l2Format f, int bytes_per_pixel);

class V4l2Device {
 public:
  /// Opens the node and checks that it captures video with streaming I/O.
  explicit V4l2Device(const std::string& path);
  ~V4l2Device();
  V4l2Device(const V4l2Device&) = delete;
  V4l2Device& operator=(const V4l2Device&) = delete;

  const std::string& path() const { return path_; }
  const std::string& card() const { return card_; }
  int fd() const { return fd_; }

  /// Pixel formats the node offers (VIDIOC_ENUM_FMT).
  std::vector<uint32_t> formats() const;
  /// Picks the first of `preferred` the node offers and sets it at the size closest to
  /// width x height (VIDIOC_S_FMT); sets the frame rate when the driver supports it. Throws
  /// IoError listing what the node offers when none of `preferred` is available.
  V4l2Format negotiate(const std::vector<uint32_t>& preferred, int width, int height, int fps);
  const V4l2Format& format() const { return format_; }

  /// Maps `buffers` driver buffers and starts streaming.
  void start(int buffers = 4);
  /// Takes one filled buffer if available (non-blocking), hands it to `fn` (data, bytes used,
  /// timestamp in seconds, driver sequence number) and re-queues it. Returns false when no
  /// buffer is ready (EAGAIN).
  bool dequeue(const std::function<void(const uint8_t*, size_t, double, uint32_t)>& fn);
  /// Stops streaming and unmaps the buffers (also done by the destructor).
  void stop();

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
  };
  std::string path_;
  std::string card_;
  int fd_ = -1;
  V4l2Format format_;
  std::vector<Buffer> buffers_;
  bool streaming_ = false;
};

}  // namespace emf::fw
