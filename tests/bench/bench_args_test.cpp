// bench/bench_args.h and the bench/ programs' argument handling: a bad number, an out-of-range
// value, a missing value or an unknown option stops a program before any work with exit code 2
// and a message naming the option; --help prints the usage and exits with 0. (Before, atoi
// turned `synth_bench --frames abc` into 0 frames and a run that never ended, detector_bench
// ignored unknown options, and map_bench died with "stoi".)
#include "bench_args.h"

#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.h"

namespace emf {
namespace {

using bench::ArgWalker;
using bench::parseInteger;
using bench::parseReal;
using bench::UsageError;

/// The message of the UsageError `f` throws ("" when it throws none).
template <typename F>
std::string usageMessage(F f) {
  try {
    f();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(BenchArgs, IntegersMustBeWholeAndInRange) {
  EXPECT_EQ(parseInteger("--frames", "12", 1, 100), 12);
  EXPECT_EQ(parseInteger("--frames", "-3", -5, 5), -3);
  EXPECT_EQ(parseInteger("--frames", "100", 1, 100), 100);
  for (const char* bad : {"", "abc", "12x", "1.5", "1e3", "0", "101", "99999999999999999999"}) {
    EXPECT_EQ(usageMessage([&] { parseInteger("--frames", bad, 1, 100); }),
              "--frames '" + std::string(bad) + "': expected an integer in [1, 100]")
        << bad;
  }
}

TEST(BenchArgs, RealsMustBeFiniteAndInRange) {
  EXPECT_DOUBLE_EQ(parseReal("--ms", "2.5", 0.0, 10.0), 2.5);
  EXPECT_DOUBLE_EQ(parseReal("--ms", "1e1", 0.0, 10.0), 10.0);
  for (const char* bad : {"", "x", "2.5ms", "nan", "inf", "-0.5", "10.5", "1e400"}) {
    const std::string message = usageMessage([&] { parseReal("--ms", bad, 0.0, 10.0); });
    EXPECT_EQ(message.rfind("--ms '" + std::string(bad) + "': expected a number in [0", 0), 0u)
        << bad << ": " << message;
  }
}

TEST(BenchArgs, TheWalkerTakesValuesAndNamesWhatIsWrong) {
  std::vector<std::string> words = {"prog", "--frames", "7", "--quick", "--ms", "0.25", "extra"};
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  ArgWalker args(static_cast<int>(argv.size()), argv.data());
  ASSERT_TRUE(args.next());
  ASSERT_TRUE(args.is("--frames"));
  EXPECT_EQ(args.integer(1, 10), 7);
  ASSERT_TRUE(args.next());
  EXPECT_TRUE(args.is("--quick"));
  ASSERT_TRUE(args.next());
  EXPECT_DOUBLE_EQ(args.real(0.0, 1.0), 0.25);
  ASSERT_TRUE(args.next());
  EXPECT_EQ(args.current(), "extra");
  EXPECT_EQ(usageMessage([&] { args.unknown(); }), "unknown option 'extra'");
  EXPECT_EQ(usageMessage([&] { args.value(); }), "extra needs a value");
  EXPECT_FALSE(args.next());
}

/// name -> path of the bench programs this build has (EMF_BENCH_PROGRAMS, "name=path,...").
std::map<std::string, std::string> programs() {
  std::map<std::string, std::string> out;
  std::stringstream list(EMF_BENCH_PROGRAMS);
  for (std::string item; std::getline(list, item, ',');) {
    const size_t eq = item.find('=');
    if (eq != std::string::npos) out[item.substr(0, eq)] = item.substr(eq + 1);
  }
  return out;
}

struct Case {
  std::string program, args, message;
};

TEST(BenchPrograms, BadArgumentsStopWithExitCode2AndNameTheOption) {
  const std::map<std::string, std::string> paths = programs();
  ASSERT_GE(paths.size(), 6u) << EMF_BENCH_PROGRAMS;
  const std::vector<Case> cases = {
      {"synth_bench", "--frames abc", "--frames 'abc': expected an integer in [1, 1000000]"},
      {"synth_bench", "--frames 0", "--frames '0': expected an integer in [1, 1000000]"},
      {"synth_bench", "--width", "--width needs a value"},
      {"synth_bench", "--bogus", "unknown option '--bogus'"},
      {"synth_bench", "kitchen", "unknown preset 'kitchen' (presets: room, cars, occlusion"},
      {"detector_bench", "--frames x", "--frames 'x': expected an integer in [1, 1000000]"},
      {"detector_bench", "--bogus 3", "unknown option '--bogus'"},
      {"detector_bench", "--slam-ms nan", "--slam-ms 'nan': expected a number in [0"},
      {"detector_bench", "--out", "--out needs a value"},
      {"map_bench", "--frames abc", "--frames 'abc': expected an integer in [0, 1000000]"},
      {"map_bench", "--depth-scale -1", "--depth-scale '-1': expected a number in ["},
      {"map_bench", "--memory-mb", "--memory-mb needs a value"},
      {"track_bench", "--trials 0", "--trials '0': expected an integer in [1, 100000]"},
      {"track_bench", "--data", "--data needs a value"},
      {"track_bench", "--fast", "unknown option '--fast'"},
      {"track_bias", "--frames 1.5 --data x", "--frames '1.5': expected an integer in [0"},
      {"track_bias", "--depth-scale big", "--depth-scale 'big': expected a number in [0"},
      {"track_bias", "--reverse", "--data DIR is required"},
      {"track_bias", "--object 0 --data x", "--object '0': expected an integer in [1, 65535]"},
      {"track_bias", "--data x --fuse-tracked --prefuse", "--fuse-tracked excludes --prefuse"},
      {"slam_bench", "--frames 1", "--frames '1': expected an integer in [2, 100000]"},
      {"slam_bench", "--res 1024", "--res '1024': use 640 (640x480@1cm) or 320"},
      {"slam_bench", "--peer-stride 0", "--peer-stride '0': expected an integer in [1, 64]"},
      {"slam_bench", "--no-pear", "unknown option '--no-pear'"},
      {"objects_scaling", "--counts 0,9", "--counts '9': expected an integer in [0, 8]"},
      {"objects_scaling", "--frames 50 --warmup 50", "--warmup must be below --frames"},
      {"objects_scaling", "--det-every 0", "--det-every '0': expected an integer in [1, 100000]"},
      {"isolation_bench", "--width 10", "--width '10': expected an integer in [64, 4096]"},
      {"dnn_bench", "--instances 21", "--instances '21': expected an integer in [1, 20]"},
      {"dnn_bench", "--depth 640x", "--depth '640x': expected WxH"},
      {"detector_share", "--frames 10", "--frames '10': expected an integer in [30, 100000]"},
      {"detector_share", "--size 640", "--size '640': expected WxH"},
      {"detector_share", "--rate -1", "--rate '-1': expected a number in [0"},
  };
  for (const Case& c : cases) {
    const auto it = paths.find(c.program);
    if (it == paths.end()) {
      ASSERT_TRUE(c.program == "dnn_bench" || c.program == "detector_share")
          << "not built: " << c.program;
      continue;  // the dnn plugin (and its benches) is optional
    }
    std::string log;
    EXPECT_EQ(test::runCommand(it->second + " " + c.args, &log), 2)
        << c.program << " " << c.args << ": " << log;
    EXPECT_NE(log.find(c.program + ": " + c.message), std::string::npos)
        << c.program << " " << c.args << ": " << log;
  }
}

TEST(BenchPrograms, HelpPrintsTheUsageAndSucceeds) {
  for (const auto& [name, path] : programs()) {
    std::string log;
    EXPECT_EQ(test::runCommand(path + " --help", &log), 0) << name << ": " << log;
    EXPECT_NE(log.find("usage: " + name), std::string::npos) << name << ": " << log;
  }
}

}  // namespace
}  // namespace emf
