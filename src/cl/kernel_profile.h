// Device time per kernel, from OpenCL profiling events: what the benchmarks print to show where
// a frame's device time goes, on any device (a GPU's kernels do not show in a CPU profiler).
// Off by default. While on, every launch through cl::enqueue keeps its event and
// takeKernelProfile() adds up, per kernel name, the launches and the device time from
// CL_PROFILING_COMMAND_START to CL_PROFILING_COMMAND_END. Process-wide, like the work counters.
#pragma once

#include <CL/cl.h>

#include <cstdint>
#include <map>
#include <string>

namespace emf::cl {

/// Turns the profile on or off for the whole process. A Context created while it is on gets a
/// profiling queue; launches on a queue without one are counted with no time.
void setKernelProfiling(bool on);
bool kernelProfiling();

struct KernelTime {
  int64_t launches = 0;
  double device_ms = 0.0;  // sum over the launches of end - start, milliseconds
};

/// The launches and device time per kernel name since the last call (waits for the launches
/// still running), then starts again from zero.
std::map<std::string, KernelTime> takeKernelProfile();

/// Called by cl::enqueue with the launch's event (taken over: released here). Events are
/// resolved into the totals in batches, so the memory held stays bounded when nobody takes the
/// profile.
void recordKernelLaunch(cl_kernel kernel, cl_event event);

}  // namespace emf::cl
