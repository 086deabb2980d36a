#include "cl/kernel_profile.h"

#include <atomic>
#include <mutex>
#include <utility>
#include <vector>

#include "cl/context.h"

namespace emf::cl {
namespace {

// Pending events are resolved once this many have gathered.
constexpr size_t kResolveBatch = 4096;

std::atomic<bool> g_on{false};

struct Pending {
  std::string name;
  cl_event event;
};

struct Profile {
  std::mutex mutex;
  std::vector<Pending> pending;
  std::map<std::string, KernelTime> totals;
} g_profile;

// Adds the pending events to the totals and releases them. Called with the mutex held.
void resolve() {
  for (Pending& p : g_profile.pending) {
    KernelTime& t = g_profile.totals[p.name];
    ++t.launches;
    cl_ulong start = 0, end = 0;
    if (clWaitForEvents(1, &p.event) == CL_SUCCESS &&
        clGetEventProfilingInfo(p.event, CL_PROFILING_COMMAND_START, sizeof(start), &start,
                                nullptr) == CL_SUCCESS &&
        clGetEventProfilingInfo(p.event, CL_PROFILING_COMMAND_END, sizeof(end), &end, nullptr) ==
            CL_SUCCESS &&
        end >= start) {
      t.device_ms += static_cast<double>(end - start) * 1e-6;
    }
    clReleaseEvent(p.event);
  }
  g_profile.pending.clear();
}

}  // namespace

void setKernelProfiling(bool on) { g_on.store(on, std::memory_order_relaxed); }

bool kernelProfiling() { return g_on.load(std::memory_order_relaxed); }

void recordKernelLaunch(cl_kernel kernel, cl_event event) {
  std::string name = kernelName(kernel);
  std::lock_guard<std::mutex> lock(g_profile.mutex);
  g_profile.pending.push_back({std::move(name), event});
  if (g_profile.pending.size() >= kResolveBatch) resolve();
}

std::map<std::string, KernelTime> takeKernelProfile() {
  std::lock_guard<std::mutex> lock(g_profile.mutex);
  resolve();
  std::map<std::string, KernelTime> out;
  out.swap(g_profile.totals);
  return out;
}

}  // namespace emf::cl
