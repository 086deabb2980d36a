// Per-stage wall-clock timing of the per-frame pipeline: ms per frame per stage, summarised as
// median and 90th percentile for the run summary and benchmarks. Storage is reserved up front
// so timing never allocates in the per-frame path.
#pragma once

#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace emf::pipeline {

struct TimingSummary {
  double median_ms = 0, p90_ms = 0, p99_ms = 0, mean_ms = 0, max_ms = 0;
  int count = 0;
};

/// Median / p90 / p99 / mean / max of a list of samples (nearest-rank percentiles).
TimingSummary summarize(std::vector<double> samples_ms);

class StageTimer {
 public:
  /// `stages` in pipeline order; `reserve_frames` samples are preallocated per stage.
  StageTimer(std::vector<std::string> stages, size_t reserve_frames);

  /// Adds `ms` to stage `name` for the current frame (several calls accumulate).
  void add(const std::string& name, double ms);
  /// Closes the current frame: every stage's accumulated time (0 if untouched) becomes one
  /// sample, and "total" gets their sum.
  void endFrame();

  /// Summary per stage, plus "total".
  std::map<std::string, TimingSummary> summary() const;
  const std::vector<std::string>& stages() const { return stages_; }
  /// Samples of one stage (ms per frame).
  const std::vector<double>& samples(const std::string& name) const;

 private:
  std::vector<std::string> stages_;
  std::map<std::string, double> current_;
  std::map<std::string, std::vector<double>> samples_;
};

/// RAII: adds the elapsed time of its scope to a stage.
class ScopedStage {
 public:
  ScopedStage(StageTimer& timer, const char* name)
      : timer_(timer), name_(name), start_(std::chrono::steady_clock::now()) {}
  ~ScopedStage() {
    timer_.add(name_,
               std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_)
                   .count());
  }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageTimer& timer_;
  const char* name_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace emf::pipeline
