// The frame ring between a sensor's capture thread (the producer) and the SLAM thread (the
// consumer): single-producer single-consumer, lock-free, with a fixed number of frame slots
// allocated once at start-up.
//
// Protocol (why it is safe without a mutex):
//  - There are capacity + 2 slots. At any time each slot index is in exactly one place: the
//    ring of published frames (at most `capacity`), the free list, the producer's hands (the
//    slot it is filling) or the consumer's hands (the slot it is reading). Counting them shows
//    the free list is never empty when the producer needs a slot, so the producer never
//    allocates and never waits for one.
//  - The ring of published frames is a circular array of slot indices with two monotonic
//    64-bit counters: `head_` (frames published, written by the producer only) and `tail_`
//    (frames taken out of the ring). Two parties may take the oldest entry: the consumer
//    (to read it) and, under drop_oldest, the producer (to drop it when the ring is full).
//    Both take it with a compare-and-swap of `tail_` from t to t+1; whoever wins owns the slot
//    of entry t, so a slot the consumer is reading is never in the ring and can never be
//    overwritten, and a frame is never both dropped and consumed.
//  - The consumer gives its slot back through an SPSC free list (release store); the producer
//    takes slots from it (acquire load), so the consumer's reads happen-before the producer's
//    next writes to that slot.
//  - Publishing: the producer fills the slot, stores its index into entry `head_ % capacity`
//    and then increments `head_` with a release store; the consumer's acquire load of `head_`
//    makes the slot contents visible.
// Policies: drop_oldest never waits (a full ring loses its oldest unread frame); block waits
// for space with a bounded, stoppable back-off (spin, yield, short sleeps; no mutex).
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/frame.h"
#include "core/ring_policy.h"

namespace emf::fw {

/// What the producer does when the ring is full (core/ring_policy.h).
using core::RingPolicy;

/// Parses "drop_oldest" / "block" (the values of runtime.ring_policy). Throws ConfigError.
RingPolicy parseRingPolicy(const std::string& text);
/// "drop_oldest" / "block".
const char* ringPolicyName(RingPolicy policy);

/// Sizes of the preallocated slots and the policy. All frames pushed must match these.
struct FrameRingOptions {
  /// Unread frames the ring can hold (runtime.ring_slots); 2 more slots are allocated for the
  /// one being written and the one being read.
  int capacity = 4;
  RingPolicy policy = RingPolicy::kBlock;
  /// Depth image size and type: CV_32FC1 (metres, NaN = invalid) or CV_16UC1 (sensor units).
  int depth_width = 640;
  int depth_height = 480;
  int depth_type = CV_32FC1;
  /// Colour image size (CV_8UC3 BGR); 0 x 0 = the ring carries no colour.
  int color_width = 640;
  int color_height = 480;
  /// block policy: longest a push waits for space before it returns kTimeout, seconds.
  double block_timeout_s = 1.0;
};

/// Capacity of FrameSlot::timestamp_text, NUL included.
constexpr size_t kTimestampTextCapacity = 64;

/// One preallocated frame slot. The producer fills it in place; the consumer reads it in place.
struct FrameSlot {
  /// 0-based position of the frame in the producer's stream (assigned at commit); consecutive
  /// values mean no frame was dropped in between.
  int64_t sequence = -1;
  /// The source's own frame index (Frame::index).
  int64_t source_index = 0;
  /// Sensor timestamps of depth and colour, seconds (sensor clock).
  double timestamp_s = 0.0;
  double color_timestamp_s = 0.0;
  /// The depth timestamp as the source wrote it (Frame::timestamp_text, which names dataset
  /// files), NUL-terminated; "" when the source gave none.
  char timestamp_text[kTimestampTextCapacity] = {};
  /// Host steady-clock time at which the producer committed the frame, nanoseconds (for
  /// end-to-end latency; std::chrono::steady_clock epoch).
  int64_t commit_time_ns = 0;
  /// Preallocated images of the sizes in FrameRingOptions (color empty when the ring has none).
  cv::Mat depth;
  cv::Mat color;
  /// False when the frame had no colour image (color then holds stale pixels).
  bool has_color = false;
};

/// Frame counters. Exact when both threads are quiescent; produced == consumed + dropped +
/// in_ring always holds for such a snapshot.
struct FrameRingStats {
  uint64_t produced = 0;  // frames published into the ring
  uint64_t consumed = 0;  // frames taken by the consumer
  uint64_t dropped = 0;   // frames overwritten unread (drop_oldest)
  uint64_t in_ring = 0;   // published, not yet taken
};

enum class RingStatus {
  kOk,
  kTimeout,  // nothing to read / no space within the timeout
  kStopped,  // stop() was called
};

class FrameRing {
 public:
  /// Allocates capacity + 2 slots. Throws InvalidArgument for a capacity < 1, unsupported depth
  /// type or non-positive sizes.
  explicit FrameRing(const FrameRingOptions& options);
  ~FrameRing();
  FrameRing(const FrameRing&) = delete;
  FrameRing& operator=(const FrameRing&) = delete;

  // ---- producer (one thread) -----------------------------------------------------------------
  /// The slot to fill for the next frame. Never blocks, never allocates, never fails. Calling it
  /// again before commit() returns the same slot.
  FrameSlot& writeSlot();
  /// Publishes the slot returned by writeSlot() (assigns its sequence number and commit time).
  /// drop_oldest: never waits, always kOk. block: waits up to block_timeout_s for space; on
  /// kTimeout / kStopped the frame is not published (not counted) and stays in writeSlot(), so
  /// the caller may call commit() again.
  RingStatus commit();
  /// Copies `frame` into the write slot and commits. Throws InvalidArgument (before touching
  /// the ring) when the images do not match the slot sizes/types chosen at start-up.
  RingStatus push(const core::Frame& frame);

  // ---- consumer (one thread) -----------------------------------------------------------------
  /// Takes the oldest unread frame, waiting up to timeout_s (0 = do not wait). On kOk *slot
  /// stays valid and unchanged until release(). Must not be called while holding a slot.
  RingStatus acquire(const FrameSlot** slot, double timeout_s);
  /// Returns the slot taken by acquire() to the producer.
  void release();
  /// acquire() + copy into `frame` (index, timestamps, depth, color) + release().
  RingStatus pop(core::Frame& frame, double timeout_s);

  // ---- either thread -------------------------------------------------------------------------
  /// Wakes every wait with kStopped (now and later). Frames already in the ring can still be
  /// read with a timeout of 0 (draining).
  void stop();
  bool stopped() const { return stopped_.load(std::memory_order_acquire); }
  FrameRingStats stats() const;
  const FrameRingOptions& options() const { return options_; }
  int capacity() const { return capacity_; }

 private:
  bool tryTakeOldest(uint32_t* slot_index);  // consumer: CAS on tail_ (see protocol above)
  bool freePop(uint32_t* slot_index);        // producer side of the free list
  void freePush(uint32_t slot_index);        // consumer side of the free list

  const FrameRingOptions options_;
  const int capacity_;
  std::vector<FrameSlot> slots_;  // capacity_ + 2, allocated once

  // Published frames: entries_[i % capacity_] for head_ > i >= tail_.
  std::unique_ptr<std::atomic<uint32_t>[]> entries_;
  alignas(64) std::atomic<uint64_t> head_{0};
  alignas(64) std::atomic<uint64_t> tail_{0};

  // Free slot indices (SPSC: consumer pushes, producer pops), capacity_ + 2 entries.
  std::unique_ptr<std::atomic<uint32_t>[]> free_;
  alignas(64) std::atomic<uint64_t> free_head_{0};  // pushes (consumer)
  alignas(64) std::atomic<uint64_t> free_tail_{0};  // pops (producer)

  alignas(64) std::atomic<uint64_t> consumed_{0};  // written by the consumer only
  std::atomic<uint64_t> dropped_{0};               // written by the producer only
  std::atomic<bool> stopped_{false};

  // Producer-private state.
  alignas(64) int64_t write_slot_ = -1;  // slot index being filled, -1 = none yet
  // Consumer-private state.
  alignas(64) int64_t read_slot_ = -1;  // slot index held by the consumer, -1 = none
};

}  // namespace emf::fw
