// What a frame ring's producer does when the ring is full (runtime.ring_policy): shared by the
// runtime's options (pipeline) and the ring itself (firmware_host).
#pragma once

#include "common/option_binder.h"

namespace emf::core {

enum class RingPolicy {
  kDropOldest,  // overwrite the oldest unread frame (live sensors: the newest frames win)
  kBlock,       // wait for the consumer (replay: lossless), bounded by a timeout / stop()
};

inline const ChoiceNames<RingPolicy>& ringPolicyNames() {
  static const ChoiceNames<RingPolicy> names = {{RingPolicy::kDropOldest, "drop_oldest"},
                                                {RingPolicy::kBlock, "block"}};
  return names;
}

}  // namespace emf::core
