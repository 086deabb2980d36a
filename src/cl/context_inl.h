// Template definitions for cl/context.h.
#pragma once

#include <string>
#include <type_traits>

#include "cl/cl_error.h"

namespace emf::cl {

std::string kernelName(cl_kernel k);

template <typename T>
void setArg(const KernelHandle& k, cl_uint index, const T& value) {
  static_assert(std::is_trivially_copyable_v<T>, "kernel arguments must be trivially copyable");
  const cl_int err = clSetKernelArg(k.get(), index, sizeof(T), &value);
  if (err != CL_SUCCESS) {
    check(err, "clSetKernelArg(" + kernelName(k.get()) + ", arg " + std::to_string(index) + ")");
  }
}

template <>
inline void setArg<MemHandle>(const KernelHandle& k, cl_uint index, const MemHandle& value) {
  cl_mem m = value.get();
  setArg(k, index, m);
}

}  // namespace emf::cl
