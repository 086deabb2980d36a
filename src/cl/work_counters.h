// Counts of the OpenCL work emf issues, process-wide: kernel launches, blocking host waits
// (blocking reads, writes and maps, clFinish) and bytes read back to the host. Unlike times they
// do not depend on the machine or its load: run.json and the benchmarks report them per frame
// (pipeline::SlamSystem::counters) next to the milliseconds.
#pragma once

#include <cstddef>
#include <cstdint>

namespace emf::cl {

struct WorkCounts {
  int64_t launches = 0;
  int64_t host_waits = 0;
  int64_t bytes_read = 0;
};

/// Totals since the process started (every thread, every Context).
WorkCounts workCounts();

/// Called by the cl module's own enqueue / read / write / finish / map wrappers.
void countLaunch();
void countHostWait(size_t bytes_read = 0);

}  // namespace emf::cl
