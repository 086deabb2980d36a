#include "cl/work_counters.h"

#include <atomic>

namespace emf::cl {
namespace {

std::atomic<int64_t> g_launches{0}, g_waits{0}, g_bytes_read{0};

}  // namespace

WorkCounts workCounts() {
  return {g_launches.load(std::memory_order_relaxed), g_waits.load(std::memory_order_relaxed),
          g_bytes_read.load(std::memory_order_relaxed)};
}

void countLaunch() { g_launches.fetch_add(1, std::memory_order_relaxed); }

void countHostWait(size_t bytes_read) {
  g_waits.fetch_add(1, std::memory_order_relaxed);
  if (bytes_read > 0) {
    g_bytes_read.fetch_add(static_cast<int64_t>(bytes_read), std::memory_order_relaxed);
  }
}

}  // namespace emf::cl
