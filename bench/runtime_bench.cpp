// runtime_bench: end-to-end latency of the runtime (capture thread -> frame ring -> SLAM thread)
// on a synthetic 30 Hz sensor, for a frame size where the SLAM is slower than the sensor
// (640x480) and one where it should keep up (160x120).
//
// The sensor: synth:room frames rendered before the run (held in memory) and replayed by the
// capture thread at 30 Hz in real time (forward, then backward, so the camera motion stays
// continuous). Frame i's sensor timestamp is its scheduled time t0 + i / 30 s on the host steady
// clock, so here the sensor clock and the host clock are the same and the true
// sensor-timestamp-to-result latency can be measured. The sensor runs for the given seconds,
// then the runtime is stopped (as a live stream would be). Figures per configuration:
//   produced / processed / dropped   frames (ring policy drop_oldest by default)
//   latency sensor->result           result time - scheduled sensor time (median, p99), ms
//   latency commit->result           RuntimeResult::latency_ms, what the C API reports
//   processing                       time in SlamSystem::process (median), ms
// Before the run, a throw-away SlamSystem processes kWarmupFrames frames so that PoCL's
// per-launch-size kernel compilation is not measured. The first result is left out of the
// latency figures (its frame is read when the runtime is created, before start()).
// Usage: runtime_bench [seconds=10] [policy=drop_oldest] [WxH ...]   (default 640x480 160x120)
// The last lines are machine-readable: `runtime_bench size=WxH policy=P produced=N ...`.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cl/context.h"
#include "common/error.h"
#include "common/log.h"
#include "core/frame_source.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "runtime/runtime.h"
#include "sources/open_source.h"

namespace {

constexpr double kSensorHz = 30.0;
/// Distinct frames rendered (replayed back and forth).
constexpr int kRenderedFrames = 60;
/// Frames processed by a throw-away system before the run.
constexpr int kWarmupFrames = 5;

/// Replays pre-rendered frames at kSensorHz in real time, ping-pong, for `seconds`.
class PacedSource : public emf::core::FrameSource {
 public:
  PacedSource(std::vector<emf::core::Frame> frames, emf::core::Intrinsics k, double seconds)
      : frames_(std::move(frames)), k_(k), total_(static_cast<int64_t>(seconds * kSensorHz)) {
    scheduled_ns_.resize(static_cast<size_t>(total_), 0);
  }
  emf::core::Intrinsics intrinsics() const override { return k_; }
  std::string describe() const override { return "paced synth:room at 30 Hz"; }
  bool isLive() const override { return true; }
  bool next(emf::core::Frame& frame) override {
    if (next_ >= total_) return false;
    if (next_ == 0) {
      // The runtime reads frame 0 at creation; the clock starts at frame 1.
      start_ns_ = emf::runtime::steadyNowNs() - static_cast<int64_t>(1e9 / kSensorHz);
    }
    const int64_t due =
        start_ns_ + static_cast<int64_t>(static_cast<double>(next_) * 1e9 / kSensorHz);
    const int64_t now = emf::runtime::steadyNowNs();
    if (due > now) std::this_thread::sleep_for(std::chrono::nanoseconds(due - now));
    const int64_t period = 2 * (static_cast<int64_t>(frames_.size()) - 1);
    int64_t k = next_ % period;
    if (k >= static_cast<int64_t>(frames_.size())) k = period - k;
    const emf::core::Frame& src = frames_[static_cast<size_t>(k)];
    frame.index = next_;
    frame.timestamp = static_cast<double>(due) * 1e-9;
    frame.rgb_timestamp = frame.timestamp;
    frame.depth = src.depth;  // shared pixels: the ring copies them
    frame.color = src.color;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      scheduled_ns_[static_cast<size_t>(next_)] = due;
    }
    ++next_;
    return true;
  }
  int64_t scheduledNs(int64_t i) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return scheduled_ns_[static_cast<size_t>(i)];
  }

 private:
  std::vector<emf::core::Frame> frames_;
  emf::core::Intrinsics k_;
  int64_t total_;
  int64_t next_ = 0;
  int64_t start_ns_ = 0;
  mutable std::mutex mutex_;
  std::vector<int64_t> scheduled_ns_;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t i =
      std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

void runOne(int width, int height, double seconds, const std::string& policy) {
  emf::Config config;
  config.runtime.ring_policy = emf::fw::parseRingPolicy(policy);
  config.validate();
  const std::string uri = "synth:room?frames=" + std::to_string(kRenderedFrames) +
                          "&width=" + std::to_string(width) + "&height=" + std::to_string(height);
  auto synth = emf::sources::openSource(uri, config.source);
  const emf::core::Intrinsics k = synth->intrinsics();
  std::vector<emf::core::Frame> frames;
  emf::core::Frame f;
  while (synth->next(f)) frames.push_back(f);

  emf::cl::Context ctx(config.cl);
  {
    // Warm-up on a throw-away system: PoCL compiles each kernel for its launch sizes on first
    // use, which would otherwise land in the first frames' latency.
    const int64_t t0 = emf::runtime::steadyNowNs();
    emf::pipeline::SlamSystem warm(ctx, config, k);
    for (int i = 0; i < kWarmupFrames; ++i) warm.process(frames[static_cast<size_t>(i)]);
    std::printf("%dx%d: warm-up of %d frames took %.1f s\n", width, height, kWarmupFrames,
                static_cast<double>(emf::runtime::steadyNowNs() - t0) * 1e-9);
  }
  emf::pipeline::SlamSystem slam(ctx, config, k);
  emf::runtime::SlamProcessor processor(slam);
  // More frames than the run needs: the run ends by time, not by the end of the source.
  auto paced = std::make_unique<PacedSource>(std::move(frames), k, seconds + 600.0);
  PacedSource* source = paced.get();

  std::mutex m;
  std::vector<double> sensor_latency_ms, commit_latency_ms, processing_ms;
  int lost = 0;
  auto callback = [&](const emf::runtime::RuntimeResult& r) {
    std::lock_guard<std::mutex> lock(m);
    if (r.lost) ++lost;
    if (r.frame_index == 0) return;
    sensor_latency_ms.push_back(
        static_cast<double>(r.result_time_ns - source->scheduledNs(r.source_index)) * 1e-6);
    commit_latency_ms.push_back(r.latency_ms);
    processing_ms.push_back(r.processing_ms);
  };
  emf::runtime::Runtime rt(std::move(paced), processor, config.runtime, callback);
  const int64_t start_ns = emf::runtime::steadyNowNs();
  rt.start();
  // The sensor runs for `seconds`; then the runtime is stopped (the frame being processed
  // completes, frames still in the ring are discarded as on a live stop).
  const int64_t end_ns = emf::runtime::steadyNowNs() + static_cast<int64_t>(seconds * 1e9);
  emf::runtime::RuntimeResult r;
  while (emf::runtime::steadyNowNs() < end_ns) {
    const emf::runtime::PollStatus s = rt.poll(0.1, &r);
    if (s != emf::runtime::PollStatus::kResult && s != emf::runtime::PollStatus::kTimeout) {
      throw emf::Error("runtime_bench: the runtime ended early (" +
                       std::string(emf::runtime::runtimeStateName(rt.state())) + ")");
    }
  }
  rt.stop();
  // The rate over the time it really ran (the last poll may overshoot `seconds` by 0.1 s).
  const double ran_s = static_cast<double>(emf::runtime::steadyNowNs() - start_ns) * 1e-9;
  const emf::runtime::RuntimeCounters c = rt.counters();
  std::lock_guard<std::mutex> lock(m);
  const double drop_pct =
      c.produced ? 100.0 * static_cast<double>(c.dropped) / static_cast<double>(c.produced) : 0.0;
  std::printf(
      "%dx%d %s, %.0f Hz for %.0f s: produced %lld, processed %lld (%.1f Hz), dropped %lld "
      "(%.1f%%), "
      "lost %d\n",
      width, height, policy.c_str(), kSensorHz, seconds, static_cast<long long>(c.produced),
      static_cast<long long>(c.processed), static_cast<double>(c.processed) / ran_s,
      static_cast<long long>(c.dropped), drop_pct, lost);
  std::printf("  latency sensor->result: median %.1f ms, p99 %.1f ms\n",
              percentile(sensor_latency_ms, 0.5), percentile(sensor_latency_ms, 0.99));
  std::printf("  latency commit->result: median %.1f ms, p99 %.1f ms\n",
              percentile(commit_latency_ms, 0.5), percentile(commit_latency_ms, 0.99));
  std::printf("  processing: median %.1f ms, p99 %.1f ms\n", percentile(processing_ms, 0.5),
              percentile(processing_ms, 0.99));
  std::printf(
      "runtime_bench size=%dx%d policy=%s sensor_hz=%.0f produced=%lld processed=%lld "
      "dropped=%lld latency_median_ms=%.1f latency_p99_ms=%.1f commit_latency_median_ms=%.1f "
      "commit_latency_p99_ms=%.1f processing_median_ms=%.1f\n",
      width, height, policy.c_str(), kSensorHz, static_cast<long long>(c.produced),
      static_cast<long long>(c.processed), static_cast<long long>(c.dropped),
      percentile(sensor_latency_ms, 0.5), percentile(sensor_latency_ms, 0.99),
      percentile(commit_latency_ms, 0.5), percentile(commit_latency_ms, 0.99),
      percentile(processing_ms, 0.5));
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    emf::setLogLevel(emf::LogLevel::kWarning);
    double seconds = 10.0;
    if (argc > 1) {
      char* end = nullptr;
      seconds = std::strtod(argv[1], &end);
      if (*end != '\0') seconds = -1;
    }
    const std::string policy = argc > 2 ? argv[2] : "drop_oldest";
    if (!(seconds >= 0.1 && seconds <= 3600)) {
      std::fprintf(stderr, "runtime_bench: seconds must be a number in [0.1, 3600]\n");
      std::fprintf(stderr, "usage: runtime_bench [seconds=10] [policy=drop_oldest] [WxH ...]\n");
      return 2;
    }
    std::vector<std::pair<int, int>> sizes;
    for (int i = 3; i < argc; ++i) {
      int w = 0, h = 0;
      char rest = 0;
      if (std::sscanf(argv[i], "%dx%d%c", &w, &h, &rest) != 2 || w <= 0 || h <= 0 || w > 4096 ||
          h > 4096) {
        std::fprintf(stderr, "runtime_bench: size '%s' is not WxH\n", argv[i]);
        return 2;
      }
      sizes.emplace_back(w, h);
    }
    if (sizes.empty()) sizes = {{640, 480}, {160, 120}};
    for (const auto& [w, h] : sizes) runOne(w, h, seconds, policy);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "runtime_bench: %s\n", e.what());
    return 1;
  }
}
