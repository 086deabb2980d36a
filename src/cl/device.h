// OpenCL platform/device enumeration and selection from ClOptions.
#pragma once

#include <CL/cl.h>

#include <cstdint>
#include <string>
#include <vector>

#include "cl/cl_options.h"

namespace emf::cl {

struct DeviceInfo {
  cl_platform_id platform = nullptr;
  cl_device_id device = nullptr;
  std::string platform_name;
  std::string platform_version;
  std::string device_name;
  std::string device_version;
  std::string driver_version;
  std::string type;  // cpu, gpu, accelerator, other
  uint32_t compute_units = 0;
  uint64_t global_mem_bytes = 0;
  uint64_t max_alloc_bytes = 0;
  size_t max_work_group_size = 0;
  bool is_pocl = false;
  /// CL_DEVICE_HOST_UNIFIED_MEMORY: the device's memory is the host's (CPU devices, most
  /// integrated GPUs). On a CPU device mapping a buffer for reading does not copy it.
  bool host_unified_memory = false;
  /// CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT / _INT: lanes of the device's SIMD units (PoCL CPU:
  /// 16 floats with AVX-512, 8 with AVX2, 4 with NEON or SSE).
  uint32_t native_vector_width_float = 0;
  uint32_t native_vector_width_int = 0;

  /// PoCL CPU devices: the target their kernels are compiled for, from PoCL's version string
  /// ("... HSTR: pthread-x86_64-pc-linux-gnu-skylake-avx512" -> "x86_64-pc-linux-gnu-skylake-
  /// avx512"), else from the device name ("pthread-haswell-AMD EPYC ..." -> "haswell").
  /// Empty for other devices.
  std::string poclTarget() const;
  /// "<name> [cpu] on <platform> (<version>, driver .., N compute units, M MiB, target ..,
  /// native vector width float F int I)": what the benches print with their figures.
  std::string describe() const;
};

/// All devices of all platforms, in platform then device order. Empty if there is no OpenCL
/// platform (no ICD installed).
std::vector<DeviceInfo> listDevices();

/// What to do when listDevices() is empty: install an ICD, or, when PoCL's ICD is installed but
/// PoCL cannot create its kernel cache folder (it then reports no platform), make that folder
/// writable.
std::string noDeviceAdvice();

struct DeviceSelection {
  DeviceInfo device;
  /// Why this device: "matches cl.device='...'" or "fallback: ..." (for `emf info` and logs).
  std::string reason;
  bool fallback = false;
};

/// Picks the first device matching platform/device substrings and type; if none matches, falls
/// back to PoCL's CPU device (then any CPU, then the first device) with a warning in `reason`.
/// Throws ClError if there is no OpenCL device at all, saying which package to install.
DeviceSelection selectDevice(const ClOptions& options);

}  // namespace emf::cl
