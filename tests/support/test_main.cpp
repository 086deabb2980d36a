// main() of every gtest binary. Sets the test environment unless the caller set it:
// - XDG_CACHE_HOME inside the build tree, so tests never touch the user's kernel cache and a
//   clean build folder really starts cold;
// - EMF_LOG_LEVEL=warning, so expected info lines do not drown failures.
#include <gtest/gtest.h>

#include <cstdlib>

#include "common/log.h"

int main(int argc, char** argv) {
  setenv("XDG_CACHE_HOME", EMF_TEST_CACHE_DIR, 0);
  setenv("EMF_LOG_LEVEL", "warning", 0);
  emf::LogLevel level = emf::LogLevel::kWarning;
  if (emf::parseLogLevel(std::getenv("EMF_LOG_LEVEL"), &level)) emf::setLogLevel(level);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
