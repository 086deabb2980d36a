// Names of the public emf_status codes (shared by the C API and the plugin host).
#pragma once

#include "emf/emf_types.h"

namespace emf {

/// "EMF_ERROR_CONFIG" etc.; "EMF_STATUS_UNKNOWN" for values not in emf_types.h.
const char* statusName(emf_status status);

}  // namespace emf
