// bench/objects_bench.sh's argument handling: every bad argument stops the script before any
// run with exit code 2 and a message naming the argument (no emf run starts: these take
// milliseconds).
#include <string>

#include "test_support.h"

namespace emf {
namespace {

struct BadArguments {
  std::string args;
  std::string message;
};

// Runs the script with `args` (emf is the build tree's); its exit code and output.
int runBench(const std::string& args, std::string* log) {
  return test::runCommand("bash " + std::string(EMF_SOURCE_DIR) + "/bench/objects_bench.sh --emf " +
                              EMF_CLI_PATH + " --out " + test::tempDir("objects_bench_args") + " " +
                              args,
                          log);
}

TEST(ObjectsBench, BadArgumentsStopWithExitCode2AndSayWhy) {
  const BadArguments cases[] = {
      {"--bogus", "unknown argument '--bogus'"},
      {"--size", "--size needs a value"},
      {"--size 320", "--size 320: expected WxH"},
      {"--size 0x240", "--size 0x240: expected WxH"},
      {"--timing --sizes 640x480,big", "--sizes: 'big' is not WxH"},
      {"--frames 0", "--frames 0: expected a positive integer"},
      {"--frames -5", "--frames -5: expected a positive integer"},
      {"--presets ,", "--presets names no preset"},
      {"--presets foo", "unknown preset 'foo': valid presets are room, cars, occlusion, enter"},
  };
  for (const BadArguments& c : cases) {
    std::string log;
    EXPECT_EQ(runBench(c.args, &log), 2) << c.args << ": " << log;
    EXPECT_NE(log.find(c.message), std::string::npos) << c.args << ": " << log;
  }
}

TEST(ObjectsBench, AMissingEmfBinaryIsNamed) {
  std::string log;
  const int code = test::runCommand("bash " + std::string(EMF_SOURCE_DIR) +
                                        "/bench/objects_bench.sh --emf /nonexistent/emf --out " +
                                        test::tempDir("objects_bench_args"),
                                    &log);
  EXPECT_EQ(code, 2) << log;
  EXPECT_NE(log.find("no emf binary at /nonexistent/emf (build first or pass --emf)"),
            std::string::npos)
      << log;
}

}  // namespace
}  // namespace emf
