// OpenCL error codes: names, the exception type and the check macro used by every host wrapper.
#pragma once

#include <CL/cl.h>

#include <string>

#include "common/error.h"

namespace emf::cl {

/// "CL_INVALID_VALUE" for -30 etc.; "CL_UNKNOWN_ERROR" for codes not in OpenCL 1.2.
const char* errorName(cl_int code);

/// An OpenCL call failed. what() = "<call> failed: <NAME> (<code>)<context>".
class ClError : public Error {
 public:
  ClError(cl_int code, const std::string& message) : Error(message), code_(code) {}
  cl_int code() const { return code_; }

 private:
  cl_int code_;
};

/// Throws ClError if `code` is not CL_SUCCESS; `what` names the call (and object).
void check(cl_int code, const char* what);
void check(cl_int code, const std::string& what);

}  // namespace emf::cl

/// Evaluates an OpenCL call returning cl_int and throws emf::cl::ClError on failure, naming
/// the call text and the error's name.
#define EMF_CL_CHECK(call) ::emf::cl::check((call), #call)
