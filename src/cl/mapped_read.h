// Read-only host access to part of a device buffer by mapping it (clEnqueueMapBuffer), for
// devices whose memory is the host's (CPU devices such as PoCL, integrated GPUs): there the
// mapping is usually the buffer's own memory, so reading a large buffer costs no copy.
#pragma once

#include <cstddef>

#include "cl/cl_handle.h"

namespace emf::cl {

class Context;

class MappedRead {
 public:
  /// Maps `bytes` of `mem` from `offset` for reading (blocking: earlier work on the queue is
  /// done). Throws ClError naming the call on failure.
  MappedRead(const Context& ctx, const MemHandle& mem, size_t bytes, size_t offset = 0);
  /// Unmaps (waits for the unmap, so the buffer may be written right after).
  ~MappedRead();
  MappedRead(const MappedRead&) = delete;
  MappedRead& operator=(const MappedRead&) = delete;

  const void* data() const { return ptr_; }
  size_t bytes() const { return bytes_; }

 private:
  const Context& ctx_;
  MemHandle mem_;
  void* ptr_ = nullptr;
  size_t bytes_ = 0;
};

}  // namespace emf::cl
