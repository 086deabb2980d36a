// A detector plugin run in a child process (detector.isolation: process): emf_detector_host
// loads it there, frames go in and detections come back through shared memory
// (pipeline/detector_ipc.h). A crash, an abort or a call that passes the deadline ends only the
// child: the call returns a DetectorOutput with the error (the SLAM goes on without detections),
// and the child is started again on a later call after a back-off that doubles from
// kFirstRestartS up to kMaxRestartS while it keeps failing.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <memory>
#include <string>

#include "core/frame.h"
#include "pipeline/detector_plugin.h"

namespace emf::pipeline {

/// Counters of an isolated detector (run.json "detector", C API emf_stats).
struct IsolationCounters {
  int64_t crashes = 0;   // the child died (signal or exit) during a call
  int64_t timeouts = 0;  // a call passed the deadline: the child was killed
  int64_t restarts = 0;  // children started after the first
};

class IsolatedDetector {
 public:
  /// Back-off before the first restart; doubles per failed restart up to kMaxRestartS.
  static constexpr double kFirstRestartS = 0.5;
  static constexpr double kMaxRestartS = 30.0;

  /// Starts the host (`host_path`) on the plugin at `plugin_path` (resolved) and waits for it to
  /// load the plugin (up to `load_timeout_s`). Throws PluginError with the plugin's own load
  /// error, or naming the host when it cannot be started. The host, and every thread it starts,
  /// runs at niceness `nice` (0-19; 0 = the caller's).
  IsolatedDetector(std::string host_path, std::string plugin_path, std::string config,
                   std::string source_uri, const core::Intrinsics& intrinsics, double deadline_s,
                   double load_timeout_s, int nice = 0);
  ~IsolatedDetector();
  IsolatedDetector(const IsolatedDetector&) = delete;
  IsolatedDetector& operator=(const IsolatedDetector&) = delete;

  /// Runs the plugin in the child on `frame`. Never throws for the child's faults: a crash, a
  /// timeout or a child that is down (restart pending) give an output with `error` set.
  DetectorOutput detect(const core::Frame& frame, const cv::Mat* background_association = nullptr,
                        const cv::Mat* residual = nullptr);

  const std::string& name() const { return name_; }
  bool newObjectsOnly() const { return new_objects_only_; }
  bool readsFeedback() const { return reads_feedback_; }
  IsolationCounters counters() const { return counters_; }
  /// The child's pid (-1 while it is down).
  pid_t childPid() const { return pid_; }

 private:
  using Clock = std::chrono::steady_clock;
  // Starts the child and waits for kReady. Returns "" or what went wrong (the plugin's load
  // error, or the host's start/death) and sets *status for PluginError.
  std::string spawn(double timeout_s, emf_status* status);
  // Kills (if needed) and reaps the child; returns how it ended ("SIGSEGV", "exit code 3").
  std::string reap(bool kill_first);
  void closeChannel();
  // Grows the segment to `bytes` (the child remaps on its next call). Throws IoError.
  void ensureSegment(uint64_t bytes);
  // Waits up to `timeout_s` for a message; false on timeout, EOF or error (`eof` says which).
  bool receive(double timeout_s, void* message, bool* eof);

  std::string host_path_, plugin_path_, config_, source_uri_;
  core::Intrinsics intrinsics_;
  double deadline_s_;
  std::string nice_;  // the host's niceness, as its argument
  std::string name_;
  bool new_objects_only_ = false, reads_feedback_ = true;

  pid_t pid_ = -1;
  int shm_fd_ = -1, socket_fd_ = -1;
  void* segment_ = nullptr;
  uint64_t segment_bytes_ = 0;
  int64_t seq_ = 0;

  IsolationCounters counters_;
  std::string down_reason_;  // why the child is down ("" = up)
  Clock::time_point restart_at_{};
  double backoff_s_ = kFirstRestartS;
};

/// The emf_detector_host executable that belongs to this emf: $EMF_DETECTOR_HOST when set, else
/// emf_detector_host in the first of modulePluginFolders() that has one. Throws PluginError
/// naming the folders looked in.
std::string detectorHostPath();

}  // namespace emf::pipeline
