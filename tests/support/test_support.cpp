#include "test_support.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

namespace emf::test {
namespace fs = std::filesystem;

std::unique_ptr<cl::Context> WithClContext::ctx_;

std::string dataPath(const std::string& name) {
  const char* env = std::getenv("EMF_DATA_DIR");
  const fs::path root = env && *env ? fs::path(env) : fs::path(EMF_SHARED_DATA_DIR);
  const fs::path p = root / name;
  if (!fs::exists(p)) {
    ADD_FAILURE() << "test data " << p
                  << " not found: tests read ../shared/data beside the repository "
                     "(or set EMF_DATA_DIR)";
  }
  return p.string();
}

namespace {
struct TempDirs {
  std::vector<fs::path> dirs;
  ~TempDirs() {
    std::error_code ec;
    for (const auto& d : dirs) fs::remove_all(d, ec);
  }
};
TempDirs& tempDirs() {
  static TempDirs t;
  return t;
}
}  // namespace

std::string tempDir(const std::string& tag) {
  std::random_device rd;
  const fs::path p = fs::temp_directory_path() /
                     ("emf-test-" + tag + "-" + std::to_string(rd()) + std::to_string(rd()));
  fs::create_directories(p);
  tempDirs().dirs.push_back(p);
  return p.string();
}

core::Intrinsics camera80x60() {
  core::Intrinsics k;
  k.fx = k.fy = 80;
  k.cx = 39.5;
  k.cy = 29.5;
  k.width = 80;
  k.height = 60;
  return k;
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

int runCommand(const std::string& command, std::string* output) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  char buf[4096];
  std::string out;
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0) out.append(buf, n);
  const int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void WithClContext::SetUpTestSuite() {
  if (ctx_) return;
  cl::ClOptions options;
  // The lanes-N kernel tests (tests/CMakeLists.txt) run the kernels at every width.
  if (const char* lanes = std::getenv("EMF_TEST_LANES")) options.lanes = lanes;
  ctx_ = std::make_unique<cl::Context>(options);
}

void WithClContext::TearDownTestSuite() {}

}  // namespace emf::test
