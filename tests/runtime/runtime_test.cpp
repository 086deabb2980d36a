// The runtime's threads with fake sources and processors (fast, deterministic, no OpenCL), so
// the suite also runs under ThreadSanitizer (label threads): frame order and content through
// the ring, end of stream after the last result, drop_oldest counts, the bounded poll queue,
// stop/start rules, sensor unplug/replug through ReconnectingSource, fatal errors, detections.
#include "runtime/runtime.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <thread>

#include "common/error.h"
#include "firmware_host/reconnecting_source.h"
#include "firmware_host/sensor_error.h"

namespace emf::runtime {
namespace {

constexpr int kWidth = 16, kHeight = 12;
/// Longest any test waits for a state it expects (never reached when the code is right; no
/// timing is asserted).
constexpr double kPatienceS = 60.0;
/// Depth values encode the frame index exactly (small integers in float).
constexpr double kDepthOffsetM = 1.0;

core::Intrinsics intrinsics() {
  core::Intrinsics k;
  k.fx = k.fy = 20;
  k.cx = 7.5;
  k.cy = 5.5;
  k.width = kWidth;
  k.height = kHeight;
  return k;
}

/// Frame i: depth = kDepthOffsetM + i everywhere but pixel (1, 0) = i * 0.5 + 2, colour (i % 256);
/// detections (class "d<i>") on every `det_every`-th frame.
void makeFrame(int64_t i, core::Frame* f, int det_every) {
  f->index = i;
  f->timestamp = 100.0 + static_cast<double>(i) / 30.0;
  f->rgb_timestamp = f->timestamp;
  f->timestamp_text = i % 5 == 4 ? "" : "t" + std::to_string(i);  // "" = the source has none
  f->depth = cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(static_cast<float>(kDepthOffsetM + i)));
  f->depth.at<float>(0, 1) = static_cast<float>(i * 0.5 + 2.0);
  f->color = cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(static_cast<double>(i % 256), 1, 2));
  f->detections.reset();
  if (det_every > 0 && i % det_every == 0) {
    core::Detection d;
    d.id = 1;
    d.class_name = "d" + std::to_string(i);
    f->detections = std::vector<core::Detection>{d};
  }
}

/// A recorded (or, with `live`, endless paced) source of synthetic frames.
class FakeSource : public core::FrameSource {
 public:
  FakeSource(int64_t frames, int det_every = 0, double period_s = 0.0, int64_t throw_at = -1)
      : frames_(frames), det_every_(det_every), period_s_(period_s), throw_at_(throw_at) {}
  core::Intrinsics intrinsics() const override { return emf::runtime::intrinsics(); }
  /// Runs before frame i is produced (gates).
  std::function<void(int64_t)> before_next;
  bool next(core::Frame& frame) override {
    if (frames_ >= 0 && next_ >= frames_) return false;
    if (before_next) before_next(next_);
    if (next_ == throw_at_)
      throw IoError("fake source: frame " + std::to_string(next_) + " is corrupt");
    if (period_s_ > 0) std::this_thread::sleep_for(std::chrono::duration<double>(period_s_));
    makeFrame(next_++, &frame, det_every_);
    return true;
  }
  int64_t size() const override { return frames_; }
  std::string describe() const override { return "fake source"; }

 private:
  int64_t frames_;
  int det_every_;
  double period_s_;
  int64_t throw_at_;
  int64_t next_ = 0;
};

/// Checks each frame's content and turns it into an outcome: T_world_camera.x = the index read
/// back from the depth, y = the index read from pixel (1, 0), z = the colour's blue value;
/// detections become one object of that class.
class FakeProcessor : public FrameProcessor {
 public:
  std::function<void(const core::Frame&)> before;  // runs first (gates, sleeps, throws)
  bool check_timestamp_text = false;               // frames must carry makeFrame's timestamp text
  pipeline::FrameOutcome process(const core::Frame& frame) override {
    if (before) before(frame);
    if (check_timestamp_text) {
      // The source's timestamp text reaches the processor (detector plugins name files by it);
      // without one the runtime writes the timestamp with 6 decimals.
      char stamp[32];
      std::snprintf(stamp, sizeof(stamp), "%.6f", frame.timestamp);
      EXPECT_EQ(frame.timestamp_text,
                frame.index % 5 == 4 ? std::string(stamp) : "t" + std::to_string(frame.index));
    }
    pipeline::FrameOutcome o;
    o.index = processed_++;
    o.timestamp = frame.timestamp;
    o.T_world_camera.translation() = Eigen::Vector3d(
        frame.depth.at<float>(5, 5) - kDepthOffsetM, (frame.depth.at<float>(0, 1) - 2.0) / 0.5,
        frame.color.empty() ? -1.0 : frame.color.at<cv::Vec3b>(3, 3)[0]);
    o.lost = frame.index % 7 == 3;
    if (frame.detections) {
      pipeline::ObjectOutcome obj;
      obj.id = static_cast<int>(frame.index) + 1;
      obj.class_name = frame.detections->front().class_name;
      o.objects.push_back(obj);
    }
    return o;
  }
  PoolCounters pool() const override {
    PoolCounters p;
    p.blocks_total = 100;
    p.blocks_used = processed_;
    return p;
  }

 private:
  int64_t processed_ = 0;
};

pipeline::RuntimeOptions options(const char* policy, int slots, int queue) {
  pipeline::RuntimeOptions o;
  o.ring_policy = fw::parseRingPolicy(policy);
  o.ring_slots = slots;
  o.result_queue = queue;
  return o;
}

/// Polls until a non-result status; returns it and appends the results.
PollStatus drain(Runtime& rt, std::vector<RuntimeResult>* out) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
  while (std::chrono::steady_clock::now() < deadline) {
    RuntimeResult r;
    const PollStatus s = rt.poll(0.2, &r);
    if (s == PollStatus::kResult) {
      out->push_back(std::move(r));
    } else if (s != PollStatus::kTimeout) {
      return s;
    }
  }
  return PollStatus::kTimeout;
}

void expectFrameContent(const RuntimeResult& r) {
  const double i = static_cast<double>(r.source_index);
  EXPECT_EQ(r.T_world_camera.translation().x(), i) << "depth of frame " << r.source_index;
  EXPECT_EQ(r.T_world_camera.translation().y(), i) << "pixel (1, 0) of frame " << r.source_index;
  EXPECT_EQ(r.T_world_camera.translation().z(), static_cast<double>(r.source_index % 256));
  EXPECT_DOUBLE_EQ(r.timestamp, 100.0 + i / 30.0);
}

TEST(Runtime, BlockPolicyDeliversEveryFrameInOrderThenEndOfStream) {
  constexpr int kFrames = 300;
  FakeSource* src = new FakeSource(kFrames, 4);
  FakeProcessor proc;
  proc.check_timestamp_text = true;
  std::mutex m;
  std::vector<int64_t> callback_indices;
  Runtime rt(std::unique_ptr<core::FrameSource>(src), proc, options("block", 3, kFrames),
             [&](const RuntimeResult& r) {
               std::lock_guard<std::mutex> lock(m);
               callback_indices.push_back(r.source_index);
             });
  EXPECT_EQ(rt.state(), RuntimeState::kCreated);
  rt.start();
  rt.start();  // idempotent
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kEndOfStream);
  EXPECT_EQ(rt.state(), RuntimeState::kEnded);
  ASSERT_EQ(results.size(), static_cast<size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i) {
    const RuntimeResult& r = results[static_cast<size_t>(i)];
    EXPECT_EQ(r.frame_index, i);
    EXPECT_EQ(r.source_index, i);
    EXPECT_EQ(r.sequence, i);
    expectFrameContent(r);
    EXPECT_EQ(r.lost, i % 7 == 3);
    EXPECT_EQ(r.counters.processed, i + 1);
    EXPECT_EQ(r.counters.pool.blocks_used, i + 1);
    EXPECT_GE(r.result_time_ns, r.commit_time_ns);
    EXPECT_DOUBLE_EQ(r.latency_ms, static_cast<double>(r.result_time_ns - r.commit_time_ns) * 1e-6);
    // Detections travel beside the ring with their own frame.
    if (i % 4 == 0) {
      ASSERT_EQ(r.objects.size(), 1u) << "frame " << i;
      EXPECT_EQ(r.objects[0].class_name, "d" + std::to_string(i));
    } else {
      EXPECT_TRUE(r.objects.empty()) << "frame " << i;
    }
  }
  rt.stop();
  {
    std::lock_guard<std::mutex> lock(m);
    ASSERT_EQ(callback_indices.size(), static_cast<size_t>(kFrames));
    for (int i = 0; i < kFrames; ++i) EXPECT_EQ(callback_indices[static_cast<size_t>(i)], i);
  }
  const RuntimeCounters c = rt.counters();
  EXPECT_EQ(c.produced, kFrames);
  EXPECT_EQ(c.processed, kFrames);
  EXPECT_EQ(c.dropped, 0);
  EXPECT_EQ(c.results_dropped, 0);
  EXPECT_EQ(c.lost, (kFrames + 3) / 7);
  EXPECT_EQ(rt.state(), RuntimeState::kEnded) << "stop() keeps the end state";
  RuntimeResult r;
  EXPECT_EQ(rt.poll(0.0, &r), PollStatus::kEndOfStream);
}

/// Waits (bounded) until `done` holds; false when it never did.
template <typename F>
bool waitUntil(F&& done) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

// The source produces frame 1 only once the SLAM thread holds frame 0, and the SLAM thread holds
// frame 0 until the source has published everything: a ring of 2 keeps the newest 2 of the
// other frames, so exactly kFrames - 3 are dropped.
TEST(Runtime, DropOldestKeepsTheNewestFramesAndCountsTheRest) {
  constexpr int kFrames = 50;
  FakeProcessor proc;
  Runtime* rt_ptr = nullptr;
  std::atomic<bool> gate_ok{true};
  std::atomic<bool> holding_first{false};
  auto source = std::make_unique<FakeSource>(kFrames, 1);
  source->before_next = [&](int64_t i) {
    if (i == 1 && !waitUntil([&] { return holding_first.load(); })) gate_ok = false;
  };
  proc.before = [&](const core::Frame& f) {
    if (f.index != 0) return;
    holding_first = true;
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
    while (rt_ptr->counters().produced < kFrames) {
      if (std::chrono::steady_clock::now() > deadline) {
        gate_ok = false;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  };
  Runtime rt(std::move(source), proc, options("drop_oldest", 2, 100));
  rt_ptr = &rt;
  rt.start();
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kEndOfStream);
  rt.stop();
  ASSERT_TRUE(gate_ok);
  ASSERT_EQ(results.size(), 3u);
  const int64_t expected[] = {0, kFrames - 2, kFrames - 1};
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(results[i].source_index, expected[i]);
    EXPECT_EQ(results[i].sequence, expected[i]) << "a sequence gap shows the drops";
    expectFrameContent(results[i]);
    ASSERT_EQ(results[i].objects.size(), 1u);
    EXPECT_EQ(results[i].objects[0].class_name, "d" + std::to_string(expected[i]));
  }
  const RuntimeCounters c = rt.counters();
  EXPECT_EQ(c.produced, kFrames);
  EXPECT_EQ(c.dropped, kFrames - 3);
  EXPECT_EQ(c.processed, 3);
  EXPECT_EQ(c.produced, c.processed + c.dropped);
  EXPECT_EQ(results.back().counters.dropped, kFrames - 3);
}

TEST(Runtime, SlowPollerGetsTheNewestResultsAndDropsAreCounted) {
  constexpr int kFrames = 20, kQueue = 4;
  FakeProcessor proc;
  Runtime rt(std::make_unique<FakeSource>(kFrames), proc, options("block", 4, kQueue));
  rt.start();
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
  while (rt.state() != RuntimeState::kEnded && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(rt.state(), RuntimeState::kEnded);
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kEndOfStream);
  ASSERT_EQ(results.size(), static_cast<size_t>(kQueue));
  for (int i = 0; i < kQueue; ++i) {
    EXPECT_EQ(results[static_cast<size_t>(i)].source_index, kFrames - kQueue + i);
  }
  EXPECT_EQ(rt.counters().results_dropped, kFrames - kQueue);
  EXPECT_EQ(rt.counters().processed, kFrames);
}

TEST(Runtime, StopIsIdempotentJoinsAndCannotRestart) {
  FakeProcessor proc;
  // An endless paced source: only stop() ends it.
  Runtime rt(std::make_unique<FakeSource>(-1, 0, 0.001), proc, options("drop_oldest", 2, 8));
  rt.start();
  RuntimeResult r;
  PollStatus s = PollStatus::kTimeout;
  for (int i = 0; i < 100 && s != PollStatus::kResult; ++i) s = rt.poll(1.0, &r);
  ASSERT_EQ(s, PollStatus::kResult);
  expectFrameContent(r);  // drop_oldest: which frame comes first depends on the scheduling
  EXPECT_EQ(r.sequence, r.source_index);
  rt.stop();
  rt.stop();
  EXPECT_EQ(rt.state(), RuntimeState::kStopped);
  const RuntimeCounters c = rt.counters();
  EXPECT_GE(c.processed, 1);
  // Queued results stay pollable, then kStopped (no waiting).
  std::vector<RuntimeResult> rest;
  EXPECT_EQ(drain(rt, &rest), PollStatus::kStopped);
  EXPECT_EQ(static_cast<int64_t>(rest.size()) + 1 + c.results_dropped, c.processed);
  EXPECT_THROW(rt.start(), StateError);
  // Nothing moves after stop.
  EXPECT_EQ(rt.counters().processed, c.processed);
  EXPECT_EQ(rt.counters().produced, c.produced);
}

TEST(Runtime, DestroyWhilePollersWaitEndsTheirPollsFirst) {
  // Two threads blocked in poll(60 s) (the source holds frame 1 back), the controlling thread
  // destroys the runtime: both polls return kStopped, and the members they use stay alive until
  // they have left (the destructor freed them under the woken pollers: ThreadSanitizer race).
  FakeProcessor proc;
  std::atomic<bool> release{false};
  auto source = std::make_unique<FakeSource>(-1);
  source->before_next = [&release](int64_t i) {
    while (i >= 1 && !release.load()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  auto rt = std::make_unique<Runtime>(std::move(source), proc, options("block", 2, 8));
  rt->start();
  RuntimeResult first;
  ASSERT_EQ(rt->poll(kPatienceS, &first), PollStatus::kResult);
  std::atomic<int> stopped{0}, other{0};
  std::vector<std::thread> pollers;
  Runtime* const polled = rt.get();  // the pollers' own copy (rt itself is reset below)
  for (int k = 0; k < 2; ++k) {
    pollers.emplace_back([polled, &stopped, &other] {
      RuntimeResult r;
      (polled->poll(60.0, &r) == PollStatus::kStopped ? stopped : other)++;
    });
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // both are waiting by now
  // The capture thread is let go once the destructor has stopped the ring: frame 1 is not
  // delivered.
  std::thread releaser([&release] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    release = true;
  });
  rt.reset();
  for (auto& t : pollers) t.join();
  releaser.join();
  EXPECT_EQ(stopped.load(), 2);
  EXPECT_EQ(other.load(), 0);
}

TEST(Runtime, TwoThreadsStoppingAtOnceBothReturn) {
  // stop() is idempotent also when called concurrently (the second used to join a thread the
  // first had joined: std::system_error or a hang).
  for (int round = 0; round < 20; ++round) {
    FakeProcessor proc;
    Runtime rt(std::make_unique<FakeSource>(-1, 0, 0.001), proc, options("drop_oldest", 2, 8));
    rt.start();
    std::thread a([&rt] { rt.stop(); });
    std::thread b([&rt] { rt.stop(); });
    a.join();
    b.join();
    EXPECT_EQ(rt.state(), RuntimeState::kStopped) << round;
  }
}

TEST(Runtime, StopBeforeStartAndDestroyWithoutStart) {
  FakeProcessor proc;
  {
    Runtime rt(std::make_unique<FakeSource>(5), proc, options("block", 2, 8));
  }  // destroyed without start: nothing to join
  Runtime rt(std::make_unique<FakeSource>(5), proc, options("block", 2, 8));
  {
    // Polling a runtime that was never started is a state error, not an endless timeout.
    RuntimeResult r;
    EXPECT_THROW(rt.poll(0.3, &r), StateError);
  }
  rt.stop();
  EXPECT_EQ(rt.state(), RuntimeState::kStopped);
  EXPECT_THROW(rt.start(), StateError);
  RuntimeResult r;
  EXPECT_EQ(rt.poll(0.0, &r), PollStatus::kStopped);
}

TEST(Runtime, EmptySourceEndsAtOnce) {
  FakeProcessor proc;
  Runtime rt(std::make_unique<FakeSource>(0), proc, options("block", 2, 8));
  rt.start();
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kEndOfStream);
  EXPECT_TRUE(results.empty());
  rt.start();  // after the end of the stream: a no-op
  rt.stop();   // ... but after stop() start() is refused, whatever the state
  EXPECT_EQ(rt.state(), RuntimeState::kEnded);
  EXPECT_THROW(rt.start(), StateError);
}

TEST(Runtime, SourceErrorFailsAfterTheFramesBeforeIt) {
  FakeProcessor proc;
  Runtime rt(std::make_unique<FakeSource>(20, 0, 0.0, 6), proc, options("block", 2, 32));
  rt.start();
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kFailed);
  ASSERT_EQ(results.size(), 6u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(results[static_cast<size_t>(i)].source_index, i);
  EXPECT_EQ(rt.state(), RuntimeState::kFailed);
  ASSERT_TRUE(rt.failure());
  try {
    std::rethrow_exception(rt.failure());
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 6 is corrupt"), std::string::npos) << e.what();
  }
  rt.stop();
  EXPECT_EQ(rt.state(), RuntimeState::kFailed);
}

TEST(Runtime, ProcessorErrorFailsAndStopsTheCapture) {
  FakeProcessor proc;
  proc.before = [](const core::Frame& f) {
    if (f.index == 3) throw InvalidArgument("fake processor: frame 3 rejected");
  };
  // Endless source with a blocking ring: the capture thread must be woken to end.
  Runtime rt(std::make_unique<FakeSource>(-1), proc, options("block", 2, 32));
  rt.start();
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kFailed);
  ASSERT_EQ(results.size(), 3u);
  rt.stop();
  ASSERT_TRUE(rt.failure());
  EXPECT_THROW(std::rethrow_exception(rt.failure()), InvalidArgument);
}

TEST(Runtime, MismatchedFrameSizeIsAFatalErrorNamingTheFrame) {
  class Growing : public FakeSource {
   public:
    Growing() : FakeSource(10) {}
    bool next(core::Frame& f) override {
      const bool ok = FakeSource::next(f);
      if (ok && f.index == 2) f.depth = cv::Mat(kHeight * 2, kWidth, CV_32FC1, cv::Scalar(1.0f));
      return ok;
    }
  };
  FakeProcessor proc;
  Runtime rt(std::make_unique<Growing>(), proc, options("block", 2, 32));
  rt.start();
  std::vector<RuntimeResult> results;
  EXPECT_EQ(drain(rt, &results), PollStatus::kFailed);
  EXPECT_EQ(results.size(), 2u);
  try {
    std::rethrow_exception(rt.failure());
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 2"), std::string::npos) << e.what();
  }
}

/// A live sensor whose cable is `plugged`: unplugged, next() throws SensorDisconnected and
/// opening fails.
class FakeSensor : public FakeSource {
 public:
  explicit FakeSensor(const std::atomic<bool>& plugged)
      : FakeSource(-1, 0, 0.002), plugged_(plugged) {
    if (!plugged_) throw IoError("fake sensor: no device");
  }
  bool next(core::Frame& f) override {
    if (!plugged_) throw fw::SensorDisconnected("fake sensor: disconnected");
    return FakeSource::next(f);
  }
  bool isLive() const override { return true; }

 private:
  const std::atomic<bool>& plugged_;
};

TEST(Runtime, UnpluggedSensorIsAnErrorStateAndReplugResumes) {
  std::atomic<bool> plugged{true};
  fw::ReconnectOptions ro;
  ro.retry_interval_s = 0.005;
  ro.reconnect_wait_s = 0.02;
  auto sensor = std::make_unique<fw::ReconnectingSource>(
      [&] { return std::make_unique<FakeSensor>(plugged); }, "fake", ro);
  FakeProcessor proc;
  Runtime rt(std::move(sensor), proc, options("drop_oldest", 2, 1000));
  rt.start();
  auto waitFor = [&](PollStatus wanted, int64_t* last_index) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
    while (std::chrono::steady_clock::now() < deadline) {
      RuntimeResult r;
      const PollStatus s = rt.poll(0.1, &r);
      if (s == PollStatus::kResult && last_index) *last_index = r.source_index;
      if (s == wanted) return true;
      if (s == PollStatus::kFailed || s == PollStatus::kEndOfStream) return false;
    }
    return false;
  };
  int64_t last = -1;
  ASSERT_TRUE(waitFor(PollStatus::kResult, &last));
  plugged = false;
  ASSERT_TRUE(waitFor(PollStatus::kSensorError, &last)) << "unplug must be reported, not hang";
  EXPECT_EQ(rt.state(), RuntimeState::kSensorError);
  EXPECT_NE(rt.sensorError().find("fake sensor"), std::string::npos) << rt.sensorError();
  EXPECT_GE(rt.counters().sensor_errors, 1);
  // Still away: once the frames captured before the unplug are polled, polls keep reporting it
  // after their timeout.
  RuntimeResult r;
  PollStatus away = PollStatus::kResult;
  for (int i = 0; i < 10 && away == PollStatus::kResult; ++i) away = rt.poll(0.05, &r);
  EXPECT_EQ(away, PollStatus::kSensorError);
  plugged = true;
  int64_t after = -1;
  ASSERT_TRUE(waitFor(PollStatus::kResult, &after));
  EXPECT_GT(after, last) << "frame indices continue after the reconnect";
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(kPatienceS);
  while (rt.state() != RuntimeState::kRunning && std::chrono::steady_clock::now() < deadline) {
    rt.poll(0.05, &r);
  }
  EXPECT_EQ(rt.state(), RuntimeState::kRunning);
  rt.stop();
  EXPECT_EQ(rt.state(), RuntimeState::kStopped);
}

TEST(Runtime, BadOptionsAreConfigErrors) {
  FakeProcessor proc;
  EXPECT_THROW(Runtime(std::make_unique<FakeSource>(3), proc, options("newest", 2, 8)),
               ConfigError);
  EXPECT_THROW(Runtime(std::make_unique<FakeSource>(3), proc, options("block", 2, 0)), ConfigError);
  EXPECT_THROW(Runtime(nullptr, proc, options("block", 2, 8)), InvalidArgument);
}

}  // namespace
}  // namespace emf::runtime
