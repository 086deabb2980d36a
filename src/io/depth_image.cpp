#include "io/depth_image.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <vector>

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

std::string depthScaleWarning(const cv::Mat& depth_units, double units_per_metre) {
  CV_Assert(depth_units.type() == CV_16UC1);
  std::vector<uint16_t> valid;
  valid.reserve(depth_units.total());
  for (int y = 0; y < depth_units.rows; ++y) {
    const uint16_t* row = depth_units.ptr<uint16_t>(y);
    for (int x = 0; x < depth_units.cols; ++x) {
      if (row[x] != 0) valid.push_back(row[x]);
    }
  }
  if (valid.empty() || valid.size() * 100 < depth_units.total()) return "";
  const auto quantile_m = [&valid, units_per_metre](double q) {
    const auto k = valid.begin() + static_cast<std::ptrdiff_t>(q * double(valid.size() - 1));
    std::nth_element(valid.begin(), k, valid.end());
    return *k / units_per_metre;
  };
  constexpr double kMillimetres = 1000.0, kTum = 5000.0;
  char text[320];
  const double p95 = quantile_m(0.95);
  if (p95 < 1.0 && units_per_metre != kMillimetres) {
    std::snprintf(text, sizeof(text),
                  "95%% of the valid depth is closer than %.2f m at depth_scale %g units per "
                  "metre; if the images are in millimetres (7-Scenes, OpenNI recordings), add "
                  "?depth_scale=1000 to the source URI",
                  p95, units_per_metre);
    return text;
  }
  const double median = quantile_m(0.5);
  if (median > 10.0 && units_per_metre != kTum) {
    std::snprintf(text, sizeof(text),
                  "half of the valid depth is farther than %.1f m at depth_scale %g units per "
                  "metre; if the images are TUM-scaled (5000 per metre), add ?depth_scale=5000 to "
                  "the source URI",
                  median, units_per_metre);
    return text;
  }
  return "";
}

std::string describeMatType(int type) {
  static const char* kDepths[] = {"8-bit",      "8-bit signed", "16-bit",       "16-bit signed",
                                  "32-bit int", "32-bit float", "64-bit float", "16-bit float"};
  return std::string(kDepths[CV_MAT_DEPTH(type)]) + " " + std::to_string(CV_MAT_CN(type)) +
         "-channel";
}

cv::Mat readImageFile(const std::string& path, int flags, const std::string& what,
                      const std::string& context) {
  const auto fail = [&](int err) {
    throw IoError((context.empty() ? "" : context + ": ") + "cannot read " + what + " '" + path +
                  "': " + (err == ENOENT ? "it does not exist" : std::strerror(err)));
  };
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(errno);
  std::vector<uchar> bytes;
  uchar chunk[65536];
  size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof(chunk), f)) > 0)
    bytes.insert(bytes.end(), chunk, chunk + n);
  const int err = std::ferror(f) ? errno : 0;
  std::fclose(f);
  if (err != 0) fail(err);
  if (bytes.empty()) return cv::Mat();
  try {
    return cv::imdecode(bytes, flags);
  } catch (const cv::Exception&) {
    return cv::Mat();  // the caller says what it expected
  }
}

cv::Mat readDepthUnits(const std::string& path, const std::string& context) {
  cv::Mat img = readImageFile(path, cv::IMREAD_UNCHANGED, "depth image", context);
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
  cv::Mat img = readImageFile(path, cv::IMREAD_COLOR, "colour image", context);
  if (img.empty()) {
    throw IoError(context + ": cannot decode colour image '" + path + "' (corrupt file?)");
  }
  return img;
}

void enableOpenExr() { setenv("OPENCV_IO_ENABLE_OPENEXR", "1", /*overwrite=*/0); }

}  // namespace emf::io
