#include "runtime/runtime.h"

#include <chrono>
#include <cstdio>

#include "common/error.h"
#include "common/log.h"
#include "firmware_host/reconnecting_source.h"
#include "firmware_host/sensor_error.h"

namespace emf::runtime {
namespace {

/// Poll interval of the SLAM thread's ring wait: bounds how long stop() waits for it.
constexpr double kSlamWaitS = 0.05;

/// Detections kept beside the ring beyond its capacity (older ones belong to dropped frames).
constexpr size_t kExtraDetectionEntries = 4;

}  // namespace

int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

const char* runtimeStateName(RuntimeState state) {
  switch (state) {
    case RuntimeState::kCreated:
      return "created";
    case RuntimeState::kRunning:
      return "running";
    case RuntimeState::kSensorError:
      return "sensor_error";
    case RuntimeState::kEnded:
      return "ended";
    case RuntimeState::kFailed:
      return "failed";
    case RuntimeState::kStopped:
      return "stopped";
  }
  return "unknown";
}

PoolCounters SlamProcessor::pool() const {
  const map::PoolStats s = slam_.pool().stats();
  PoolCounters p;
  p.blocks_total = s.capacity_slots;
  p.blocks_used = s.used_slots;
  p.blocks_dropped = s.dropped_blocks;
  p.bytes = static_cast<int64_t>(s.pool_bytes);
  return p;
}

Runtime::Runtime(std::unique_ptr<core::FrameSource> source, FrameProcessor& processor,
                 const pipeline::RuntimeOptions& options, Callback callback)
    : source_(std::move(source)),
      processor_(processor),
      options_(options),
      callback_(std::move(callback)) {
  if (!source_) throw InvalidArgument("runtime: no frame source");
  const fw::RingPolicy policy = options_.ring_policy;
  if (options_.result_queue < 1) {
    throw ConfigError("runtime.result_queue is " + std::to_string(options_.result_queue) +
                      ": must be at least 1");
  }
  reconnecting_ = dynamic_cast<fw::ReconnectingSource*>(source_.get()) != nullptr;
  source_description_ = source_->describe();
  intrinsics_ = source_->intrinsics();
  has_first_ = source_->next(first_);
  if (!has_first_) capture_done_.store(true);  // nothing will ever come

  fw::FrameRingOptions ring;
  ring.capacity = options_.ring_slots;
  ring.policy = policy;
  if (has_first_ && !first_.depth.empty()) {
    ring.depth_width = first_.depth.cols;
    ring.depth_height = first_.depth.rows;
  } else {
    ring.depth_width = intrinsics_.width > 0 ? intrinsics_.width : 1;
    ring.depth_height = intrinsics_.height > 0 ? intrinsics_.height : 1;
  }
  if (intrinsics_.valid() &&
      (ring.depth_width != intrinsics_.width || ring.depth_height != intrinsics_.height)) {
    throw IoError("runtime: source " + source_description_ + ": frame " +
                  std::to_string(first_.index) + " has a " + std::to_string(ring.depth_width) +
                  "x" + std::to_string(ring.depth_height) +
                  " depth image but the source's intrinsics are " +
                  std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height));
  }
  ring.depth_type = CV_32FC1;
  if (has_first_ && !first_.color.empty() && first_.color.type() == CV_8UC3) {
    ring.color_width = first_.color.cols;
    ring.color_height = first_.color.rows;
  } else {
    ring.color_width = ring.color_height = 0;
  }
  ring_ = std::make_unique<fw::FrameRing>(ring);
}

Runtime::~Runtime() {
  try {
    stop();
  } catch (...) {
    // stop() only joins; nothing to report from a destructor.
  }
  // stop() set kStopped and woke the pollers; the members must outlive their way out of poll().
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return pollers_ == 0; });
}

void Runtime::start() {
  const std::lock_guard<std::mutex> control(control_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  if (stop_called_) {
    throw StateError(
        "runtime: start() after stop(): a stopped runtime cannot be restarted; "
        "create a new one");
  }
  if (started_) return;
  started_ = true;
  state_ = RuntimeState::kRunning;
  capture_thread_ = std::thread([this] { captureLoop(); });
  slam_thread_ = std::thread([this] { slamLoop(); });
}

void Runtime::stop() {
  const std::lock_guard<std::mutex> control(control_mutex_);
  stop_called_ = true;
  stop_requested_.store(true, std::memory_order_release);
  ring_->stop();
  if (capture_thread_.joinable()) capture_thread_.join();
  if (slam_thread_.joinable()) slam_thread_.join();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (state_ == RuntimeState::kCreated || state_ == RuntimeState::kRunning) {
      state_ = RuntimeState::kStopped;
    }
  }
  cv_.notify_all();
}

void Runtime::setState(RuntimeState state) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    state_ = state;
  }
  cv_.notify_all();
}

void Runtime::fail(std::exception_ptr error, bool now) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!failure_) failure_ = error;
    if (now) state_ = RuntimeState::kFailed;
  }
  cv_.notify_all();
}

bool Runtime::pushFrame(core::Frame& frame) {
  const fw::FrameRingOptions& o = ring_->options();
  if (frame.depth.cols != o.depth_width || frame.depth.rows != o.depth_height ||
      frame.depth.type() != CV_32FC1) {
    throw IoError("runtime: source " + source_description_ + ": frame " +
                  std::to_string(frame.index) + " has a " + std::to_string(frame.depth.cols) + "x" +
                  std::to_string(frame.depth.rows) + " depth image, expected " +
                  std::to_string(o.depth_width) + "x" + std::to_string(o.depth_height) +
                  " float metres like the first frame");
  }
  // The ring copies the images; a colour image of another size than the first frame's (or a
  // ring without colour) travels without colour.
  core::Frame view;
  view.index = frame.index;
  view.timestamp = frame.timestamp;
  view.rgb_timestamp = frame.rgb_timestamp;
  view.timestamp_text = frame.timestamp_text;  // names dataset files (detector plugins)
  view.depth = frame.depth;
  if (o.color_width > 0 && frame.color.type() == CV_8UC3 && frame.color.cols == o.color_width &&
      frame.color.rows == o.color_height) {
    view.color = frame.color;
  }
  if (frame.detections) {
    std::lock_guard<std::mutex> lock(detections_mutex_);
    detections_.emplace_back(frame.index, std::move(*frame.detections));
    frame.detections.reset();
    while (detections_.size() > static_cast<size_t>(ring_->capacity()) + kExtraDetectionEntries) {
      detections_.pop_front();
    }
  }
  fw::RingStatus s = ring_->push(view);
  while (s == fw::RingStatus::kTimeout) {  // block policy: the SLAM thread is behind
    if (stop_requested_.load(std::memory_order_acquire)) return false;
    s = ring_->commit();
  }
  return s == fw::RingStatus::kOk;
}

void Runtime::captureLoop() {
  try {
    if (has_first_) {
      has_first_ = false;
      if (!pushFrame(first_)) {
        capture_done_.store(true, std::memory_order_release);
        return;
      }
      first_ = core::Frame();
    }
    core::Frame frame;
    while (!capture_done_.load(std::memory_order_relaxed) &&
           !stop_requested_.load(std::memory_order_acquire)) {
      bool got = false;
      try {
        got = source_->next(frame);
      } catch (const fw::SensorDisconnected& e) {
        if (!reconnecting_) throw;
        {
          std::lock_guard<std::mutex> lock(mutex_);
          if (!sensor_down_) logWarning("runtime: ", e.what());
          sensor_down_ = true;
          sensor_error_ = e.what();
          ++counters_.sensor_errors;
        }
        cv_.notify_all();
        continue;  // the ReconnectingSource retries (bounded) on the next call
      }
      if (!got) break;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (sensor_down_) logInfo("runtime: sensor ", source_description_, " is back");
        sensor_down_ = false;
        counters_.source_dropped = source_->droppedFrames();
      }
      if (!pushFrame(frame)) break;
    }
  } catch (...) {
    // The SLAM thread still processes the frames in the ring, then ends in kFailed.
    fail(std::current_exception(), false);
  }
  capture_done_.store(true, std::memory_order_release);
}

void Runtime::slamLoop() {
  bool holding = false;
  try {
    while (!stop_requested_.load(std::memory_order_acquire)) {
      const fw::FrameSlot* slot = nullptr;
      fw::RingStatus s = ring_->acquire(&slot, kSlamWaitS);
      if (s == fw::RingStatus::kStopped) break;
      if (s == fw::RingStatus::kTimeout) {
        if (!capture_done_.load(std::memory_order_acquire)) continue;
        // The capture thread published its last frame before setting capture_done_: one more
        // look drains the ring.
        s = ring_->acquire(&slot, 0.0);
        if (s != fw::RingStatus::kOk) {
          std::lock_guard<std::mutex> lock(mutex_);
          if (state_ == RuntimeState::kRunning) {
            state_ = failure_ ? RuntimeState::kFailed : RuntimeState::kEnded;
          }
          break;
        }
      }
      holding = true;
      core::Frame frame;
      frame.index = slot->source_index;
      frame.timestamp = slot->timestamp_s;
      frame.rgb_timestamp = slot->color_timestamp_s;
      if (slot->timestamp_text[0] != '\0') {
        frame.timestamp_text = slot->timestamp_text;
      } else {
        char stamp[32];
        std::snprintf(stamp, sizeof(stamp), "%.6f", slot->timestamp_s);
        frame.timestamp_text = stamp;
      }
      frame.depth = slot->depth;  // shares the slot's pixels while the slot is held
      if (slot->has_color) frame.color = slot->color;
      {
        std::lock_guard<std::mutex> lock(detections_mutex_);
        while (!detections_.empty() && detections_.front().first < frame.index) {
          detections_.pop_front();
        }
        if (!detections_.empty() && detections_.front().first == frame.index) {
          frame.detections = std::move(detections_.front().second);
          detections_.pop_front();
        }
      }
      RuntimeResult result;
      result.source_index = frame.index;
      result.sequence = slot->sequence;
      result.timestamp = frame.timestamp;
      result.commit_time_ns = slot->commit_time_ns;

      const int64_t t0 = steadyNowNs();
      pipeline::FrameOutcome outcome = processor_.process(frame);
      const int64_t t1 = steadyNowNs();
      frame = core::Frame();
      ring_->release();
      holding = false;

      result.T_world_camera = outcome.T_world_camera;
      result.lost = outcome.lost;
      result.objects = std::move(outcome.objects);
      result.processing_ms = static_cast<double>(t1 - t0) * 1e-6;
      const PoolCounters pool = processor_.pool();
      const fw::FrameRingStats ring = ring_->stats();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        result.frame_index = counters_.processed;
        ++counters_.processed;
        if (result.lost) ++counters_.lost;
        counters_.pool = pool;
        counters_.produced = static_cast<int64_t>(ring.produced);
        counters_.dropped = static_cast<int64_t>(ring.dropped);
        result.counters = counters_;
      }
      result.result_time_ns = steadyNowNs();
      result.latency_ms = static_cast<double>(result.result_time_ns - result.commit_time_ns) * 1e-6;
      if (callback_) callback_(result);
      {
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.push_back(std::move(result));
        while (queue_.size() > static_cast<size_t>(options_.result_queue)) {
          queue_.pop_front();
          ++counters_.results_dropped;
        }
      }
      cv_.notify_all();
    }
  } catch (...) {
    if (holding) ring_->release();
    fail(std::current_exception(), true);
    // Wake and end the capture thread too (a block push may be waiting for space).
    stop_requested_.store(true, std::memory_order_release);
    ring_->stop();
  }
  cv_.notify_all();
}

PollStatus Runtime::poll(double timeout_s, RuntimeResult* result) {
  if (!result) throw InvalidArgument("runtime: poll() needs a result to fill");
  const auto deadline =
      std::chrono::steady_clock::now() +
      std::chrono::nanoseconds(static_cast<int64_t>(std::max(0.0, timeout_s) * 1e9));
  std::unique_lock<std::mutex> lock(mutex_);
  if (state_ == RuntimeState::kCreated) {
    throw StateError("runtime: poll() before start(): start the runtime first");
  }
  // Counted while inside (under mutex_ on both ends), so the destructor can wait for us.
  struct Inside {
    Runtime& rt;
    explicit Inside(Runtime& r) : rt(r) { ++rt.pollers_; }
    ~Inside() {
      if (--rt.pollers_ == 0) rt.cv_.notify_all();
    }
  } inside(*this);
  const bool down_at_entry = sensor_down_;
  while (true) {
    if (!queue_.empty()) {
      *result = std::move(queue_.front());
      queue_.pop_front();
      return PollStatus::kResult;
    }
    switch (state_) {
      case RuntimeState::kEnded:
        return PollStatus::kEndOfStream;
      case RuntimeState::kFailed:
        return PollStatus::kFailed;
      case RuntimeState::kStopped:
        return PollStatus::kStopped;
      default:
        break;
    }
    // A disconnection during the wait ends it at once; an ongoing one after the timeout.
    if (sensor_down_ && !down_at_entry) return PollStatus::kSensorError;
    if (cv_.wait_until(lock, deadline) == std::cv_status::timeout && queue_.empty() &&
        (state_ == RuntimeState::kCreated || state_ == RuntimeState::kRunning)) {
      return sensor_down_ ? PollStatus::kSensorError : PollStatus::kTimeout;
    }
  }
}

RuntimeState Runtime::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (state_ == RuntimeState::kRunning && sensor_down_) return RuntimeState::kSensorError;
  return state_;
}

RuntimeCounters Runtime::counters() const {
  const fw::FrameRingStats ring = ring_->stats();
  std::lock_guard<std::mutex> lock(mutex_);
  RuntimeCounters c = counters_;
  c.produced = static_cast<int64_t>(ring.produced);
  c.dropped = static_cast<int64_t>(ring.dropped);
  return c;
}

std::string Runtime::sensorError() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return sensor_error_;
}

std::exception_ptr Runtime::failure() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return failure_;
}

}  // namespace emf::runtime
