// The exception firewall of the C API: every emf_* function body runs inside guard(), which
// maps C++ exceptions to emf_status and stores the message in the thread-local last error.
#pragma once

#include <string>

#include "emf/emf.h"

namespace emf::capi {

/// Records `message` as this thread's last error and returns `status`.
emf_status fail(emf_status status, const std::string& message);
/// Clears this thread's last error (called on entry of every API function).
void clearError();
/// Maps the current exception (inside a catch block) to a status + message.
emf_status translateCurrentException(const char* function);

/// Runs `body` (returning emf_status) with all exceptions translated.
template <typename F>
emf_status guard(const char* function, F&& body) noexcept {
  try {
    clearError();
    return body();
  } catch (...) {
    return translateCurrentException(function);
  }
}

/// Checks a caller struct: non-NULL and struct_size at least the size of the fields we read
/// (`min_size`). Returns EMF_OK or an error naming the struct.
emf_status checkStruct(const void* ptr, size_t struct_size, size_t min_size, const char* name,
                       const char* function);

}  // namespace emf::capi
