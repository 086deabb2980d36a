// Shared test helpers: data paths, OpenCL fixtures and assertion macros.
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "cl/cl_error.h"
#include "cl/context.h"
#include "core/frame.h"

namespace emf::test {

/// Vec(x, y, z) from three calls of `draw`, z first, one per statement. The arguments of one
/// call are evaluated in an unspecified order (GCC: right to left on x86-64, left to right on
/// aarch64), so `Vec(u(rng), u(rng), u(rng))` is a different case on each platform; z first
/// keeps the cases the tests were written against on x86-64.
template <typename Vec, typename Draw>
Vec drawXyz(Draw&& draw) {
  const auto z = draw();
  const auto y = draw();
  const auto x = draw();
  return Vec(x, y, z);
}

/// ../shared/data/<name> (or $EMF_DATA_DIR/<name>). Fails the test when it does not exist.
std::string dataPath(const std::string& name);
/// A fresh empty temporary folder, removed at process exit.
std::string tempDir(const std::string& tag);
/// An 80x60 pinhole camera (fx = fy = 80, principal point at the centre) for tests that need
/// only a small frame size.
core::Intrinsics camera80x60();

/// The whole file as text ("" when it cannot be read).
std::string readText(const std::string& path);
/// Runs a shell command, returns its exit code and puts stdout+stderr into *output.
int runCommand(const std::string& command, std::string* output);

/// A test with an OpenCL context on the selected device (PoCL CPU in CI). Shared across the
/// tests of one process; never skipped: a missing device is a failure. $EMF_TEST_LANES, when
/// set, is its cl.lanes (4, 8 or 16).
class WithClContext : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  cl::Context& ctx() { return *ctx_; }
  cl_context context() { return ctx_->context(); }

  static std::unique_ptr<cl::Context> ctx_;
};

/// WithClContext plus its queue.
class WithClQueue : public WithClContext {
 protected:
  cl_command_queue queue() { return ctx_->queue(); }
};

}  // namespace emf::test

/// Asserts that an OpenCL call returned CL_SUCCESS, printing the error's name otherwise.
#define ASSERT_CL_SUCCESS(expr)                                                              \
  do {                                                                                       \
    const cl_int emf_cl_err_ = (expr);                                                       \
    ASSERT_EQ(emf_cl_err_, CL_SUCCESS)                                                       \
        << #expr << " returned " << ::emf::cl::errorName(emf_cl_err_) << " (" << emf_cl_err_ \
        << ")";                                                                              \
  } while (0)

#define EXPECT_CL_SUCCESS(expr)                                                              \
  do {                                                                                       \
    const cl_int emf_cl_err_ = (expr);                                                       \
    EXPECT_EQ(emf_cl_err_, CL_SUCCESS)                                                       \
        << #expr << " returned " << ::emf::cl::errorName(emf_cl_err_) << " (" << emf_cl_err_ \
        << ")";                                                                              \
  } while (0)
