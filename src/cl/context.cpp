#include "cl/context.h"

#include <vector>

#include "cl/cl_error.h"
#include "cl/embedded_kernels.h"
#include "cl/kernel_profile.h"
#include "cl/work_counters.h"
#include "common/error.h"
#include "common/log.h"

namespace emf::cl {

std::string kernelName(cl_kernel k) {
  size_t n = 0;
  if (!k || clGetKernelInfo(k, CL_KERNEL_FUNCTION_NAME, 0, nullptr, &n) != CL_SUCCESS) {
    return "<kernel>";
  }
  std::string s(n, '\0');
  clGetKernelInfo(k, CL_KERNEL_FUNCTION_NAME, n, s.data(), nullptr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

int parseLanes(const std::string& key_value) {
  if (key_value == "4" || key_value == "8" || key_value == "16") return std::stoi(key_value);
  throw ConfigError("cl.lanes: '" + key_value + "' is not one of 4, 8, 16");
}

Context::Context(const ClOptions& options)
    : options_(options),
      selection_(selectDevice(options)),
      lanes_(parseLanes(options.lanes)),
      cache_(options.cache_dir, !options.disable_cache) {
  cl_int err = CL_SUCCESS;
  const cl_context_properties props[] = {
      CL_CONTEXT_PLATFORM, reinterpret_cast<cl_context_properties>(selection_.device.platform), 0};
  cl_device_id dev = selection_.device.device;
  context_ = ContextHandle(clCreateContext(props, 1, &dev, nullptr, nullptr, &err));
  check(err, "clCreateContext(" + selection_.device.device_name + ")");
  const cl_command_queue_properties queue_props =
      kernelProfiling() ? CL_QUEUE_PROFILING_ENABLE : 0;  // the benchmarks' kernel profile
  queue_ = QueueHandle(clCreateCommandQueue(context_.get(), dev, queue_props, &err));
  check(err, "clCreateCommandQueue(" + selection_.device.device_name + ")");
}

std::string Context::cacheKey(const std::string& sha256, const std::string& build_options) const {
  return "source=" + sha256 + "\noptions=" + build_options +
         "\ndevice=" + selection_.device.device_name +
         "\ndriver=" + selection_.device.driver_version +
         "\nplatform=" + selection_.device.platform_version + "\n";
}

std::string Context::describe() const {
  return selection_.device.describe() + ", kernel lanes " + std::to_string(lanes_);
}

ProgramCacheStats Context::cacheStats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

std::string Context::programOptions(const std::string& extra_options) const {
  std::string options = "-cl-std=CL1.2 -DEMF_W=" + std::to_string(lanes_);
  if (!options_.build_options.empty()) options += " " + options_.build_options;
  if (!extra_options.empty()) options += " " + extra_options;
  return options;
}

cl_program Context::program(const std::string& file, const std::string& extra_options) {
  const std::string options = programOptions(extra_options);
  const std::string memo_key = file + "\n" + options;
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = programs_.find(memo_key);
  if (it != programs_.end()) {
    ++stats_.memory_hits;
    return it->second.get();
  }
  ProgramHandle p = build(file, options);
  cl_program raw = p.get();
  programs_.emplace(memo_key, std::move(p));
  return raw;
}

namespace {

std::string buildLog(cl_program p, cl_device_id d) {
  size_t n = 0;
  if (clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n) != CL_SUCCESS || !n) {
    return "(no build log)";
  }
  std::string log(n, '\0');
  clGetProgramBuildInfo(p, d, CL_PROGRAM_BUILD_LOG, n, log.data(), nullptr);
  while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) log.pop_back();
  return log.empty() ? "(empty build log)" : log;
}

}  // namespace

ProgramHandle Context::build(const std::string& file, const std::string& options) {
  const KernelSource* src = findEmbeddedKernel(file);
  if (!src) {
    throw ClError(CL_INVALID_VALUE, "no embedded kernel file kernels_cl/" + file +
                                        ".cl (is it in kernels_cl/ and was cmake re-run?)");
  }
  cl_device_id dev = selection_.device.device;
  const std::string key = cacheKey(src->sha256, options);
  cl_int err = CL_SUCCESS;

  // 1. Cached binary.
  std::vector<unsigned char> binary = cache_.load(key);
  if (!binary.empty()) {
    const unsigned char* bin_ptr = binary.data();
    const size_t bin_len = binary.size();
    cl_int bin_status = CL_SUCCESS;
    ProgramHandle p(
        clCreateProgramWithBinary(context_.get(), 1, &dev, &bin_len, &bin_ptr, &bin_status, &err));
    if (err == CL_SUCCESS && bin_status == CL_SUCCESS &&
        clBuildProgram(p.get(), 1, &dev, options.c_str(), nullptr, nullptr) == CL_SUCCESS) {
      ++stats_.disk_hits;
      logDebug("kernels_cl/", file, ".cl: loaded from cache ", cache_.pathFor(key));
      return p;
    }
    logWarning("kernel cache entry ", cache_.pathFor(key), " for kernels_cl/", file,
               ".cl was rejected by the driver; compiling from source");
  }

  // 2. Compile from source.
  const char* text = src->source;
  ProgramHandle p(clCreateProgramWithSource(context_.get(), 1, &text, nullptr, &err));
  check(err, "clCreateProgramWithSource(kernels_cl/" + file + ".cl)");
  err = clBuildProgram(p.get(), 1, &dev, options.c_str(), nullptr, nullptr);
  if (err != CL_SUCCESS) {
    throw ClError(err, "building kernels_cl/" + file + ".cl for " + selection_.device.device_name +
                           " with options '" + options + "' failed: " + errorName(err) + " (" +
                           std::to_string(err) + ")\nbuild log:\n" + buildLog(p.get(), dev));
  }
  ++stats_.compiled;
  logDebug("kernels_cl/", file, ".cl: compiled from source");

  // 3. Store the binary.
  size_t bin_len = 0;
  if (clGetProgramInfo(p.get(), CL_PROGRAM_BINARY_SIZES, sizeof(bin_len), &bin_len, nullptr) ==
          CL_SUCCESS &&
      bin_len > 0) {
    std::vector<unsigned char> out(bin_len);
    unsigned char* out_ptr = out.data();
    if (clGetProgramInfo(p.get(), CL_PROGRAM_BINARIES, sizeof(out_ptr), &out_ptr, nullptr) ==
            CL_SUCCESS &&
        cache_.store(key, out)) {
      ++stats_.stored;
    }
  }
  return p;
}

KernelHandle Context::kernel(const std::string& file, const std::string& kernel_name,
                             const std::string& extra_options) {
  cl_program p = program(file, extra_options);
  cl_int err = CL_SUCCESS;
  KernelHandle k(clCreateKernel(p, kernel_name.c_str(), &err));
  check(err, "clCreateKernel(" + kernel_name + " in kernels_cl/" + file + ".cl)");
  return k;
}

MemHandle Context::buffer(cl_mem_flags flags, size_t bytes, const void* host) const {
  cl_int err = CL_SUCCESS;
  if (host) flags |= CL_MEM_COPY_HOST_PTR;
  MemHandle m(
      clCreateBuffer(context_.get(), flags, bytes == 0 ? 1 : bytes, const_cast<void*>(host), &err));
  check(err, "clCreateBuffer(" + std::to_string(bytes) + " bytes)");
  return m;
}

void Context::write(const MemHandle& mem, const void* host, size_t bytes, size_t offset) const {
  if (bytes == 0) return;
  EMF_CL_CHECK(clEnqueueWriteBuffer(queue_.get(), mem.get(), CL_TRUE, offset, bytes, host, 0,
                                    nullptr, nullptr));
  countHostWait();
}

void Context::read(const MemHandle& mem, void* host, size_t bytes, size_t offset) const {
  if (bytes == 0) return;
  EMF_CL_CHECK(clEnqueueReadBuffer(queue_.get(), mem.get(), CL_TRUE, offset, bytes, host, 0,
                                   nullptr, nullptr));
  countHostWait(bytes);
}

void Context::finish() const {
  EMF_CL_CHECK(clFinish(queue_.get()));
  countHostWait();
}

void enqueue(cl_command_queue q, const KernelHandle& k, size_t gx, size_t gy, size_t gz,
             size_t local_x, size_t local_y) {
  const cl_uint dims = gz ? 3 : (gy ? 2 : 1);
  size_t global[3] = {gx, gy ? gy : 1, gz ? gz : 1};
  size_t local[3] = {local_x, local_y ? local_y : 1, 1};
  const bool use_local = local_x > 0;
  if (use_local) {
    for (cl_uint i = 0; i < dims && i < 2; ++i) {
      global[i] = (global[i] + local[i] - 1) / local[i] * local[i];
    }
  }
  if (gx == 0 || (dims >= 2 && gy == 0)) return;  // nothing to do
  cl_event event = nullptr;
  const bool profile = kernelProfiling();
  const cl_int err =
      clEnqueueNDRangeKernel(q, k.get(), dims, nullptr, global, use_local ? local : nullptr, 0,
                             nullptr, profile ? &event : nullptr);
  if (err != CL_SUCCESS) check(err, "clEnqueueNDRangeKernel(" + kernelName(k.get()) + ")");
  countLaunch();
  if (profile && event) recordKernelLaunch(k.get(), event);
}

}  // namespace emf::cl
