#include "cl/device.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "cl/cl_error.h"
#include "common/log.h"

namespace emf::cl {
namespace {

std::string platformString(cl_platform_id p, cl_platform_info what) {
  size_t n = 0;
  if (clGetPlatformInfo(p, what, 0, nullptr, &n) != CL_SUCCESS || n == 0) return "";
  std::string s(n, '\0');
  clGetPlatformInfo(p, what, n, s.data(), nullptr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

std::string deviceString(cl_device_id d, cl_device_info what) {
  size_t n = 0;
  if (clGetDeviceInfo(d, what, 0, nullptr, &n) != CL_SUCCESS || n == 0) return "";
  std::string s(n, '\0');
  clGetDeviceInfo(d, what, n, s.data(), nullptr);
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

template <typename T>
T deviceValue(cl_device_id d, cl_device_info what) {
  T v{};
  clGetDeviceInfo(d, what, sizeof(T), &v, nullptr);
  return v;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool contains(const std::string& haystack, const std::string& needle) {
  return needle.empty() || lower(haystack).find(lower(needle)) != std::string::npos;
}

}  // namespace

std::string DeviceInfo::poclTarget() const {
  if (!is_pocl || type != "cpu") return "";
  // PoCL's version string names the target: "OpenCL 3.0 PoCL HSTR: <driver>-<triple>-<cpu>".
  const std::string hstr = "HSTR: ";
  const size_t at = device_version.find(hstr);
  if (at != std::string::npos) {
    const size_t from = device_version.find('-', at) + 1;  // after "pthread-" / "cpu-"
    const size_t end = device_version.find(' ', from);
    return device_version.substr(from, end == std::string::npos ? end : end - from);
  }
  // Otherwise the device name, "<driver>-<llvm cpu>-<cpu brand>": the brand is the first word
  // followed by a space or "(R)"; LLVM CPU names have neither (but may have '-').
  const size_t driver_end = device_name.find('-');
  if (driver_end == std::string::npos) return "";
  const size_t word_end = device_name.find_first_of(" (", driver_end + 1);
  const size_t brand = device_name.rfind('-', word_end);
  if (brand == std::string::npos || brand <= driver_end) return device_name.substr(driver_end + 1);
  return device_name.substr(driver_end + 1, brand - driver_end - 1);
}

std::string DeviceInfo::describe() const {
  std::ostringstream os;
  os << device_name << " [" << type << "] on " << platform_name << " (" << device_version
     << ", driver " << driver_version << ", " << compute_units << " compute units, "
     << (global_mem_bytes >> 20) << " MiB";
  const std::string target = poclTarget();
  if (!target.empty()) os << ", target " << target;
  os << ", native vector width float " << native_vector_width_float << " int "
     << native_vector_width_int << ")";
  return os.str();
}

std::vector<DeviceInfo> listDevices() {
  std::vector<DeviceInfo> out;
  cl_uint num_platforms = 0;
  if (clGetPlatformIDs(0, nullptr, &num_platforms) != CL_SUCCESS || num_platforms == 0) {
    return out;
  }
  std::vector<cl_platform_id> platforms(num_platforms);
  clGetPlatformIDs(num_platforms, platforms.data(), nullptr);
  for (cl_platform_id p : platforms) {
    cl_uint num_devices = 0;
    if (clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &num_devices) != CL_SUCCESS) continue;
    std::vector<cl_device_id> devices(num_devices);
    clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, num_devices, devices.data(), nullptr);
    for (cl_device_id d : devices) {
      DeviceInfo info;
      info.platform = p;
      info.device = d;
      info.platform_name = platformString(p, CL_PLATFORM_NAME);
      info.platform_version = platformString(p, CL_PLATFORM_VERSION);
      info.device_name = deviceString(d, CL_DEVICE_NAME);
      info.device_version = deviceString(d, CL_DEVICE_VERSION);
      info.driver_version = deviceString(d, CL_DRIVER_VERSION);
      const auto type = deviceValue<cl_device_type>(d, CL_DEVICE_TYPE);
      info.type = (type & CL_DEVICE_TYPE_GPU)           ? "gpu"
                  : (type & CL_DEVICE_TYPE_CPU)         ? "cpu"
                  : (type & CL_DEVICE_TYPE_ACCELERATOR) ? "accelerator"
                                                        : "other";
      info.compute_units = deviceValue<cl_uint>(d, CL_DEVICE_MAX_COMPUTE_UNITS);
      info.global_mem_bytes = deviceValue<cl_ulong>(d, CL_DEVICE_GLOBAL_MEM_SIZE);
      info.max_alloc_bytes = deviceValue<cl_ulong>(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE);
      info.max_work_group_size = deviceValue<size_t>(d, CL_DEVICE_MAX_WORK_GROUP_SIZE);
      info.host_unified_memory = deviceValue<cl_bool>(d, CL_DEVICE_HOST_UNIFIED_MEMORY) == CL_TRUE;
      info.native_vector_width_float = deviceValue<cl_uint>(d, CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT);
      info.native_vector_width_int = deviceValue<cl_uint>(d, CL_DEVICE_NATIVE_VECTOR_WIDTH_INT);
      info.is_pocl = contains(info.platform_name, "portable computing language") ||
                     contains(info.platform_name, "pocl");
      out.push_back(info);
    }
  }
  return out;
}

std::string noDeviceAdvice() {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists("/etc/OpenCL/vendors/pocl.icd", ec)) {
    // PoCL's cache folder: POCL_CACHE_DIR, else $XDG_CACHE_HOME/pocl, else $HOME/.cache/pocl.
    std::string cache;
    if (const char* d = std::getenv("POCL_CACHE_DIR"); d && *d) {
      cache = d;
    } else if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) {
      cache = std::string(x) + "/pocl";
    } else if (const char* h = std::getenv("HOME"); h && *h) {
      cache = std::string(h) + "/.cache/pocl";
    }
    // The nearest existing folder on the way must be writable for PoCL to create the cache.
    fs::path p = cache;
    while (!p.empty() && !fs::exists(p, ec)) p = p.parent_path();
    if (cache.empty() || p.empty() || !fs::is_directory(p, ec) || ::access(p.c_str(), W_OK) != 0) {
      return "PoCL is installed but cannot create its kernel cache folder '" +
             (cache.empty() ? std::string("(HOME unset)") : cache) +
             "' and then reports no device: set POCL_CACHE_DIR (or HOME) to a writable folder";
    }
  }
  return "no ICD is installed or none reports a device; install pocl-opencl-icd (CPU device) or "
         "your GPU vendor's OpenCL driver (scripts/install_deps.sh does it)";
}

DeviceSelection selectDevice(const ClOptions& options) {
  const std::vector<DeviceInfo> devices = listDevices();
  if (devices.empty()) {
    throw ClError(CL_DEVICE_NOT_FOUND, "no OpenCL device found: " + noDeviceAdvice());
  }
  const std::string type = choiceName(options.device_type, deviceTypeNames());
  const bool has_preference = !options.platform.empty() || !options.device.empty() ||
                              options.device_type != DeviceType::kAny;
  for (const DeviceInfo& d : devices) {
    if (!contains(d.platform_name, options.platform)) continue;
    if (!contains(d.device_name, options.device)) continue;
    if (options.device_type != DeviceType::kAny && d.type != type) continue;
    DeviceSelection s;
    s.device = d;
    s.reason = has_preference ? "matches cl.platform='" + options.platform + "' cl.device='" +
                                    options.device + "' cl.device_type=" + type
                              : "first device (no preference configured)";
    return s;
  }
  // Fallback order: PoCL CPU, any CPU, first device.
  const DeviceInfo* pick = nullptr;
  std::string kind;
  for (const DeviceInfo& d : devices) {
    if (d.is_pocl && d.type == "cpu") {
      pick = &d;
      kind = "PoCL CPU device";
      break;
    }
  }
  if (!pick) {
    for (const DeviceInfo& d : devices) {
      if (d.type == "cpu") {
        pick = &d;
        kind = "first CPU device";
        break;
      }
    }
  }
  if (!pick) {
    pick = &devices.front();
    kind = "first device";
  }
  DeviceSelection s;
  s.device = *pick;
  s.fallback = true;
  s.reason = "fallback to the " + kind + ": no device matches cl.platform='" + options.platform +
             "' cl.device='" + options.device +
             "' cl.device_type=" + choiceName(options.device_type, deviceTypeNames());
  logWarning(s.reason);
  return s;
}

}  // namespace emf::cl
