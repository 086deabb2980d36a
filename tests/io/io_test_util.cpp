#include "io_test_util.h"

#include <filesystem>
#include <fstream>

#include "common/error.h"

namespace emf::io::testing {

void writeText(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

std::string expectErrorContaining(const std::function<void()>& f,
                                  const std::vector<std::string>& needles) {
  try {
    f();
  } catch (const emf::Error& e) {
    const std::string msg = e.what();
    for (const auto& n : needles) {
      EXPECT_NE(msg.find(n), std::string::npos) << "message lacks '" << n << "': " << msg;
    }
    return msg;
  }
  ADD_FAILURE() << "expected an emf::Error";
  return "";
}

}  // namespace emf::io::testing
