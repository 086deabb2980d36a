#include "map/device_image.h"

#include <string>

#include "common/error.h"

namespace emf::map {

DeviceImage::DeviceImage(cl::Context& ctx, int max_width, int max_height)
    : ctx_(ctx), max_width_(max_width), max_height_(max_height) {
  if (max_width <= 0 || max_height <= 0) {
    throw InvalidArgument("DeviceImage needs a positive capacity, got " +
                          std::to_string(max_width) + "x" + std::to_string(max_height));
  }
  buffer_ = ctx_.buffer(CL_MEM_READ_WRITE, static_cast<size_t>(max_width) *
                                               static_cast<size_t>(max_height) * sizeof(float));
}

void DeviceImage::upload(const cv::Mat& image, const char* what) {
  if (image.type() != CV_32FC1) {
    throw InvalidArgument(std::string(what) + ": expected a CV_32FC1 image, got type " +
                          std::to_string(image.type()));
  }
  if (image.cols > max_width_ || image.rows > max_height_ || image.empty()) {
    throw InvalidArgument(std::string(what) + ": " + std::to_string(image.cols) + "x" +
                          std::to_string(image.rows) + " does not fit the " +
                          std::to_string(max_width_) + "x" + std::to_string(max_height_) +
                          " device image allocated at start-up");
  }
  width_ = image.cols;
  height_ = image.rows;
  const size_t row_bytes = static_cast<size_t>(width_) * sizeof(float);
  if (image.isContinuous()) {
    ctx_.write(buffer_, image.ptr<float>(0), row_bytes * static_cast<size_t>(height_));
    return;
  }
  for (int y = 0; y < height_; ++y) {
    ctx_.write(buffer_, image.ptr<float>(y), row_bytes, row_bytes * static_cast<size_t>(y));
  }
}

cv::Mat DeviceImage::download() const {
  cv::Mat out(height_, width_, CV_32FC1);
  ctx_.read(buffer_, out.ptr<float>(0), out.total() * sizeof(float));
  return out;
}

}  // namespace emf::map
