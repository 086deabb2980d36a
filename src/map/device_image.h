// A float image on the device with a capacity fixed at construction: uploading a frame reuses
// the buffer (no allocation per frame). Used for depth (metres, NaN = invalid), association
// weights q and detection masks.
#pragma once

#include <opencv2/core.hpp>

#include "cl/context.h"

namespace emf::map {

class DeviceImage {
 public:
  /// Room for images of up to max_width x max_height floats.
  DeviceImage(cl::Context& ctx, int max_width, int max_height);

  /// Copies a CV_32F image (continuous or not). Throws InvalidArgument when it is not CV_32FC1
  /// or larger than the capacity, naming `what` (e.g. "depth of frame 12").
  void upload(const cv::Mat& image, const char* what = "image");
  /// Downloads the current image (allocates the Mat; for tests and tools).
  cv::Mat download() const;

  const cl::MemHandle& buffer() const { return buffer_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  cl::Context& ctx_;
  cl::MemHandle buffer_;
  int max_width_ = 0, max_height_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace emf::map
