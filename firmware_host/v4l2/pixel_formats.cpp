#include "firmware_host/v4l2/pixel_formats.h"

#include <cstring>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace emf::fw {

std::string fourccName(uint32_t fourcc) {
  std::string s(4, ' ');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    s[static_cast<size_t>(i)] = (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

void yuyvToBgr(const uint8_t* yuyv, int width, int height, size_t stride_bytes, cv::Mat& bgr) {
  // OpenCV's YUV422 (YUY2) conversion implements BT.601 limited range.
  const cv::Mat src(height, width, CV_8UC2, const_cast<uint8_t*>(yuyv), stride_bytes);
  cv::cvtColor(src, bgr, cv::COLOR_YUV2BGR_YUYV);
}

bool decodeMjpeg(const uint8_t* data, size_t bytes, cv::Mat& bgr) {
  if (bytes < 4 || data[0] != 0xff || data[1] != 0xd8) return false;
  const cv::Mat buf(1, static_cast<int>(bytes), CV_8UC1, const_cast<uint8_t*>(data));
  cv::Mat out = cv::imdecode(buf, cv::IMREAD_COLOR);
  if (out.empty()) return false;
  bgr = out;
  return true;
}

void depth16ToMetres(const uint8_t* data, int width, int height, size_t stride_bytes, double unit_m,
                     cv::Mat& depth) {
  depth.create(height, width, CV_32FC1);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int y = 0; y < height; ++y) {
    const uint8_t* row = data + static_cast<size_t>(y) * stride_bytes;
    float* dst = depth.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      uint16_t v;
      std::memcpy(&v, row + 2 * x, 2);  // little-endian, possibly unaligned
      dst[x] = v == 0 ? nan : static_cast<float>(v * unit_m);
    }
  }
}

}  // namespace emf::fw
