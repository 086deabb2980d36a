#include "firmware_host/frame_ring.h"

#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

#include "common/error.h"

namespace emf::fw {
namespace {

using Clock = std::chrono::steady_clock;

int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

/// Bounded back-off for the two waits (consumer on an empty ring, blocking producer on a full
/// one): spin briefly, then yield, then sleep in short steps. No mutex, no condition variable,
/// so neither side can ever be blocked by the other holding a lock; the cost is up to
/// kMaxSleepUs of extra latency once the wait has lasted a while.
class Backoff {
 public:
  explicit Backoff(double timeout_s)
      : deadline_(timeout_s <= 0
                      ? Clock::now()
                      : Clock::now() +
                            std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(std::min(timeout_s, 1e6)))) {}
  /// Waits a little; returns false once the deadline has passed.
  bool wait() {
    if (Clock::now() >= deadline_) return false;
    if (round_ < kSpinRounds) {
      ++round_;
    } else if (round_ < kSpinRounds + kYieldRounds) {
      ++round_;
      std::this_thread::yield();
    } else {
      std::this_thread::sleep_for(std::chrono::microseconds(sleep_us_));
      sleep_us_ = std::min(sleep_us_ * 2, kMaxSleepUs);
    }
    return true;
  }

 private:
  static constexpr int kSpinRounds = 64;
  static constexpr int kYieldRounds = 64;
  static constexpr int kMaxSleepUs = 200;
  Clock::time_point deadline_;
  int round_ = 0;
  int sleep_us_ = 10;
};

void checkImage(const cv::Mat& image, int width, int height, int type, const char* what) {
  if (image.cols != width || image.rows != height || image.type() != type) {
    throw InvalidArgument(std::string("frame ring: ") + what + " image " +
                          std::to_string(image.cols) + "x" + std::to_string(image.rows) + " type " +
                          std::to_string(image.type()) + " does not match the ring's " +
                          std::to_string(width) + "x" + std::to_string(height) + " type " +
                          std::to_string(type) +
                          " slots (sized at start-up): open the ring with the source's image "
                          "sizes or convert the frame first");
  }
}

}  // namespace

RingPolicy parseRingPolicy(const std::string& text) {
  for (const auto& [policy, name] : core::ringPolicyNames()) {
    if (text == name) return policy;
  }
  throw ConfigError("runtime.ring_policy: unknown policy '" + text +
                    "': use drop_oldest (live sensors) or block (replay, lossless)");
}

const char* ringPolicyName(RingPolicy policy) {
  return choiceName(policy, core::ringPolicyNames());
}

FrameRing::FrameRing(const FrameRingOptions& options)
    : options_(options), capacity_(options.capacity) {
  if (options.capacity < 1 || options.capacity > (1 << 20)) {
    throw InvalidArgument("frame ring: capacity " + std::to_string(options.capacity) +
                          " is out of range [1, 1048576] (runtime.ring_slots)");
  }
  if (options.depth_type != CV_32FC1 && options.depth_type != CV_16UC1) {
    throw InvalidArgument("frame ring: depth type " + std::to_string(options.depth_type) +
                          " is not supported: use CV_32FC1 (metres) or CV_16UC1 (sensor units)");
  }
  if (options.depth_width <= 0 || options.depth_height <= 0 || options.color_width < 0 ||
      options.color_height < 0 || (options.color_width == 0) != (options.color_height == 0)) {
    throw InvalidArgument("frame ring: image sizes must be positive (depth " +
                          std::to_string(options.depth_width) + "x" +
                          std::to_string(options.depth_height) + ", colour " +
                          std::to_string(options.color_width) + "x" +
                          std::to_string(options.color_height) + "; colour 0x0 = none)");
  }
  if (!(options.block_timeout_s >= 0) || !std::isfinite(options.block_timeout_s)) {
    throw InvalidArgument("frame ring: block_timeout_s must be a finite value >= 0");
  }
  const int num_slots = capacity_ + 2;
  slots_.resize(num_slots);
  for (auto& s : slots_) {
    s.depth.create(options.depth_height, options.depth_width, options.depth_type);
    s.depth.setTo(0);
    if (options.color_width > 0) {
      s.color.create(options.color_height, options.color_width, CV_8UC3);
      s.color.setTo(0);
    }
  }
  entries_.reset(new std::atomic<uint32_t>[capacity_]);
  for (int i = 0; i < capacity_; ++i) entries_[i].store(0, std::memory_order_relaxed);
  free_.reset(new std::atomic<uint32_t>[num_slots]);
  for (int i = 0; i < num_slots; ++i) free_[i].store(static_cast<uint32_t>(i));
  free_head_.store(static_cast<uint64_t>(num_slots), std::memory_order_release);
}

FrameRing::~FrameRing() = default;

// ---- free list (SPSC) ------------------------------------------------------------------------

bool FrameRing::freePop(uint32_t* slot_index) {
  const uint64_t tail = free_tail_.load(std::memory_order_relaxed);
  const uint64_t head = free_head_.load(std::memory_order_acquire);
  if (head == tail) return false;
  const uint64_t n = slots_.size();
  *slot_index = free_[tail % n].load(std::memory_order_relaxed);
  free_tail_.store(tail + 1, std::memory_order_release);
  return true;
}

void FrameRing::freePush(uint32_t slot_index) {
  // Never full: there are exactly slots_.size() indices and the list has that many entries.
  const uint64_t head = free_head_.load(std::memory_order_relaxed);
  const uint64_t n = slots_.size();
  free_[head % n].store(slot_index, std::memory_order_relaxed);
  free_head_.store(head + 1, std::memory_order_release);
}

// ---- the ring --------------------------------------------------------------------------------

bool FrameRing::tryTakeOldest(uint32_t* slot_index) {
  uint64_t t = tail_.load(std::memory_order_acquire);
  for (;;) {
    const uint64_t h = head_.load(std::memory_order_acquire);
    if (t >= h) return false;
    // Read the entry before claiming it: it cannot change while tail_ == t, because the
    // producer rewrites entry t % capacity only for frame t + capacity, which needs tail_ > t.
    const uint32_t idx = entries_[t % capacity_].load(std::memory_order_relaxed);
    if (tail_.compare_exchange_weak(t, t + 1, std::memory_order_acq_rel,
                                    std::memory_order_acquire)) {
      *slot_index = idx;
      return true;
    }
    // t now holds the current tail; someone else took that frame. Retry with the next one.
  }
}

FrameSlot& FrameRing::writeSlot() {
  if (write_slot_ < 0) {
    uint32_t idx = 0;
    // The counting argument in the header guarantees a free slot here; the loop only guards
    // against a broken invariant, which would be a bug in this file.
    for (int attempt = 0; !freePop(&idx); ++attempt) {
      if (attempt > 1000000) {
        throw ResourceError("frame ring: no free slot (internal invariant broken)");
      }
      std::this_thread::yield();
    }
    write_slot_ = idx;
  }
  return slots_[static_cast<size_t>(write_slot_)];
}

RingStatus FrameRing::commit() {
  FrameSlot& slot = writeSlot();
  const uint64_t h = head_.load(std::memory_order_relaxed);  // producer owns head_
  const uint64_t cap = static_cast<uint64_t>(capacity_);
  int64_t next_write_slot = -1;
  if (h - tail_.load(std::memory_order_acquire) >= cap) {
    if (options_.policy == RingPolicy::kDropOldest) {
      // Full: take the oldest unread frame out of the ring. If the consumer takes it first,
      // the ring is no longer full and nothing is dropped.
      uint64_t t = tail_.load(std::memory_order_acquire);
      while (h - t >= cap) {
        const uint32_t idx = entries_[t % cap].load(std::memory_order_relaxed);
        if (tail_.compare_exchange_weak(t, t + 1, std::memory_order_acq_rel,
                                        std::memory_order_acquire)) {
          dropped_.fetch_add(1, std::memory_order_relaxed);
          next_write_slot = idx;
          break;
        }
        // t is the new tail: re-check whether the ring is still full.
      }
    } else {
      Backoff backoff(options_.block_timeout_s);
      while (h - tail_.load(std::memory_order_acquire) >= cap) {
        if (stopped()) return RingStatus::kStopped;
        if (!backoff.wait()) return RingStatus::kTimeout;
      }
    }
  }
  slot.sequence = static_cast<int64_t>(h);
  slot.commit_time_ns = nowNs();
  entries_[h % cap].store(static_cast<uint32_t>(write_slot_), std::memory_order_relaxed);
  head_.store(h + 1, std::memory_order_release);
  write_slot_ = next_write_slot;
  return RingStatus::kOk;
}

RingStatus FrameRing::push(const core::Frame& frame) {
  checkImage(frame.depth, options_.depth_width, options_.depth_height, options_.depth_type,
             "depth");
  const bool has_color = !frame.color.empty();
  if (has_color) {
    if (options_.color_width == 0) {
      throw InvalidArgument(
          "frame ring: the frame has a colour image but the ring was sized without colour "
          "(color 0x0): size the ring with the source's colour resolution");
    }
    checkImage(frame.color, options_.color_width, options_.color_height, CV_8UC3, "colour");
  }
  if (frame.timestamp_text.size() >= kTimestampTextCapacity) {
    throw InvalidArgument("frame ring: frame " + std::to_string(frame.index) +
                          ": timestamp text '" + frame.timestamp_text + "' is longer than " +
                          std::to_string(kTimestampTextCapacity - 1) + " characters");
  }
  FrameSlot& slot = writeSlot();
  frame.depth.copyTo(slot.depth);  // same size and type: copies in place, no allocation
  if (has_color) frame.color.copyTo(slot.color);
  slot.has_color = has_color;
  slot.source_index = frame.index;
  slot.timestamp_s = frame.timestamp;
  std::memcpy(slot.timestamp_text, frame.timestamp_text.c_str(), frame.timestamp_text.size() + 1);
  slot.color_timestamp_s = frame.rgb_timestamp;
  return commit();
}

RingStatus FrameRing::acquire(const FrameSlot** slot, double timeout_s) {
  if (read_slot_ >= 0) {
    throw InvalidArgument(
        "frame ring: acquire() called while still holding a slot: call "
        "release() after reading each frame");
  }
  uint32_t idx = 0;
  if (!tryTakeOldest(&idx)) {  // fast path first: no clock read when a frame is waiting
    Backoff backoff(timeout_s);
    while (!tryTakeOldest(&idx)) {
      if (stopped()) return RingStatus::kStopped;
      if (!backoff.wait()) return RingStatus::kTimeout;
    }
  }
  consumed_.fetch_add(1, std::memory_order_relaxed);
  read_slot_ = idx;
  *slot = &slots_[idx];
  return RingStatus::kOk;
}

void FrameRing::release() {
  if (read_slot_ < 0) return;
  freePush(static_cast<uint32_t>(read_slot_));
  read_slot_ = -1;
}

RingStatus FrameRing::pop(core::Frame& frame, double timeout_s) {
  const FrameSlot* slot = nullptr;
  const RingStatus status = acquire(&slot, timeout_s);
  if (status != RingStatus::kOk) return status;
  frame.index = slot->source_index;
  frame.timestamp = slot->timestamp_s;
  frame.rgb_timestamp = slot->color_timestamp_s;
  frame.timestamp_text = slot->timestamp_text;
  slot->depth.copyTo(frame.depth);
  if (slot->has_color) {
    slot->color.copyTo(frame.color);
  } else {
    frame.color.release();
  }
  release();
  return RingStatus::kOk;
}

void FrameRing::stop() { stopped_.store(true, std::memory_order_release); }

FrameRingStats FrameRing::stats() const {
  FrameRingStats s;
  // Read tail first: head only grows, so head - tail never underflows.
  const uint64_t tail = tail_.load(std::memory_order_acquire);
  s.produced = head_.load(std::memory_order_acquire);
  s.in_ring = s.produced - tail;
  s.consumed = consumed_.load(std::memory_order_relaxed);
  s.dropped = dropped_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace emf::fw
