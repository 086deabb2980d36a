// Atomic file output: every file is written to a temporary file in the same folder and renamed
// over the destination, so a reader (or a crash) never sees a half-written file. (Not fsync'ed:
// atomic with respect to other processes, not durable across a power loss.)
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace emf::io {

/// Writes `size` bytes to `path` atomically. Throws IoError naming the path and the system
/// error (the temporary file is removed).
void writeFileAtomic(const std::string& path, const void* data, size_t size);

/// Writes text to `path` atomically.
void writeTextAtomic(const std::string& path, const std::string& text);

/// Encodes `image` with OpenCV (format from the extension, e.g. .png) and writes it atomically.
/// Throws IoError if the image cannot be encoded in that format.
void writeImageAtomic(const std::string& path, const cv::Mat& image,
                      const std::vector<int>& params = {});

}  // namespace emf::io
