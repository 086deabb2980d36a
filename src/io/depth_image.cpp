#include "io/depth_image.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"

namespace emf::io {

cv::Mat depthFromUnits(const cv::Mat& depth_units, double units_per_metre) {
  CV_Assert(depth_units.type() == CV_16UC1);
  cv::Mat out(depth_units.size(), CV_32FC1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < depth_units.rows; ++y) {
    const uint16_t* src = depth_units.ptr<uint16_t>(y);
    float* dst = out.ptr<float>(y);
    for (int x = 0; x < depth_units.cols; ++x) {
      dst[x] = src[x] == 0 ? nan : static_cast<float>(src[x] / units_per_metre);
    }
  }
  return out;
}

cv::Mat depthToUnits(const cv::Mat& depth_m, double units_per_metre) {
  CV_Assert(depth_m.type() == CV_32FC1);
  cv::Mat out(depth_m.size(), CV_16UC1);
  for (int y = 0; y < depth_m.rows; ++y) {
    const float* src = depth_m.ptr<float>(y);
    uint16_t* dst = out.ptr<uint16_t>(y);
    for (int x = 0; x < depth_m.cols; ++x) {
      const double u = std::round(static_cast<double>(src[x]) * units_per_metre);
      dst[x] = (std::isfinite(u) && u > 0 && u <= 65535.0) ? static_cast<uint16_t>(u) : 0;
    }
  }
  return out;
}

std::string describeMatType(int type) {
  static const char* kDepths[] = {"8-bit",      "8-bit signed", "16-bit",       "16-bit signed",
                                  "32-bit int", "32-bit float", "64-bit float", "16-bit float"};
  return std::string(kDepths[CV_MAT_DEPTH(type)]) + " " + std::to_string(CV_MAT_CN(type)) +
         "-channel";
}

cv::Mat readDepthUnits(const std::string& path, const std::string& context) {
  if (!std::filesystem::exists(path)) {
    throw IoError(context + ": depth image '" + path + "' does not exist");
  }
  cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) {
    throw IoError(context + ": cannot decode depth image '" + path + "' (corrupt or not a PNG)");
  }
  if (img.type() != CV_16UC1) {
    throw IoError(context + ": depth image '" + path + "' is " + describeMatType(img.type()) +
                  "; expected a 16-bit single-channel PNG (depth units, 0 = invalid)");
  }
  return img;
}

cv::Mat readColor(const std::string& path, const std::string& context) {
  if (!std::filesystem::exists(path)) {
    throw IoError(context + ": colour image '" + path + "' does not exist");
  }
  cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  if (img.empty()) {
    throw IoError(context + ": cannot decode colour image '" + path + "' (corrupt file?)");
  }
  return img;
}

void enableOpenExr() { setenv("OPENCV_IO_ENABLE_OPENEXR", "1", /*overwrite=*/0); }

}  // namespace emf::io
