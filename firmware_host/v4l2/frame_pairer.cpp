#include "firmware_host/v4l2/frame_pairer.h"

#include <cmath>

namespace emf::fw {

FramePairer::FramePairer(double max_dt_s, int max_pending_depth)
    : max_dt_s_(max_dt_s), max_pending_depth_(max_pending_depth < 1 ? 1 : max_pending_depth) {}

void FramePairer::addDepth(TimedImage image) {
  if (image.timestamp_s <= last_depth_t_) {
    ++stats_.out_of_order;
    return;
  }
  last_depth_t_ = image.timestamp_s;
  depth_.push_back(std::move(image));
  decide(false);
}

void FramePairer::addColor(TimedImage image) {
  if (image.timestamp_s <= last_color_t_) {
    ++stats_.out_of_order;
    return;
  }
  last_color_t_ = image.timestamp_s;
  color_.push_back(std::move(image));
  decide(false);
}

void FramePairer::flush() { decide(true); }

bool FramePairer::pop(PairedFrame* out) {
  if (ready_.empty()) return false;
  *out = std::move(ready_.front());
  ready_.pop_front();
  return true;
}

void FramePairer::decide(bool force_all) {
  while (!depth_.empty()) {
    const double t = depth_.front().timestamp_s;
    // Colour images too old for this (and, timestamps increasing, every later) depth image.
    while (!color_.empty() && color_.front().timestamp_s < t - max_dt_s_) {
      color_.pop_front();
      ++stats_.color_unused;
    }
    const bool colour_caught_up = last_color_t_ >= t;
    const bool stalled = static_cast<int>(depth_.size()) > max_pending_depth_;
    if (!colour_caught_up && !stalled && !force_all) return;
    // Nearest colour within the window (the deque is sorted by time).
    int best = -1;
    double best_dt = max_dt_s_;
    for (size_t i = 0; i < color_.size(); ++i) {
      const double dt = std::fabs(color_[i].timestamp_s - t);
      if (dt <= best_dt) {
        best_dt = dt;
        best = static_cast<int>(i);
      }
      if (color_[i].timestamp_s > t + max_dt_s_) break;
    }
    PairedFrame p;
    p.depth = std::move(depth_.front());
    depth_.pop_front();
    if (best >= 0) {
      // Colour images before the chosen one can no longer be the nearest for later depth.
      for (int i = 0; i < best; ++i) {
        color_.pop_front();
        ++stats_.color_unused;
      }
      p.color = std::move(color_.front());
      color_.pop_front();
      ++stats_.paired;
    } else {
      ++stats_.depth_alone;
    }
    ready_.push_back(std::move(p));
  }
}

}  // namespace emf::fw
