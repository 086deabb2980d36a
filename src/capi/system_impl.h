// The objects behind the opaque emf_system and emf_runtime handles, and the conversions between
// the C structs and the C++ types shared by system.cpp and runtime.cpp.
#pragma once

#include <Eigen/Geometry>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "emf/emf.h"
#include "map/raycaster.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "runtime/runtime.h"

struct emf_system {
  emf::Config config;
  std::unique_ptr<emf::cl::Context> cl;
  /// Created by emf_system_set_intrinsics (or by the runtime from its source).
  std::unique_ptr<emf::pipeline::SlamSystem> slam;
  /// Created by the first emf_system_render.
  std::unique_ptr<emf::map::RayCaster> raycaster;
  /// Objects of the last processed frame (alive plus deleted in it).
  std::vector<emf::pipeline::ObjectOutcome> last_objects;
  bool has_frame = false;
  double last_timestamp = 0;
  /// Non-null when this system belongs to a runtime (emf_runtime_system): then its calls are
  /// refused while the runtime runs, and emf_system_destroy ignores it.
  const emf::runtime::Runtime* owner = nullptr;
};

namespace emf::capi {

/// Loads the configuration of a create call: defaults, then `file`, then `yaml` (either may be
/// NULL), validated.
Config loadConfig(const char* file, const char* yaml);

/// True when the caller's API version is supported by this library (same major, minor <=).
bool apiVersionSupported(uint32_t caller);

/// Throws StateError when `system` belongs to a running runtime (`function` names the call).
void requireIdle(const emf_system& system, const char* function);

emf_pose toCPose(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromCPose(const emf_pose& pose);

/// One object as the C API reports it.
emf_object_info toObjectInfo(const pipeline::ObjectOutcome& object);

/// Copies up to `capacity` of `objects` into the caller's array (stride = objects_out[0]
/// .struct_size, which must be at least sizeof(emf_object_info)) and their number into *count
/// (count may be NULL). Returns EMF_OK or an error status (message recorded).
emf_status writeObjects(const std::vector<pipeline::ObjectOutcome>& objects,
                        emf_object_info* objects_out, int32_t capacity, int32_t* count,
                        const char* function);

/// Copies `full` (a complete struct of type T) into the caller's struct, keeping its
/// struct_size and writing only the bytes that fit (callers compiled against older headers).
template <typename T>
void copyOut(const T& full, T* out) {
  const size_t caller_size = out->struct_size;
  const size_t n = caller_size < sizeof(T) ? caller_size : sizeof(T);
  std::memcpy(static_cast<void*>(out), &full, n);
  out->struct_size = caller_size;
}

}  // namespace emf::capi
