// Pixel-format conversions of the V4L2 backend (pure functions, testable without a device):
// YUYV 4:2:2 -> BGR, Motion-JPEG -> BGR, 16-bit depth (Z16 / Y16) -> metres.
#pragma once

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace emf::fw {

/// "YUYV", "MJPG", "Z16 " ... for a V4L2 fourcc (non-printable bytes as '?').
std::string fourccName(uint32_t fourcc);

/// Converts packed YUYV 4:2:2 (Y0 U Y1 V per 2 pixels; ITU-R BT.601 limited range, what UVC
/// cameras send) to BGR. `stride_bytes` >= 2 * width. `bgr` is (re)allocated to height x width.
void yuyvToBgr(const uint8_t* yuyv, int width, int height, size_t stride_bytes, cv::Mat& bgr);

/// Decodes one Motion-JPEG frame (a JPEG image; UVC cameras often omit the Huffman tables,
/// which the decoder then takes from the JPEG standard). Returns false for undecodable data.
bool decodeMjpeg(const uint8_t* data, size_t bytes, cv::Mat& bgr);

/// Converts 16-bit depth in sensor units to metres: depth_m = value * unit_m, 0 -> NaN (no
/// measurement). `stride_bytes` >= 2 * width. `depth` is (re)allocated to CV_32F height x width.
void depth16ToMetres(const uint8_t* data, int width, int height, size_t stride_bytes, double unit_m,
                     cv::Mat& depth);

}  // namespace emf::fw
