// Options of the OpenCL runtime (section `cl`).
#pragma once

#include <string>

#include "common/option_binder.h"

namespace emf::cl {

enum class DeviceType { kAny, kCpu, kGpu, kAccelerator };
/// The key texts, which are also the device types DeviceInfo::type names.
inline const ChoiceNames<DeviceType>& deviceTypeNames() {
  static const ChoiceNames<DeviceType> names = {{DeviceType::kAny, "any"},
                                                {DeviceType::kCpu, "cpu"},
                                                {DeviceType::kGpu, "gpu"},
                                                {DeviceType::kAccelerator, "accelerator"}};
  return names;
}

struct ClOptions {
  /// Substring of the platform name to prefer ("" = any), case-insensitive.
  std::string platform;
  /// Substring of the device name to prefer ("" = any), case-insensitive.
  std::string device;
  /// Device type to prefer.
  DeviceType device_type = DeviceType::kAny;
  /// Directory of the compiled-program cache ("" = $XDG_CACHE_HOME/emf/kernels or
  /// ~/.cache/emf/kernels).
  std::string cache_dir;
  /// Disable the on-disk program cache (always compile from source).
  bool disable_cache = false;
  /// Extra options passed to clBuildProgram for every program.
  std::string build_options;
  /// Pixels (voxels) per work item of the explicit-SIMD kernels (kernels_cl/common.clh, EMF_W):
  /// "16", "8" or "4". 16 on every device by default: as fast as 8 on an AVX2 CPU, and the same
  /// results on every x86 CPU (the compiler fuses multiply-adds per vector width, so another
  /// width rounds differently); 8 or 4 for a device whose registers 16 lanes overfill.
  std::string lanes = "16";

  void bind(OptionBinder& b) {
    b.text("platform", platform, "platform name substring to prefer, case-insensitive");
    b.text("device", device, "device name substring to prefer, case-insensitive");
    b.choice("device_type", device_type, deviceTypeNames(), "device type to prefer");
    b.text("cache_dir", cache_dir, "compiled-kernel cache folder");
    b.boolean("disable_cache", disable_cache, "always compile kernels from source");
    b.text("build_options", build_options, "extra clBuildProgram options");
    b.choice("lanes", lanes, {"4", "8", "16"}, "pixels per work item of the SIMD kernels");
  }
};

}  // namespace emf::cl
