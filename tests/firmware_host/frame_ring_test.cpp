// The SPSC frame ring: deterministic protocol tests (single thread) and a multi-million-frame
// two-thread stress test per policy that checks every pixel of every frame the consumer sees
// (no torn frame), strictly increasing sequence numbers (no duplicate, no reordering), no gap
// under `block`, and produced == consumed + dropped + in-ring.
// The stress frame count is EMF_RING_STRESS_FRAMES (default: 2,000,000; 150,000 under
// ThreadSanitizer / AddressSanitizer, which are ~10x slower).
#include "firmware_host/frame_ring.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <string>
#include <thread>

#include "common/error.h"

namespace emf::fw {
namespace {

#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
constexpr int64_t kDefaultStressFrames = 150000;
#else
constexpr int64_t kDefaultStressFrames = 2000000;
#endif

int64_t stressFrames() {
  const char* env = std::getenv("EMF_RING_STRESS_FRAMES");
  if (env && *env) return std::strtoll(env, nullptr, 10);
  return kDefaultStressFrames;
}

// Small frames keep the stress test fast while still covering every byte of a slot.
FrameRingOptions smallOptions(RingPolicy policy, int capacity) {
  FrameRingOptions o;
  o.policy = policy;
  o.capacity = capacity;
  o.depth_width = 32;
  o.depth_height = 24;
  o.depth_type = CV_32FC1;
  o.color_width = 16;
  o.color_height = 12;
  o.block_timeout_s = 5.0;
  return o;
}

// The payload of frame `seq`: every depth pixel and colour byte is a function of seq and the
// position, so a slot holding parts of two frames is detected.
// Depth values stay below 2^24, so they are exact in float.
float depthValue(int64_t seq, int i) { return static_cast<float>(((seq & 0x3fffff) << 2) + i); }
uint8_t colorValue(int64_t seq, int i) { return static_cast<uint8_t>((seq + i * 13) & 0xff); }

void fillSlot(FrameSlot& slot, int64_t seq) {
  float* d = slot.depth.ptr<float>();
  const int nd = static_cast<int>(slot.depth.total());
  for (int i = 0; i < nd; ++i) d[i] = depthValue(seq, i);
  uint8_t* c = slot.color.ptr<uint8_t>();
  const int nc = static_cast<int>(slot.color.total() * 3);
  for (int i = 0; i < nc; ++i) c[i] = colorValue(seq, i);
  slot.source_index = seq;
  slot.timestamp_s = static_cast<double>(seq) / 30.0;
  slot.color_timestamp_s = static_cast<double>(seq) / 30.0 + 0.001;
  slot.has_color = true;
}

/// Returns the number of mismatching values (0 = the slot holds exactly frame `seq`).
int64_t checkSlot(const FrameSlot& slot, int64_t seq) {
  int64_t bad = 0;
  const float* d = slot.depth.ptr<float>();
  const int nd = static_cast<int>(slot.depth.total());
  for (int i = 0; i < nd; ++i) bad += d[i] != depthValue(seq, i);
  const uint8_t* c = slot.color.ptr<uint8_t>();
  const int nc = static_cast<int>(slot.color.total() * 3);
  for (int i = 0; i < nc; ++i) bad += c[i] != colorValue(seq, i);
  bad += slot.source_index != seq;
  bad += slot.timestamp_s != static_cast<double>(seq) / 30.0;
  bad += slot.color_timestamp_s != static_cast<double>(seq) / 30.0 + 0.001;
  return bad;
}

TEST(FrameRing, DropOldestKeepsNewestFrames) {
  FrameRing ring(smallOptions(RingPolicy::kDropOldest, 3));
  for (int64_t s = 0; s < 5; ++s) {
    fillSlot(ring.writeSlot(), s);
    ASSERT_EQ(ring.commit(), RingStatus::kOk);
  }
  auto st = ring.stats();
  EXPECT_EQ(st.produced, 5u);
  EXPECT_EQ(st.dropped, 2u);
  EXPECT_EQ(st.in_ring, 3u);
  for (int64_t expected = 2; expected < 5; ++expected) {
    const FrameSlot* slot = nullptr;
    ASSERT_EQ(ring.acquire(&slot, 0.0), RingStatus::kOk);
    EXPECT_EQ(slot->sequence, expected);
    EXPECT_EQ(checkSlot(*slot, expected), 0);
    ring.release();
  }
  const FrameSlot* slot = nullptr;
  EXPECT_EQ(ring.acquire(&slot, 0.0), RingStatus::kTimeout);
  st = ring.stats();
  EXPECT_EQ(st.consumed, 3u);
  EXPECT_EQ(st.produced, st.consumed + st.dropped + st.in_ring);
}

// The race the protocol exists for: the consumer holds the oldest frame while the producer
// laps the ring many times. The held slot must stay intact and the frames after it arrive in
// order.
TEST(FrameRing, SlotHeldByConsumerIsNeverOverwritten) {
  FrameRing ring(smallOptions(RingPolicy::kDropOldest, 2));
  fillSlot(ring.writeSlot(), 0);
  ASSERT_EQ(ring.commit(), RingStatus::kOk);
  const FrameSlot* held = nullptr;
  ASSERT_EQ(ring.acquire(&held, 0.0), RingStatus::kOk);
  ASSERT_EQ(held->sequence, 0);
  for (int64_t s = 1; s <= 50; ++s) {
    FrameSlot& w = ring.writeSlot();
    ASSERT_NE(&w, held) << "producer was handed the slot the consumer is reading (frame " << s
                        << ")";
    fillSlot(w, s);
    ASSERT_EQ(ring.commit(), RingStatus::kOk);
  }
  EXPECT_EQ(checkSlot(*held, 0), 0);
  ring.release();
  const auto st = ring.stats();
  EXPECT_EQ(st.produced, 51u);
  EXPECT_EQ(st.consumed, 1u);
  EXPECT_EQ(st.in_ring, 2u);
  EXPECT_EQ(st.dropped, 48u);
  for (int64_t expected : {49, 50}) {
    const FrameSlot* slot = nullptr;
    ASSERT_EQ(ring.acquire(&slot, 0.0), RingStatus::kOk);
    EXPECT_EQ(slot->sequence, expected);
    EXPECT_EQ(checkSlot(*slot, expected), 0);
    ring.release();
  }
}

TEST(FrameRing, BlockIsLosslessAndTimesOutWhenFull) {
  auto o = smallOptions(RingPolicy::kBlock, 2);
  o.block_timeout_s = 0.01;
  FrameRing ring(o);
  for (int64_t s = 0; s < 2; ++s) {
    fillSlot(ring.writeSlot(), s);
    ASSERT_EQ(ring.commit(), RingStatus::kOk);
  }
  fillSlot(ring.writeSlot(), 2);
  EXPECT_EQ(ring.commit(), RingStatus::kTimeout);
  auto st = ring.stats();
  EXPECT_EQ(st.produced, 2u);
  EXPECT_EQ(st.dropped, 0u);
  // The unpublished frame stays in the write slot; after a read there is space for it.
  const FrameSlot* slot = nullptr;
  ASSERT_EQ(ring.acquire(&slot, 0.0), RingStatus::kOk);
  EXPECT_EQ(slot->sequence, 0);
  ring.release();
  EXPECT_EQ(checkSlot(ring.writeSlot(), 2), 0);
  EXPECT_EQ(ring.commit(), RingStatus::kOk);
  for (int64_t expected : {1, 2}) {
    ASSERT_EQ(ring.acquire(&slot, 0.0), RingStatus::kOk);
    EXPECT_EQ(slot->sequence, expected);
    EXPECT_EQ(checkSlot(*slot, expected), 0);
    ring.release();
  }
  st = ring.stats();
  EXPECT_EQ(st.produced, 3u);
  EXPECT_EQ(st.consumed, 3u);
  EXPECT_EQ(st.in_ring, 0u);
}

TEST(FrameRing, StopWakesBlockedProducerAndWaitingConsumer) {
  auto o = smallOptions(RingPolicy::kBlock, 1);
  o.block_timeout_s = 1e5;  // would wait "forever" without stop()
  FrameRing ring(o);
  fillSlot(ring.writeSlot(), 0);
  ASSERT_EQ(ring.commit(), RingStatus::kOk);
  std::atomic<int> producer_status{-1};
  std::thread producer([&] {
    fillSlot(ring.writeSlot(), 1);
    producer_status = static_cast<int>(ring.commit());
  });
  ring.stop();
  producer.join();
  EXPECT_EQ(producer_status.load(), static_cast<int>(RingStatus::kStopped));
  // Draining after stop still works; an empty ring then reports kStopped, not a hang.
  const FrameSlot* slot = nullptr;
  ASSERT_EQ(ring.acquire(&slot, 0.0), RingStatus::kOk);
  EXPECT_EQ(slot->sequence, 0);
  ring.release();
  EXPECT_EQ(ring.acquire(&slot, 1e5), RingStatus::kStopped);
}

TEST(FrameRing, PushCopiesFramesAndRejectsWrongSizes) {
  FrameRingOptions o;
  o.capacity = 2;
  o.depth_width = 4;
  o.depth_height = 3;
  o.color_width = 4;
  o.color_height = 3;
  FrameRing ring(o);
  core::Frame f;
  f.index = 17;
  f.timestamp = 1.5;
  f.rgb_timestamp = 1.52;
  f.timestamp_text = "1.5000";  // as the source wrote it: names the dataset's files
  f.depth = cv::Mat(3, 4, CV_32F);
  for (int i = 0; i < 12; ++i) f.depth.ptr<float>()[i] = 0.25f * static_cast<float>(i);
  f.depth.at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
  f.color = cv::Mat(3, 4, CV_8UC3, cv::Scalar(1, 2, 3));
  ASSERT_EQ(ring.push(f), RingStatus::kOk);
  core::Frame out;
  ASSERT_EQ(ring.pop(out, 0.0), RingStatus::kOk);
  EXPECT_EQ(out.index, 17);
  EXPECT_EQ(out.timestamp, 1.5);
  EXPECT_EQ(out.rgb_timestamp, 1.52);
  EXPECT_EQ(out.timestamp_text, "1.5000");
  ASSERT_EQ(out.depth.type(), CV_32FC1);
  for (int i = 0; i < 12; ++i) {
    const float a = f.depth.ptr<float>()[i], b = out.depth.ptr<float>()[i];
    EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << i;
  }
  EXPECT_EQ(cv::norm(out.color, f.color, cv::NORM_INF), 0.0);

  core::Frame wrong = f;
  wrong.depth = cv::Mat(4, 4, CV_32F, cv::Scalar(0));
  try {
    ring.push(wrong);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("depth image 4x4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("sized at start-up"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ring.stats().produced, 1u);

  core::Frame long_text = f;
  long_text.timestamp_text = std::string(kTimestampTextCapacity, '7');
  try {
    ring.push(long_text);
    FAIL() << "expected InvalidArgument";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 17: timestamp text"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(ring.stats().produced, 1u);
}

TEST(FrameRing, RejectsBadOptions) {
  FrameRingOptions o;
  o.capacity = 0;
  EXPECT_THROW(FrameRing{o}, InvalidArgument);
  o.capacity = 2;
  o.depth_type = CV_8UC1;
  EXPECT_THROW(FrameRing{o}, InvalidArgument);
  EXPECT_EQ(parseRingPolicy("drop_oldest"), RingPolicy::kDropOldest);
  EXPECT_EQ(parseRingPolicy("block"), RingPolicy::kBlock);
  EXPECT_THROW(parseRingPolicy("drop-oldest"), ConfigError);
}

struct StressResult {
  int64_t received = 0;
  int64_t torn = 0;            // frames with at least one wrong value
  int64_t not_increasing = 0;  // duplicates or reordering
  int64_t gaps = 0;            // frames skipped between consecutive reads
  int64_t last_sequence = -1;
  FrameRingStats stats;
};

/// Producer pushes `frames` frames as fast as it can; the consumer checks every frame and,
/// every `slow_every` frames, pauses briefly so that drop_oldest really drops (and laps the
/// slot being read).
StressResult runStress(RingPolicy policy, int capacity, int64_t frames, int slow_every) {
  FrameRing ring(smallOptions(policy, capacity));
  StressResult r;
  std::atomic<bool> producer_done{false};
  std::thread producer([&] {
    for (int64_t s = 0; s < frames; ++s) {
      fillSlot(ring.writeSlot(), s);
      RingStatus st;
      while ((st = ring.commit()) == RingStatus::kTimeout) {
      }
      if (st != RingStatus::kOk) break;
    }
    producer_done.store(true, std::memory_order_release);
  });
  for (;;) {
    const FrameSlot* slot = nullptr;
    const bool done = producer_done.load(std::memory_order_acquire);
    const RingStatus st = ring.acquire(&slot, 0.001);
    if (st != RingStatus::kOk) {
      if (done) break;  // producer finished before our last look and the ring is empty
      continue;
    }
    const int64_t seq = slot->sequence;
    if (checkSlot(*slot, seq) != 0) ++r.torn;
    if (seq <= r.last_sequence) ++r.not_increasing;
    if (seq > r.last_sequence + 1) r.gaps += seq - r.last_sequence - 1;
    r.last_sequence = seq;
    ++r.received;
    if (slow_every > 0 && r.received % slow_every == 0) {
      // Hold the slot while the producer runs on (the overwrite race).
      for (int i = 0; i < 100; ++i) std::this_thread::yield();
      if (checkSlot(*slot, seq) != 0) ++r.torn;
    }
    ring.release();
  }
  producer.join();
  r.stats = ring.stats();
  return r;
}

TEST(FrameRingStress, DropOldestNoTornDuplicateOrReorderedFrames) {
  const int64_t n = stressFrames();
  const StressResult r = runStress(RingPolicy::kDropOldest, 2, n, 64);
  EXPECT_EQ(r.torn, 0);
  EXPECT_EQ(r.not_increasing, 0);
  EXPECT_EQ(r.stats.produced, static_cast<uint64_t>(n));
  EXPECT_EQ(r.stats.consumed, static_cast<uint64_t>(r.received));
  EXPECT_EQ(r.stats.in_ring, 0u);
  EXPECT_EQ(r.stats.produced, r.stats.consumed + r.stats.dropped + r.stats.in_ring);
  // Every skipped sequence number is a dropped frame and vice versa.
  EXPECT_EQ(static_cast<uint64_t>(r.gaps), r.stats.dropped);
  // The newest frame always survives, and the test really exercised dropping.
  EXPECT_EQ(r.last_sequence, n - 1);
  EXPECT_GT(r.stats.dropped, 0u);
  EXPECT_GT(r.received, 0);
  std::printf("drop_oldest: %lld frames, consumed %llu, dropped %llu\n", static_cast<long long>(n),
              static_cast<unsigned long long>(r.stats.consumed),
              static_cast<unsigned long long>(r.stats.dropped));
}

TEST(FrameRingStress, BlockIsLosslessInOrderAndUntorn) {
  const int64_t n = stressFrames();
  const StressResult r = runStress(RingPolicy::kBlock, 8, n, 256);
  EXPECT_EQ(r.torn, 0);
  EXPECT_EQ(r.not_increasing, 0);
  EXPECT_EQ(r.gaps, 0);
  EXPECT_EQ(r.received, n);
  EXPECT_EQ(r.last_sequence, n - 1);
  EXPECT_EQ(r.stats.produced, static_cast<uint64_t>(n));
  EXPECT_EQ(r.stats.consumed, static_cast<uint64_t>(n));
  EXPECT_EQ(r.stats.dropped, 0u);
  EXPECT_EQ(r.stats.in_ring, 0u);
}

}  // namespace
}  // namespace emf::fw
