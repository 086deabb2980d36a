// Hot-plug handling for live sensors: a FrameSource that wraps a sensor source and re-opens it
// after the sensor was unplugged.
//
// Documented behaviour (what an integrator sees):
//  - While the sensor streams, next() returns its frames (state kStreaming).
//  - When the sensor is unplugged or stalls, next() throws SensorDisconnected naming the device
//    and the state becomes kDisconnected. It never hangs: the wrapped source bounds its wait by
//    its frame timeout (openni2: timeout_s, v4l2: timeout_s).
//  - Each later next() tries to re-open the sensor for at most `reconnect_wait_s` (one attempt
//    every `retry_interval_s`); while that fails it throws SensorDisconnected again ("still
//    disconnected ... re-plug it"), so a capture loop keeps running and can report the state.
//  - Once the sensor is back, next() returns frames again (state kStreaming); frame indices
//    continue where they stopped; reconnects() counts the recoveries.
// Not thread-safe: one capture thread calls next(); state() may be read from any thread.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "core/frame_source.h"

namespace emf::fw {

enum class SensorState { kStreaming = 0, kDisconnected = 1, kEnded = 2 };
const char* sensorStateName(SensorState state);

struct ReconnectOptions {
  /// Pause between two re-open attempts, seconds.
  double retry_interval_s = 0.25;
  /// Longest a next() call spends re-opening before it reports the sensor as still missing, s.
  double reconnect_wait_s = 1.0;
};

class ReconnectingSource : public core::FrameSource {
 public:
  using Factory = std::function<std::unique_ptr<core::FrameSource>()>;

  /// Opens the sensor once through `factory` (errors propagate: a sensor that is missing at
  /// start-up is a configuration problem, not a hot-plug event).
  ReconnectingSource(Factory factory, std::string name, const ReconnectOptions& options = {});

  core::Intrinsics intrinsics() const override { return intrinsics_; }
  bool next(core::Frame& frame) override;
  int64_t size() const override { return -1; }
  bool isLive() const override { return true; }
  /// Frames dropped by every sensor connection so far.
  int64_t droppedFrames() const override {
    return dropped_before_ + (inner_ ? inner_->droppedFrames() : 0);
  }
  std::string describe() const override;
  void close() override;

  SensorState state() const { return static_cast<SensorState>(state_.load()); }
  /// The message of the last disconnection / failed re-open ("" while none happened).
  std::string lastError() const { return last_error_; }
  int disconnects() const { return disconnects_; }
  int reconnects() const { return reconnects_; }

 private:
  Factory factory_;
  std::string name_;
  ReconnectOptions options_;
  std::unique_ptr<core::FrameSource> inner_;
  core::Intrinsics intrinsics_;
  std::string inner_description_;
  std::atomic<int> state_{static_cast<int>(SensorState::kStreaming)};
  std::string last_error_;
  int disconnects_ = 0;
  int reconnects_ = 0;
  int64_t delivered_ = 0;
  int64_t dropped_before_ = 0;  // droppedFrames() of the connections that ended
};

}  // namespace emf::fw
