// The OpenCL runtime of one emf system: selected device, context, in-order queue, and the
// programs built from the embedded kernels (compiled once per device, cached on disk).
//
// Thread safety: program()/kernel() may be called from several threads; each caller owns the
// returned KernelHandle (cl_kernel argument state is not thread-safe, so never share one).
// The queue is in-order; enqueue from one thread at a time.
#pragma once

#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "cl/cl_handle.h"
#include "cl/cl_options.h"
#include "cl/device.h"
#include "cl/program_cache.h"

namespace emf::cl {

struct ProgramCacheStats {
  int memory_hits = 0;  // program already built in this process
  int disk_hits = 0;    // loaded from a cached binary
  int compiled = 0;     // compiled from source
  int stored = 0;       // binaries written to the cache
};

class Context {
 public:
  /// Selects the device from `options` (PoCL CPU as fallback), creates context and queue.
  explicit Context(const ClOptions& options);
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  /// The program built from kernels_cl/<file>.cl with -DEMF_W=lanes(), the configured build
  /// options and `extra_options` (e.g. "-DBLOCK=8"). Throws ClError with the build log on failure.
  cl_program program(const std::string& file, const std::string& extra_options = "");
  /// The clBuildProgram options program() uses with `extra_options`.
  std::string programOptions(const std::string& extra_options = "") const;
  /// A new kernel object for `kernel_name` in kernels_cl/<file>.cl.
  KernelHandle kernel(const std::string& file, const std::string& kernel_name,
                      const std::string& extra_options = "");

  /// Device buffer of `bytes` bytes (initialised from `host` if given).
  MemHandle buffer(cl_mem_flags flags, size_t bytes, const void* host = nullptr) const;
  /// Blocking copies between host memory and a buffer.
  void write(const MemHandle& mem, const void* host, size_t bytes, size_t offset = 0) const;
  void read(const MemHandle& mem, void* host, size_t bytes, size_t offset = 0) const;
  /// Waits for all enqueued work.
  void finish() const;

  cl_context context() const { return context_.get(); }
  cl_command_queue queue() const { return queue_.get(); }
  cl_device_id deviceId() const { return selection_.device.device; }
  const DeviceInfo& device() const { return selection_.device; }
  const DeviceSelection& selection() const { return selection_; }
  /// Lanes per work item of the explicit-SIMD kernels (EMF_W): the launches divide their pixel
  /// or voxel counts by it.
  int lanes() const { return lanes_; }
  /// device().describe() plus ", kernel lanes N": what the benches and run.json print.
  std::string describe() const;
  const ProgramCache& cache() const { return cache_; }
  ProgramCacheStats cacheStats() const;

  /// The cache key of a program (exposed for tests).
  std::string cacheKey(const std::string& sha256, const std::string& build_options) const;

 private:
  ProgramHandle build(const std::string& file, const std::string& options);

  ClOptions options_;
  DeviceSelection selection_;
  int lanes_ = 16;
  ContextHandle context_;
  QueueHandle queue_;
  ProgramCache cache_;
  mutable std::mutex mutex_;
  std::map<std::string, ProgramHandle> programs_;
  ProgramCacheStats stats_;
};

/// EMF_W from the key cl.lanes ("4", "8" or "16"). Throws ConfigError on another text.
int parseLanes(const std::string& key_value);

/// Sets kernel argument `index` to `value` (a POD or cl_mem), naming the kernel on error.
template <typename T>
void setArg(const KernelHandle& k, cl_uint index, const T& value);

/// Sets all arguments in order: setArgs(k, a, b, c).
template <typename... Args>
void setArgs(const KernelHandle& k, const Args&... args) {
  cl_uint i = 0;
  (setArg(k, i++, args), ...);
}

/// Enqueues a 1-D/2-D/3-D NDRange with global size rounded up to `local` multiples when local
/// is given (kernels must bounds-check). Throws ClError naming the kernel.
void enqueue(cl_command_queue q, const KernelHandle& k, size_t gx, size_t gy = 0, size_t gz = 0,
             size_t local_x = 0, size_t local_y = 0);

}  // namespace emf::cl

#include "cl/context_inl.h"
