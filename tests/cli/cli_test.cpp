// The `emf` command line: exit codes, --help for every subcommand, `emf info`.
#include "test_support.h"

namespace emf {
namespace {

std::string cli() { return std::string(EMF_CLI_PATH); }

TEST(Cli, NoArgumentsIsUsageError) {
  std::string out;
  EXPECT_EQ(test::runCommand(cli(), &out), 2);
  EXPECT_NE(out.find("usage: emf <command>"), std::string::npos) << out;
}

TEST(Cli, UnknownSubcommandIsUsageErrorWithSuggestion) {
  std::string out;
  EXPECT_EQ(test::runCommand(cli() + " inof", &out), 2);
  EXPECT_NE(out.find("unknown command 'inof'"), std::string::npos) << out;
  EXPECT_NE(out.find("did you mean 'info'"), std::string::npos) << out;
}

TEST(Cli, UnknownFlagIsUsageError) {
  std::string out;
  EXPECT_EQ(test::runCommand(cli() + " info --colour", &out), 2);
  EXPECT_NE(out.find("unknown option --colour"), std::string::npos) << out;
  EXPECT_NE(out.find("usage: emf info"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(cli() + " info --config", &out), 2);
  EXPECT_NE(out.find("--config needs a value"), std::string::npos) << out;
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const char* c : {"info", "version", "config"}) {
    std::string out;
    EXPECT_EQ(test::runCommand(cli() + " " + c + " --help", &out), 0) << c;
    EXPECT_NE(out.find(std::string("usage: emf ") + c), std::string::npos) << out;
  }
  std::string out;
  EXPECT_EQ(test::runCommand(cli() + " --help", &out), 0);
}

TEST(Cli, Version) {
  std::string out;
  EXPECT_EQ(test::runCommand(cli() + " version", &out), 0);
  EXPECT_EQ(out, "emf 0.1.0\n");
}

TEST(Cli, InfoListsSelectedDeviceAndReusesKernelCache) {
  const std::string cache = test::tempDir("cli-cache");
  const std::string cmd = cli() + " info --set cl.cache_dir=" + cache;
  std::string first, second;
  ASSERT_EQ(test::runCommand(cmd, &first), 0) << first;
  EXPECT_NE(first.find("selected: "), std::string::npos) << first;
  EXPECT_NE(first.find("  * "), std::string::npos) << first;
  EXPECT_NE(first.find("plugin search path:"), std::string::npos) << first;
  EXPECT_NE(first.find("0 loaded from cache"), std::string::npos) << first;
  ASSERT_EQ(test::runCommand(cmd, &second), 0) << second;
  EXPECT_NE(second.find(" 0 compiled from source"), std::string::npos) << second;
  if (cl::listDevices().size() == 1) {
    EXPECT_NE(first.find("Portable Computing Language"), std::string::npos) << first;
  }
}

TEST(Cli, ConfigErrorsExitOneWithMessage) {
  std::string out;
  EXPECT_EQ(test::runCommand(cli() + " config --set em.alpha=3", &out), 1);
  EXPECT_NE(out.find("em.alpha: value 3 is out of range [0, 1]"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(cli() + " config --list", &out), 0);
  EXPECT_NE(out.find("map.memory_mb"), std::string::npos) << out;
}

}  // namespace
}  // namespace emf
