// The runtime: emf owns the loop. A capture thread reads a FrameSource (dataset, synthetic world
// or live sensor) and pushes every frame into a fw::FrameRing (runtime.ring_slots,
// runtime.ring_policy); a SLAM thread takes frames out of the ring and runs a FrameProcessor
// (pipeline::SlamSystem in production) on them; each result is delivered to a callback (on the
// SLAM thread) and to a bounded queue read by poll().
//
// Documented behaviour:
//  - Results: one per processed frame, in frame order. The poll queue keeps the newest
//    runtime.result_queue results; when the poller is slower, the oldest queued result is
//    discarded and counted in RuntimeCounters::results_dropped (the callback still saw it).
//  - Latency (RuntimeResult::latency_ms): host steady clock from the moment the capture thread
//    committed the frame into the ring (FrameSlot::commit_time_ns, right after the source
//    returned it) to the moment its result is complete (after processing, before the callback
//    and the queue). It includes ring wait and processing; it does not include what happened
//    before the source returned the frame (sensor exposure, USB transfer, driver buffering): the
//    sensor clock of FrameSlot::timestamp_s is not comparable with the host clock.
//  - End of stream: when a recorded source is exhausted, the SLAM thread processes every frame
//    still in the ring, then the state becomes kEnded; poll() returns every queued result and
//    then kEndOfStream.
//  - Sensor failure: a live source wrapped in fw::ReconnectingSource that reports
//    SensorDisconnected puts the runtime into kSensorError (the capture thread keeps retrying,
//    bounded by the source's timeouts); poll() returns queued results first, then
//    kSensorError as soon as the sensor disconnects during its wait, or at its timeout while
//    the sensor is still away. When the sensor is back, frames flow again and the state
//    returns to kRunning. Any other error (unreadable file, SLAM failure,
//    a sensor failure of a source without reconnect) is fatal: both threads end, the state is
//    kFailed and poll() returns kFailed after the queued results (failure() holds the error;
//    after a source error the frames already in the ring are still processed first). An
//    exception thrown by the callback is such a fatal error.
//  - start() is idempotent while running; stop() is idempotent, wakes and joins both threads
//    and discards frames still in the ring; results already queued stay pollable. A runtime
//    cannot be restarted after stop() (StateError).
// Thread safety: start(), stop() and the destructor from one controlling thread; poll(),
// state(), counters(), sensorError() from any thread.
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "core/frame_source.h"
#include "firmware_host/frame_ring.h"
#include "pipeline/pipeline_options.h"
#include "pipeline/slam_system.h"

namespace emf::runtime {

/// Counters of the fixed voxel pool (all zero when the processor has none).
struct PoolCounters {
  int64_t blocks_total = 0;    // slots in the pool
  int64_t blocks_used = 0;     // slots in use
  int64_t blocks_dropped = 0;  // block allocations refused because the pool was full
  int64_t bytes = 0;           // bytes of the pool allocation
};

/// What the SLAM thread does with one frame: SlamSystem in production, fakes in thread tests.
class FrameProcessor {
 public:
  virtual ~FrameProcessor() = default;
  /// Processes one frame (depth CV_32F metres of the source's intrinsics' size). May throw; an
  /// exception ends the runtime in kFailed.
  virtual pipeline::FrameOutcome process(const core::Frame& frame) = 0;
  /// Pool counters after the last process() (called on the SLAM thread).
  virtual PoolCounters pool() const { return {}; }
};

/// FrameProcessor running a SlamSystem (borrowed; must outlive the runtime).
class SlamProcessor : public FrameProcessor {
 public:
  explicit SlamProcessor(pipeline::SlamSystem& slam) : slam_(slam) {}
  pipeline::FrameOutcome process(const core::Frame& frame) override { return slam_.process(frame); }
  PoolCounters pool() const override;

 private:
  pipeline::SlamSystem& slam_;
};

/// Frame-flow counters of a runtime. A consistent snapshot (taken under one lock); once both
/// threads have ended, produced == processed + dropped + discarded_at_stop.
struct RuntimeCounters {
  int64_t produced = 0;         // frames the capture thread published into the ring
  int64_t dropped = 0;          // frames the ring overwrote unread (drop_oldest)
  int64_t processed = 0;        // frames the SLAM thread processed (= results produced)
  int64_t lost = 0;             // processed frames whose camera tracking failed
  int64_t results_dropped = 0;  // results discarded from the full poll queue (never polled)
  int64_t sensor_errors = 0;    // SensorDisconnected reports of the source
  int64_t source_dropped = 0;   // frames the source dropped before the capture thread read them
  PoolCounters pool;            // after the last processed frame
};

/// The result of one processed frame.
struct RuntimeResult {
  int64_t frame_index = 0;   // 0-based count of results of this runtime
  int64_t source_index = 0;  // the source's frame index (core::Frame::index)
  int64_t sequence = 0;      // ring sequence number (a gap to the previous = dropped frames)
  double timestamp = 0;      // the frame's sensor timestamp, seconds (sensor clock)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // camera in the world
  bool lost = false;  // camera tracking failed: the frame was not integrated
  /// Objects alive after the frame plus those deleted in it (pipeline::FrameOutcome::objects).
  std::vector<pipeline::ObjectOutcome> objects;
  double processing_ms = 0;    // time in FrameProcessor::process
  int64_t commit_time_ns = 0;  // host steady clock when the frame entered the ring
  int64_t result_time_ns = 0;  // host steady clock when the result was complete
  double latency_ms = 0;       // (result_time_ns - commit_time_ns) / 1e6, see the file comment
  RuntimeCounters counters;    // snapshot right after this frame
};

enum class RuntimeState {
  kCreated,      // not started
  kRunning,      // threads running, frames flowing
  kSensorError,  // running, but the live sensor is disconnected (recoverable)
  kEnded,        // the recorded source is exhausted and every frame was processed
  kFailed,       // a fatal error ended both threads (failure())
  kStopped,      // stop() was called
};
const char* runtimeStateName(RuntimeState state);

/// What poll() returned.
enum class PollStatus {
  kResult,       // *result holds the next result
  kTimeout,      // nothing arrived within the timeout
  kEndOfStream,  // kEnded and every result was polled
  kSensorError,  // the sensor is disconnected and no result is queued (sensorError())
  kFailed,       // kFailed and every result was polled (failure())
  kStopped,      // stopped and every queued result was polled
};

class Runtime {
 public:
  using Callback = std::function<void(const RuntimeResult&)>;

  /// Sizes the ring from the source's intrinsics and its first frame (read here, so a source
  /// that cannot deliver fails at creation), does not start threads. `processor` is borrowed
  /// and must outlive the runtime; `callback` (may be empty) runs on the SLAM thread and must
  /// return quickly. Throws ConfigError for a bad ring policy, IoError from the source.
  Runtime(std::unique_ptr<core::FrameSource> source, FrameProcessor& processor,
          const pipeline::RuntimeOptions& options, Callback callback = {});
  /// Stops, joins, wakes every thread blocked in poll() (they return kStopped) and waits until
  /// they have left it.
  ~Runtime();
  Runtime(const Runtime&) = delete;
  Runtime& operator=(const Runtime&) = delete;

  /// Starts the capture and SLAM threads. No-op while running or after the end of the stream;
  /// throws StateError after stop().
  void start();
  /// Stops both threads and joins them. Idempotent, also when two threads call it at once;
  /// frames still in the ring are discarded.
  void stop();
  /// Waits up to timeout_s for the next result (see PollStatus). Any thread. Throws StateError
  /// before start() (nothing would ever arrive).
  PollStatus poll(double timeout_s, RuntimeResult* result);

  RuntimeState state() const;
  RuntimeCounters counters() const;
  /// Message of the current / last sensor disconnection ("" if none).
  std::string sensorError() const;
  /// The fatal error in kFailed (null otherwise).
  std::exception_ptr failure() const;
  const core::Intrinsics& intrinsics() const { return intrinsics_; }
  std::string describeSource() const { return source_description_; }
  fw::RingPolicy policy() const { return ring_->options().policy; }

 private:
  void captureLoop();
  void slamLoop();
  /// Records a fatal error; `now`: the state becomes kFailed at once (else when the SLAM thread
  /// has drained the ring).
  void fail(std::exception_ptr error, bool now);
  /// Pushes `frame` into the ring, retrying a full ring (block) until stop. False when stopped.
  bool pushFrame(core::Frame& frame);
  void setState(RuntimeState state);  // under mutex_, notifies pollers

  std::unique_ptr<core::FrameSource> source_;
  FrameProcessor& processor_;
  const pipeline::RuntimeOptions options_;
  Callback callback_;
  core::Intrinsics intrinsics_;
  std::string source_description_;
  bool reconnecting_ = false;  // the source is a fw::ReconnectingSource
  std::unique_ptr<fw::FrameRing> ring_;
  bool has_first_ = false;  // first_ was read at construction and not yet pushed
  core::Frame first_;

  // Detections travel beside the ring (slots carry images only): (source index, detections),
  // pushed by the capture thread before the frame's commit, taken by the SLAM thread.
  std::mutex detections_mutex_;
  std::deque<std::pair<int64_t, std::vector<core::Detection>>> detections_;

  std::mutex control_mutex_;  // serialises start() and stop() (and the joins in them)
  std::thread capture_thread_, slam_thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> capture_done_{false};  // the capture thread published its last frame
  bool started_ = false;                   // under control_mutex_
  bool stop_called_ = false;               // under control_mutex_: start() is refused

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable cv_;
  RuntimeState state_ = RuntimeState::kCreated;
  std::deque<RuntimeResult> queue_;
  RuntimeCounters counters_;
  std::string sensor_error_;
  bool sensor_down_ = false;
  std::exception_ptr failure_;
  int pollers_ = 0;  // threads inside poll(); the destructor waits for 0
};

/// Current host steady-clock time in nanoseconds (the clock of FrameSlot::commit_time_ns).
int64_t steadyNowNs();

}  // namespace emf::runtime
