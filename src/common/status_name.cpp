#include "common/status_name.h"

namespace emf {

const char* statusName(emf_status status) {
  switch (status) {
    case EMF_OK:
      return "EMF_OK";
    case EMF_ERROR_INVALID_ARGUMENT:
      return "EMF_ERROR_INVALID_ARGUMENT";
    case EMF_ERROR_VERSION_MISMATCH:
      return "EMF_ERROR_VERSION_MISMATCH";
    case EMF_ERROR_CONFIG:
      return "EMF_ERROR_CONFIG";
    case EMF_ERROR_IO:
      return "EMF_ERROR_IO";
    case EMF_ERROR_OPENCL:
      return "EMF_ERROR_OPENCL";
    case EMF_ERROR_OUT_OF_MEMORY:
      return "EMF_ERROR_OUT_OF_MEMORY";
    case EMF_ERROR_NOT_FOUND:
      return "EMF_ERROR_NOT_FOUND";
    case EMF_ERROR_DEVICE:
      return "EMF_ERROR_DEVICE";
    case EMF_ERROR_STATE:
      return "EMF_ERROR_STATE";
    case EMF_ERROR_TIMEOUT:
      return "EMF_ERROR_TIMEOUT";
    case EMF_ERROR_END_OF_STREAM:
      return "EMF_ERROR_END_OF_STREAM";
    case EMF_ERROR_INTERNAL:
      return "EMF_ERROR_INTERNAL";
  }
  return "EMF_STATUS_UNKNOWN";
}

}  // namespace emf
