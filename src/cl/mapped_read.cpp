#include "cl/mapped_read.h"

#include "cl/cl_error.h"
#include "cl/context.h"
#include "cl/work_counters.h"
#include "common/log.h"

namespace emf::cl {

MappedRead::MappedRead(const Context& ctx, const MemHandle& mem, size_t bytes, size_t offset)
    : ctx_(ctx), mem_(mem), bytes_(bytes) {
  if (bytes == 0) return;
  cl_int err = CL_SUCCESS;
  ptr_ = clEnqueueMapBuffer(ctx.queue(), mem.get(), CL_TRUE, CL_MAP_READ, offset, bytes, 0, nullptr,
                            nullptr, &err);
  check(err, "clEnqueueMapBuffer(" + std::to_string(bytes) + " bytes, read)");
  countHostWait(bytes);
}

MappedRead::~MappedRead() {
  if (!ptr_) return;
  // A destructor cannot throw: a failed unmap is logged (the buffer stays mapped until it is
  // released, which the next write to it would wait for or fail on).
  cl_int err = clEnqueueUnmapMemObject(ctx_.queue(), mem_.get(), ptr_, 0, nullptr, nullptr);
  if (err == CL_SUCCESS) err = clFinish(ctx_.queue());
  countHostWait();
  if (err != CL_SUCCESS) {
    logWarning("clEnqueueUnmapMemObject failed: ", errorName(err));
  }
}

}  // namespace emf::cl
