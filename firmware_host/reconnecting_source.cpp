#include "firmware_host/reconnecting_source.h"

#include <chrono>
#include <thread>

#include "common/log.h"
#include "firmware_host/sensor_error.h"

namespace emf::fw {

const char* sensorStateName(SensorState state) {
  switch (state) {
    case SensorState::kStreaming:
      return "streaming";
    case SensorState::kDisconnected:
      return "disconnected";
    case SensorState::kEnded:
      return "ended";
  }
  return "unknown";
}

ReconnectingSource::ReconnectingSource(Factory factory, std::string name,
                                       const ReconnectOptions& options)
    : factory_(std::move(factory)), name_(std::move(name)), options_(options) {
  inner_ = factory_();
  if (!inner_) throw IoError("sensor '" + name_ + "': the source factory returned nothing");
  intrinsics_ = inner_->intrinsics();
  inner_description_ = inner_->describe();
}

std::string ReconnectingSource::describe() const {
  return inner_description_ + " [hot-plug: " + sensorStateName(state()) + "]";
}

void ReconnectingSource::close() {
  if (inner_) inner_->close();
  inner_.reset();
}

bool ReconnectingSource::next(core::Frame& frame) {
  if (state() == SensorState::kEnded) return false;
  if (!inner_) {
    using Clock = std::chrono::steady_clock;
    const auto deadline =
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(options_.reconnect_wait_s));
    for (;;) {
      try {
        inner_ = factory_();
      } catch (const Error& e) {
        last_error_ = e.what();
        inner_.reset();
      }
      if (inner_) break;
      if (Clock::now() + std::chrono::duration_cast<Clock::duration>(
                             std::chrono::duration<double>(options_.retry_interval_s)) >
          deadline) {
        throw SensorDisconnected("sensor '" + name_ + "' is still disconnected (" + last_error_ +
                                 "): re-plug it; frames resume automatically");
      }
      std::this_thread::sleep_for(std::chrono::duration<double>(options_.retry_interval_s));
    }
    ++reconnects_;
    state_ = static_cast<int>(SensorState::kStreaming);
    logInfo("sensor '", name_, "' reconnected (", inner_->describe(), ")");
  }
  bool ok = false;
  try {
    ok = inner_->next(frame);
  } catch (const SensorDisconnected& e) {
    dropped_before_ += inner_->droppedFrames();
    inner_.reset();
    state_ = static_cast<int>(SensorState::kDisconnected);
    ++disconnects_;
    last_error_ = e.what();
    logWarning(last_error_);
    throw;
  }
  if (!ok) {
    state_ = static_cast<int>(SensorState::kEnded);
    return false;
  }
  frame.index = delivered_++;
  return true;
}

}  // namespace emf::fw
