// OpenCL sources embedded at build time from kernels_cl/*.cl (cmake/EmfKernels.cmake).
#pragma once

#include <string>
#include <vector>

namespace emf::cl {

struct KernelSource {
  const char* name;    // file name without .cl, e.g. "image_scale"
  const char* source;  // preprocessed text (.clh includes inlined)
  const char* sha256;  // of `source`; part of the program cache key
};

/// Every embedded kernel file.
const std::vector<const KernelSource*>& embeddedKernels();
/// The kernel file `name` (without .cl), or nullptr.
const KernelSource* findEmbeddedKernel(const std::string& name);

}  // namespace emf::cl
