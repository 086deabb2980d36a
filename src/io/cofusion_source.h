// The Co-Fusion synthetic dataset folder reader (`cofusion:<dir>`):
//   Color####.png          colour (in the folder or in colour/)
//   Depth####.exr          float depth in metres (in the folder, or depth_noise/, or
//                          depth_original/ — the first that has files); channel 0 is used for
//                          multi-channel EXR; <= 0, non-finite or >= 1000 m is invalid
//   calibration.txt        `fx fy cx cy [width height]` (or fx/fy/cx/cy from config/query)
//   masks_id/              optional ground-truth instance ids, *####.png (8- or 16-bit, one
//                          channel, 0 = background) -> Frame::instance_ids
// Frames are ordered by number; timestamps are (number - first number) / fps (query `fps`,
// default 30 Hz), so a gap in the numbering stays a gap in time (with a warning). Two files with
// the same number (Depth3.exr, Depth0003.exr) are an error.
// EXR needs OpenCV's EXR codec: the reader sets OPENCV_IO_ENABLE_OPENEXR=1 before reading.
#pragma once

#include <string>
#include <vector>

#include "core/frame_source.h"

namespace emf::io {

class CoFusionSource : public core::FrameSource {
 public:
  /// Indexes the folder and reads the first depth image (for the size). Throws IoError naming
  /// the file for a missing colour/depth partner, unreadable EXR, or missing intrinsics.
  CoFusionSource(const std::string& dir, const core::SourceOptions& options, double fps = 30.0);

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  bool next(core::Frame& frame) override;
  int64_t size() const override { return static_cast<int64_t>(frames_.size()); }
  std::string describe() const override;

 private:
  struct Entry {
    long number;
    std::string color, depth, mask;  // full paths; color/mask may be empty
  };
  cv::Mat readDepth(const std::string& path) const;

  std::string dir_;
  double fps_;
  std::vector<Entry> frames_;
  core::Intrinsics intrinsics_;
  cv::Size depth_size_;
  cv::Size color_size_;
  size_t cursor_ = 0;
};

}  // namespace emf::io
