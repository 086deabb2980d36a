// ring_bench: per-frame overhead of the frame ring for 640x480 frames (CV_32F depth + BGR
// colour), both policies.
//   1. protocol only: writeSlot()+commit() and acquire()+release() on one thread (no pixels)
//   2. push() (copies depth+colour into the slot) + acquire()/release() on one thread
//   3. two threads: a producer pushing as fast as it can, a consumer reading in place
// Usage: ring_bench [frames]   (default 20000)
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "firmware_host/frame_ring.h"

namespace {

using Clock = std::chrono::steady_clock;
using emf::fw::FrameRing;
using emf::fw::FrameRingOptions;
using emf::fw::FrameSlot;
using emf::fw::RingPolicy;
using emf::fw::RingStatus;

double nsSince(Clock::time_point t0, int64_t n) {
  return std::chrono::duration<double, std::nano>(Clock::now() - t0).count() /
         static_cast<double>(n);
}

FrameRingOptions options(RingPolicy policy) {
  FrameRingOptions o;
  o.capacity = 4;
  o.policy = policy;
  o.depth_width = 640;
  o.depth_height = 480;
  o.color_width = 640;
  o.color_height = 480;
  o.block_timeout_s = 10.0;
  return o;
}

void protocolOnly(RingPolicy policy, int64_t n) {
  FrameRing ring(options(policy));
  const FrameSlot* slot = nullptr;
  auto t0 = Clock::now();
  int64_t sink = 0;
  for (int64_t i = 0; i < n; ++i) {
    ring.writeSlot().source_index = i;
    ring.commit();
    ring.acquire(&slot, 0.0);
    sink += slot->source_index;
    ring.release();
  }
  const double ns = nsSince(t0, n);
  std::printf("  %-12s protocol only (writeSlot+commit+acquire+release): %8.1f ns/frame%s\n",
              emf::fw::ringPolicyName(policy), ns, sink < 0 ? "!" : "");
}

void singleThreadCopy(RingPolicy policy, int64_t n, const emf::core::Frame& frame) {
  FrameRing ring(options(policy));
  const FrameSlot* slot = nullptr;
  double push_ns = 0, pop_ns = 0;
  for (int64_t i = 0; i < n; ++i) {
    auto t0 = Clock::now();
    ring.push(frame);
    auto t1 = Clock::now();
    ring.acquire(&slot, 0.0);
    ring.release();
    auto t2 = Clock::now();
    push_ns += std::chrono::duration<double, std::nano>(t1 - t0).count();
    pop_ns += std::chrono::duration<double, std::nano>(t2 - t1).count();
  }
  std::printf(
      "  %-12s push (copy 640x480 depth+colour): %9.1f ns/frame   acquire+release: "
      "%6.1f ns/frame\n",
      emf::fw::ringPolicyName(policy), push_ns / static_cast<double>(n),
      pop_ns / static_cast<double>(n));
}

void twoThreads(RingPolicy policy, int64_t n, const emf::core::Frame& frame) {
  FrameRing ring(options(policy));
  auto t0 = Clock::now();
  std::thread producer([&] {
    for (int64_t i = 0; i < n; ++i) {
      while (ring.push(frame) == RingStatus::kTimeout) {
      }
    }
    ring.stop();
  });
  int64_t received = 0;
  const FrameSlot* slot = nullptr;
  for (;;) {
    const RingStatus st = ring.acquire(&slot, 1.0);
    if (st == RingStatus::kStopped) break;  // stopped and drained
    if (st != RingStatus::kOk) continue;
    ++received;
    ring.release();
  }
  producer.join();
  const double ns = nsSince(t0, n);
  const auto s = ring.stats();
  std::printf("  %-12s two threads: %9.1f ns per produced frame, consumed %lld, dropped %llu\n",
              emf::fw::ringPolicyName(policy), ns, static_cast<long long>(received),
              static_cast<unsigned long long>(s.dropped));
}

}  // namespace

int main(int argc, char** argv) {
  int64_t n = 20000;
  if (argc > 1) {
    char* end = nullptr;
    n = std::strtoll(argv[1], &end, 10);
    if (*end != '\0') n = 0;
  }
  if (argc > 2 || n <= 0 || n > 100000000) {
    std::fprintf(stderr, "usage: ring_bench [frames: an integer in [1, 100000000]]\n");
    return 2;
  }
  emf::core::Frame frame;
  frame.depth = cv::Mat(480, 640, CV_32F);
  cv::randu(frame.depth, 0.5, 4.0);
  frame.color = cv::Mat(480, 640, CV_8UC3);
  cv::randu(frame.color, 0, 255);
  std::printf(
      "ring_bench: %lld frames of 640x480 (CV_32F depth 1.2 MB + BGR colour 0.9 MB), "
      "capacity 4\n",
      static_cast<long long>(n));
  for (RingPolicy p : {RingPolicy::kDropOldest, RingPolicy::kBlock}) protocolOnly(p, n * 50);
  for (RingPolicy p : {RingPolicy::kDropOldest, RingPolicy::kBlock}) singleThreadCopy(p, n, frame);
  for (RingPolicy p : {RingPolicy::kDropOldest, RingPolicy::kBlock}) twoThreads(p, n, frame);
  return 0;
}
