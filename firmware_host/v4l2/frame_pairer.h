// Pairs depth and colour images from two independent streams (two V4L2 nodes) by timestamp.
// Each depth image is matched with the colour image of nearest timestamp within max_dt_s; a
// depth image is emitted as soon as that decision cannot change any more:
//  - a colour image at or after its timestamp arrived (later ones are only farther away), or
//  - more than `max_pending_depth` depth images wait (the colour stream stalled): the oldest is
//    emitted without colour rather than delaying depth.
// Timestamps of each stream must increase; images that go back in time are dropped (counted).
// Not thread-safe (one capture thread feeds and pops).
#pragma once

#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>

namespace emf::fw {

struct TimedImage {
  double timestamp_s = 0;  // sensor / driver timestamp, seconds (same clock for both streams)
  int64_t sequence = 0;    // driver sequence number (for diagnostics)
  cv::Mat image;
};

struct PairedFrame {
  TimedImage depth;
  TimedImage color;  // color.image empty when no colour image matched
};

struct PairerStats {
  int64_t paired = 0;        // depth images emitted with colour
  int64_t depth_alone = 0;   // depth images emitted without colour
  int64_t color_unused = 0;  // colour images never paired
  int64_t out_of_order = 0;  // images dropped because their timestamp went backwards
};

class FramePairer {
 public:
  explicit FramePairer(double max_dt_s, int max_pending_depth = 3);

  void addDepth(TimedImage image);
  void addColor(TimedImage image);
  /// Takes the next decided pair (in depth order). Returns false when none is decided yet.
  bool pop(PairedFrame* out);
  /// Emits the remaining depth images with their best match now (end of stream).
  void flush();
  const PairerStats& stats() const { return stats_; }

 private:
  void decide(bool force_all);

  double max_dt_s_;
  int max_pending_depth_;
  std::deque<TimedImage> depth_;
  std::deque<TimedImage> color_;
  std::deque<PairedFrame> ready_;
  double last_depth_t_ = -1e300, last_color_t_ = -1e300;
  PairerStats stats_;
};

}  // namespace emf::fw
