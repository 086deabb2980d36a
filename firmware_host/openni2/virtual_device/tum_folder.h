// The data behind the virtual OpenNI2 device: a TUM-layout RGB-D folder (depth.txt + uint16
// depth PNGs, rgb.txt + colour JPEG/PNG images, optional calibration.txt). This code lives inside
// the OpenNI2 driver, which must not link libemf, so it has its own small parser and uses libpng
// / libjpeg directly. Errors are returned as text (the driver reports them through OpenNI2's
// error log); nothing here throws across the driver's C boundary.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace emf::fw::virtual_device {

/// One TUM folder, parsed. Depth images are served at the timestamps of depth.txt; each depth
/// frame is paired with the colour image of nearest timestamp.
struct TumFolder {
  std::string dir;
  std::vector<double> depth_timestamps_s;
  std::vector<std::string> depth_files;  // absolute paths
  std::vector<double> rgb_timestamps_s;
  std::vector<std::string> rgb_files;  // absolute paths
  std::vector<int> rgb_for_depth;      // index into rgb_files per depth frame, -1 = none
  /// Pinhole intrinsics of the depth camera, pixels (calibration.txt `fx fy cx cy [w h]`, scaled
  /// to the depth images' size; a folder without it is refused).
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int depth_width = 0, depth_height = 0;
  int color_width = 0, color_height = 0;
  /// uint16 depth units per metre (the `depth scale N` note in depth.txt's header, else TUM's
  /// 5000, or the `depth_scale` URI parameter).
  double depth_scale = 5000.0;
  /// Nominal frame rate from the median depth timestamp step, frames per second.
  int fps = 30;

  /// Parses the folder and reads the first depth and colour images to learn their sizes.
  /// `depth_scale_override` > 0 replaces the scale found in depth.txt. Returns false and sets
  /// *error (naming the file and line) on failure.
  static bool load(const std::string& dir, double depth_scale_override, TumFolder* out,
                   std::string* error);
};

/// Reads a 16-bit single-channel PNG into `pixels` (row-major, width*height values, exactly as
/// stored). Returns false and sets *error otherwise.
bool readDepthPng(const std::string& path, std::vector<uint16_t>* pixels, int* width, int* height,
                  std::string* error);

/// Reads a JPEG or PNG colour image as packed RGB888 (row-major, 3 bytes per pixel).
bool readColorRgb(const std::string& path, std::vector<uint8_t>* rgb, int* width, int* height,
                  std::string* error);

}  // namespace emf::fw::virtual_device
