// The progress line of long runs: frames done, frames/s and ETA, redrawn in place on a
// terminal (stderr) at most every 0.25 s; silent when stderr is not a terminal.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace emf::pipeline {

class Progress {
 public:
  /// `total` frames (-1 = unknown, e.g. a live sensor). `force` prints even without a terminal.
  explicit Progress(int64_t total, bool force = false);
  /// Called after each frame; `note` is appended (e.g. "lost 2").
  void update(int64_t done, const std::string& note = "");
  /// Ends the line.
  void finish();
  /// The text of the line for `done` frames after `elapsed_s` seconds (exposed for tests).
  static std::string format(int64_t done, int64_t total, double elapsed_s, const std::string& note);

 private:
  int64_t total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace emf::pipeline
