#include "firmware_host/v4l2/v4l2_device.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "common/error.h"
#include "common/log.h"
#include "firmware_host/v4l2/pixel_formats.h"

namespace emf::fw {
namespace {

std::string errnoText(int e) { return std::string(std::strerror(e)); }

}  // namespace

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do {
    r = ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

V4l2Format fixUpFormat(V4l2Format f, int bytes_per_pixel) {
  if (bytes_per_pixel > 0) {
    const size_t min_line = static_cast<size_t>(f.width) * static_cast<size_t>(bytes_per_pixel);
    if (f.bytes_per_line < min_line) f.bytes_per_line = min_line;
    const size_t min_size = f.bytes_per_line * static_cast<size_t>(f.height);
    if (f.size_image < min_size) f.size_image = min_size;
  } else if (f.size_image == 0) {
    f.size_image = 1;
  }
  return f;
}

V4l2Device::V4l2Device(const std::string& path) : path_(path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == -1) {
    throw IoError("v4l2: " + path + ": " + errnoText(errno) +
                  " (no such video node: `emf devices` lists the connected cameras)");
  }
  if (!S_ISCHR(st.st_mode)) {
    throw IoError("v4l2: " + path + " is not a device node");
  }
  fd_ = ::open(path.c_str(), O_RDWR | O_NONBLOCK, 0);
  if (fd_ == -1) {
    const int e = errno;
    throw IoError("v4l2: cannot open " + path + ": " + errnoText(e) +
                  (e == EACCES ? " (add the user to the 'video' group)" : "") +
                  (e == EBUSY ? " (another program is using the camera)" : ""));
  }
  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) == -1) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw IoError("v4l2: " + path + " is not a V4L2 device (VIDIOC_QUERYCAP: " + errnoText(e) +
                  ")");
  }
  card_ = reinterpret_cast<const char*>(cap.card);
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) {
    ::close(fd_);
    fd_ = -1;
    throw IoError("v4l2: " + path + " (" + card_ +
                  ") is not a video capture node (metadata or output node?): try the "
                  "neighbouring /dev/videoN");
  }
  if (!(caps & V4L2_CAP_STREAMING)) {
    ::close(fd_);
    fd_ = -1;
    throw IoError("v4l2: " + path + " (" + card_ + ") does not support streaming I/O");
  }
}

V4l2Device::~V4l2Device() {
  stop();
  if (fd_ != -1) ::close(fd_);
}

std::vector<uint32_t> V4l2Device::formats() const {
  std::vector<uint32_t> out;
  for (uint32_t i = 0;; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_ENUM_FMT, &d) == -1) break;
    out.push_back(d.pixelformat);
  }
  return out;
}

V4l2Format V4l2Device::negotiate(const std::vector<uint32_t>& preferred, int width, int height,
                                 int fps) {
  const std::vector<uint32_t> offered = formats();
  uint32_t chosen = 0;
  for (uint32_t f : preferred) {
    if (std::find(offered.begin(), offered.end(), f) != offered.end()) {
      chosen = f;
      break;
    }
  }
  if (chosen == 0) {
    std::string want, have;
    for (uint32_t f : preferred) want += (want.empty() ? "" : ", ") + fourccName(f);
    for (uint32_t f : offered) have += (have.empty() ? "" : ", ") + fourccName(f);
    throw IoError("v4l2: " + path_ + " (" + card_ + ") offers " +
                  (have.empty() ? std::string("no formats") : have) + "; need one of " + want);
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<uint32_t>(width);
  fmt.fmt.pix.height = static_cast<uint32_t>(height);
  fmt.fmt.pix.pixelformat = chosen;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) == -1) {
    throw IoError("v4l2: " + path_ + ": setting " + fourccName(chosen) + " " +
                  std::to_string(width) + "x" + std::to_string(height) +
                  " failed (VIDIOC_S_FMT: " + errnoText(errno) + ")");
  }
  if (fmt.fmt.pix.pixelformat != chosen) {
    throw IoError("v4l2: " + path_ + " switched to " + fourccName(fmt.fmt.pix.pixelformat) +
                  " when asked for " + fourccName(chosen));
  }
  V4l2Format f;
  f.fourcc = chosen;
  f.width = static_cast<int>(fmt.fmt.pix.width);
  f.height = static_cast<int>(fmt.fmt.pix.height);
  f.bytes_per_line = fmt.fmt.pix.bytesperline;
  f.size_image = fmt.fmt.pix.sizeimage;
  const bool compressed = chosen == V4L2_PIX_FMT_MJPEG || chosen == V4L2_PIX_FMT_JPEG;
  format_ = fixUpFormat(f, compressed ? 0 : 2);
  if (format_.width != width || format_.height != height) {
    logInfo("v4l2: ", path_, " uses ", format_.width, "x", format_.height, " (asked for ", width,
            "x", height, ")");
  }
  if (fps > 0) {
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_G_PARM, &parm) == 0 &&
        (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
      parm.parm.capture.timeperframe.numerator = 1;
      parm.parm.capture.timeperframe.denominator = static_cast<uint32_t>(fps);
      if (xioctl(fd_, VIDIOC_S_PARM, &parm) == -1) {
        logWarning("v4l2: ", path_, ": cannot set ", fps, " fps (", errnoText(errno), ")");
      }
    }
  }
  return format_;
}

void V4l2Device::start(int buffers) {
  if (streaming_) return;
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(buffers);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) == -1) {
    throw IoError("v4l2: " + path_ + " does not support memory-mapped streaming (VIDIOC_REQBUFS: " +
                  errnoText(errno) + ")");
  }
  if (req.count < 2) {
    throw IoError("v4l2: " + path_ + ": the driver granted " + std::to_string(req.count) +
                  " buffer(s); at least 2 are needed");
  }
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) == -1) {
      stop();
      throw IoError("v4l2: " + path_ + ": VIDIOC_QUERYBUF failed: " + errnoText(errno));
    }
    Buffer b;
    b.length = buf.length;
    b.start = mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
    if (b.start == MAP_FAILED) {
      stop();
      throw IoError("v4l2: " + path_ + ": mmap of buffer " + std::to_string(i) +
                    " failed: " + errnoText(errno));
    }
    buffers_.push_back(b);
  }
  for (uint32_t i = 0; i < buffers_.size(); ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (xioctl(fd_, VIDIOC_QBUF, &buf) == -1) {
      stop();
      throw IoError("v4l2: " + path_ + ": VIDIOC_QBUF failed: " + errnoText(errno));
    }
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) == -1) {
    stop();
    throw IoError("v4l2: " + path_ + ": VIDIOC_STREAMON failed: " + errnoText(errno) +
                  " (is the USB bandwidth exhausted by another camera?)");
  }
  streaming_ = true;
}

bool V4l2Device::dequeue(const std::function<void(const uint8_t*, size_t, double, uint32_t)>& fn) {
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_DQBUF, &buf) == -1) {
    if (errno == EAGAIN) return false;
    const int e = errno;
    throw IoError("v4l2: " + path_ + ": VIDIOC_DQBUF failed: " + errnoText(e) +
                  (e == ENODEV ? " (the camera was unplugged)" : ""));
  }
  if (buf.index >= buffers_.size()) {
    throw IoError("v4l2: " + path_ + ": driver returned buffer index " + std::to_string(buf.index) +
                  " of " + std::to_string(buffers_.size()));
  }
  const Buffer& b = buffers_[buf.index];
  const size_t used = std::min<size_t>(buf.bytesused, b.length);
  const double t =
      static_cast<double>(buf.timestamp.tv_sec) + static_cast<double>(buf.timestamp.tv_usec) * 1e-6;
  if (!(buf.flags & V4L2_BUF_FLAG_ERROR)) {
    fn(static_cast<const uint8_t*>(b.start), used, t, buf.sequence);
  }
  if (xioctl(fd_, VIDIOC_QBUF, &buf) == -1) {
    throw IoError("v4l2: " + path_ + ": VIDIOC_QBUF failed: " + errnoText(errno));
  }
  return true;
}

void V4l2Device::stop() {
  if (fd_ == -1) return;
  if (streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (auto& b : buffers_) munmap(b.start, b.length);
  if (!buffers_.empty()) {
    v4l2_requestbuffers req{};
    req.count = 0;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(fd_, VIDIOC_REQBUFS, &req);
  }
  buffers_.clear();
}

}  // namespace emf::fw
