// Depth image conversions and reading shared by the dataset readers and writers.
// emf's in-memory depth: CV_32F metres, NaN = invalid. On disk: uint16 "units" with a scale in
// units per metre (TUM 5000, 7-Scenes and KLG 1000), 0 = invalid.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace emf::io {

/// CV_16UC1 units -> CV_32F metres (v / units_per_metre), 0 -> NaN.
cv::Mat depthFromUnits(const cv::Mat& depth_units, double units_per_metre);

/// CV_32F metres -> CV_16UC1 units (rounded to nearest). NaN, non-positive values and values
/// that do not fit in 16 bits become 0 (invalid). depthFromUnits(depthToUnits(d)) == d
/// bit-exactly when d came from depthFromUnits with the same scale.
cv::Mat depthToUnits(const cv::Mat& depth_m, double units_per_metre);

/// A warning when the valid depth of `depth_units` read at `units_per_metre` looks like the wrong
/// scale, empty when it looks plausible (or fewer than 1 % of the pixels are valid):
/// - 95 % of the valid pixels closer than 1 m at a scale other than 1000: the typical picture of
///   millimetre images (7-Scenes, OpenNI recordings) read at TUM's 5000;
/// - half of them farther than 10 m at a scale other than 5000: TUM-scaled images read as
///   millimetres.
/// The text names the depth found and the URI key to set (`?depth_scale=`).
std::string depthScaleWarning(const cv::Mat& depth_units, double units_per_metre);

/// Reads an image file and decodes it with OpenCV (`flags` as cv::imread's). A file that cannot
/// be read is named with the system's reason (does not exist, permission denied, a folder);
/// one that cannot be decoded returns an empty cv::Mat, for the caller's message. Throws
/// IoError "<context>: cannot read <what> '<path>': <reason>" (context may be empty).
cv::Mat readImageFile(const std::string& path, int flags, const std::string& what,
                      const std::string& context);

/// Reads a 16-bit single-channel depth PNG. Throws IoError starting with `context` (e.g.
/// "depth.txt:12") and naming `path` when the file is missing/undecodable or not 16-bit
/// single-channel.
cv::Mat readDepthUnits(const std::string& path, const std::string& context);

/// Reads a colour image as CV_8UC3 BGR. Throws IoError naming `context` and `path`.
cv::Mat readColor(const std::string& path, const std::string& context);

/// OpenCV's EXR codec is disabled unless OPENCV_IO_ENABLE_OPENEXR is set before its first use;
/// this sets it (keeping a value the user set). Call before the first EXR imread/imwrite.
void enableOpenExr();

/// Human-readable OpenCV type, e.g. "8-bit 3-channel".
std::string describeMatType(int type);

}  // namespace emf::io
