// The KLG log of Kintinuous/ElasticFusion (`klg:<file>`), little-endian:
//   int32 frame_count
//   per frame: int64 timestamp (microseconds), int32 depth_size, int32 image_size,
//              depth_size bytes: zlib-compressed uint16 depth in millimetres (row-major; a
//                                 block of exactly width*height*2 bytes is raw, uncompressed),
//              image_size bytes: JPEG colour (0 = no colour; exactly width*height*3 = raw RGB)
// The format stores neither intrinsics nor the image size: intrinsics come from the
// configuration or the URI (?fx=..&fy=..&cx=..&cy=..), the size from ?width=&height=
// (default 640x480, the size Kintinuous/ElasticFusion assume). The JPEG is a standard JPEG
// (decodes to the right colours in any viewer).
#pragma once

#include <cstdint>
#include <fstream>
#include <memory>
#include <string>

#include "core/frame_source.h"
#include "io/atomic_output.h"

namespace emf::io {

/// KLG depth units per metre (millimetres).
constexpr double kKlgDepthScale = 1000.0;

class KlgSource : public core::FrameSource {
 public:
  /// Opens `path` and reads the header. `options` must carry fx, fy, cx, cy (IoError otherwise);
  /// `size` is the depth image size; `depth_scale` the depth units per metre.
  KlgSource(const std::string& path, const core::SourceOptions& options, cv::Size size = {640, 480},
            double depth_scale = kKlgDepthScale);

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  /// Throws IoError naming the file, frame and byte offset for a truncated or corrupt frame.
  bool next(core::Frame& frame) override;
  int64_t size() const override { return frames_to_read_; }
  std::string describe() const override;

 private:
  void readExact(void* dst, size_t bytes, int64_t frame, const char* what);
  /// Complete frames in the file, found by walking the frame headers from byte 4 (stops at the
  /// first header that is incomplete, invalid or runs past the end).
  int64_t countCompleteFrames();

  std::string path_;
  std::ifstream in_;
  uint64_t file_size_ = 0;
  uint64_t offset_ = 0;
  int32_t frame_count_ = 0;
  int64_t frames_to_read_ = 0;
  int64_t cursor_ = 0;
  int64_t last_timestamp_us_ = 0;
  cv::Size size_;
  double depth_scale_;
  core::Intrinsics intrinsics_;
};

/// Writes a KLG log atomically: frames go to a temporary file, close() patches the frame count
/// and renames it to `path`. Without close() (e.g. an exception) nothing appears at `path`.
class KlgWriter {
 public:
  /// `depth_scale`: depth units per metre written (1000 = mm, what readers expect);
  /// `jpeg_quality` 0..100.
  explicit KlgWriter(const std::string& path, double depth_scale = kKlgDepthScale,
                     int jpeg_quality = 90);

  /// Appends a frame: depth CV_32F metres (NaN/non-positive/over 65.535 m at 1000 units per
  /// metre become 0 = invalid, quantised to 1/depth_scale m), colour CV_8UC3 BGR or empty.
  /// Throws InvalidArgument for a wrong type, a size different from the first frame, or a
  /// timestamp not after the previous one; IoError on write errors.
  void write(const core::Frame& frame);
  /// Patches the frame count and moves the file into place. Throws IoError.
  void close();
  int64_t framesWritten() const { return frames_; }

 private:
  std::unique_ptr<AtomicOutputFile> out_;
  double depth_scale_;
  int jpeg_quality_;
  int64_t frames_ = 0;
  int64_t last_timestamp_us_ = 0;
  cv::Size size_;
};

}  // namespace emf::io
