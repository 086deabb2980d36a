#include "capi/firewall.h"

#include <exception>
#include <new>

#include "cl/cl_error.h"
#include "common/error.h"
#include "common/status_name.h"
#include "firmware_host/sensor_error.h"
#include "pipeline/detector_plugin.h"

namespace emf::capi {
namespace {
thread_local std::string t_last_error;
}

emf_status fail(emf_status status, const std::string& message) {
  t_last_error = message;
  return status;
}

void clearError() { t_last_error.clear(); }

const char* lastError() { return t_last_error.c_str(); }

const char* lastError();

emf_status translateCurrentException(const char* function) {
  const std::string where = std::string(function) + ": ";
  try {
    throw;
  } catch (const ConfigError& e) {
    return fail(EMF_ERROR_CONFIG, where + e.what());
  } catch (const fw::SensorDisconnected& e) {
    return fail(EMF_ERROR_DEVICE, where + e.what());
  } catch (const IoError& e) {
    return fail(EMF_ERROR_IO, where + e.what());
  } catch (const cl::ClError& e) {
    return fail(e.code() == CL_MEM_OBJECT_ALLOCATION_FAILURE || e.code() == CL_OUT_OF_HOST_MEMORY
                    ? EMF_ERROR_OUT_OF_MEMORY
                    : EMF_ERROR_OPENCL,
                where + e.what());
  } catch (const InvalidArgument& e) {
    return fail(EMF_ERROR_INVALID_ARGUMENT, where + e.what());
  } catch (const StateError& e) {
    return fail(EMF_ERROR_STATE, where + e.what());
  } catch (const NotFoundError& e) {
    return fail(EMF_ERROR_NOT_FOUND, where + e.what());
  } catch (const ResourceError& e) {
    return fail(EMF_ERROR_OUT_OF_MEMORY, where + e.what());
  } catch (const pipeline::PluginError& e) {
    return fail(e.status(), where + e.what());
  } catch (const Error& e) {
    return fail(EMF_ERROR_INTERNAL, where + e.what());
  } catch (const std::bad_alloc&) {
    return fail(EMF_ERROR_OUT_OF_MEMORY, where + "out of host memory");
  } catch (const std::exception& e) {
    return fail(EMF_ERROR_INTERNAL, where + "internal error: " + e.what());
  } catch (...) {
    return fail(EMF_ERROR_INTERNAL, where + "internal error: unknown exception");
  }
}

emf_status checkStruct(const void* ptr, size_t struct_size, size_t min_size, const char* name,
                       const char* function) {
  if (!ptr)
    return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + name + " is NULL");
  if (struct_size < min_size) {
    return fail(EMF_ERROR_INVALID_ARGUMENT, std::string(function) + ": " + name +
                                                "->struct_size is " + std::to_string(struct_size) +
                                                ", expected at least " + std::to_string(min_size) +
                                                " (set it to sizeof(" + name + "))");
  }
  return EMF_OK;
}

}  // namespace emf::capi

extern "C" {

EMF_API const char* emf_last_error_message(void) { return emf::capi::lastError(); }

EMF_API const char* emf_status_string(emf_status status) { return emf::statusName(status); }

EMF_API uint32_t emf_version(void) { return EMF_VERSION; }

EMF_API const char* emf_version_string(void) {
#define EMF_STR2(x) #x
#define EMF_STR(x) EMF_STR2(x)
  return EMF_STR(EMF_VERSION_MAJOR) "." EMF_STR(EMF_VERSION_MINOR) "." EMF_STR(EMF_VERSION_PATCH);
#undef EMF_STR
#undef EMF_STR2
}

}  // extern "C"
