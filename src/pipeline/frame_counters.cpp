#include "pipeline/frame_counters.h"

#include "common/error.h"
#include "pipeline/stage_timer.h"

namespace emf::pipeline {

FrameCounters::FrameCounters(std::vector<std::string> names, size_t reserve_frames) {
  for (const auto& n : names) {
    current_[n] = 0;
    samples_[n].reserve(reserve_frames);
  }
}

void FrameCounters::add(const std::string& name, double value) {
  auto it = current_.find(name);
  if (it == current_.end()) throw InvalidArgument("FrameCounters: unknown counter '" + name + "'");
  it->second += value;
}

void FrameCounters::endFrame() {
  for (auto& [name, value] : current_) {
    samples_[name].push_back(value);
    value = 0;
  }
}

std::map<std::string, CountSummary> FrameCounters::summary() const {
  std::map<std::string, CountSummary> out;
  for (const auto& [name, samples] : samples_) {
    const TimingSummary t = summarize(samples);  // the same percentiles as the stage times
    out[name] = {t.median_ms, t.p90_ms, t.mean_ms, t.max_ms, t.count};
  }
  return out;
}

const std::vector<double>& FrameCounters::samples(const std::string& name) const {
  auto it = samples_.find(name);
  if (it == samples_.end()) throw InvalidArgument("FrameCounters: unknown counter '" + name + "'");
  return it->second;
}

}  // namespace emf::pipeline
