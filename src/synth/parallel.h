// Splits [0, n) into contiguous chunks processed on std::threads (the calling thread takes the
// last one). Exceptions thrown by a chunk are rethrown on the calling thread.
#pragma once

#include <algorithm>
#include <exception>
#include <functional>
#include <thread>
#include <vector>

namespace emf::synth {

/// Number of worker threads for `requested` (0 = hardware concurrency, capped at 8).
inline int resolveThreads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return static_cast<int>(std::clamp(hw, 1u, 8u));
}

/// Calls fn(begin, end) on at most `threads` disjoint chunks covering [0, n).
inline void parallelFor(int n, int threads, const std::function<void(int, int)>& fn) {
  threads = std::max(1, std::min(threads, n));
  if (threads <= 1) {
    if (n > 0) fn(0, n);
    return;
  }
  std::vector<std::thread> workers;
  std::vector<std::exception_ptr> errors(static_cast<size_t>(threads));
  auto run = [&](int k) {
    try {
      fn(n * k / threads, n * (k + 1) / threads);
    } catch (...) {
      errors[static_cast<size_t>(k)] = std::current_exception();
    }
  };
  for (int k = 0; k + 1 < threads; ++k) workers.emplace_back(run, k);
  run(threads - 1);
  for (auto& w : workers) w.join();
  for (auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace emf::synth
