// Per-frame work counters of the pipeline (LM iterations, integrated blocks), summarised like
// the stage times. Unlike times they do not depend on how busy the machine is, so they show
// whether a change did more or less work when the wall clock cannot tell.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace emf::pipeline {

struct CountSummary {
  double median = 0, p90 = 0, mean = 0, max = 0;
  int count = 0;
};

class FrameCounters {
 public:
  /// The counters' names; `reserve_frames` samples are preallocated per counter.
  FrameCounters(std::vector<std::string> names, size_t reserve_frames);

  /// Adds `value` to counter `name` for the current frame (several calls accumulate).
  void add(const std::string& name, double value);
  /// Closes the current frame: every counter's sum (0 if untouched) becomes one sample.
  void endFrame();

  /// Median / p90 / mean / max per counter over the frames closed so far.
  std::map<std::string, CountSummary> summary() const;
  /// Samples of one counter, one per frame.
  const std::vector<double>& samples(const std::string& name) const;

 private:
  std::map<std::string, double> current_;
  std::map<std::string, std::vector<double>> samples_;
};

}  // namespace emf::pipeline
