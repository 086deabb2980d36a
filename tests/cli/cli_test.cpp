// The `emf` command line: exit codes, --help for every subcommand, `emf info`, `emf run`'s
// detector flags and its outputs (also when a run stops at a broken frame).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "io/trajectory.h"
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
  // An empty value is not "not given" (it would run the default source, all frames, ...).
  EXPECT_EQ(test::runCommand(cli() + " run --source '' --out x", &out), 2);
  EXPECT_NE(out.find("--source needs a non-empty value"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(cli() + " run --frames= --out x", &out), 2);
  EXPECT_NE(out.find("--frames needs a non-empty value"), std::string::npos) << out;
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

// ---- emf run ---------------------------------------------------------------------------------

// A tiny, fast run: 80x60 synthetic room, small pool, quiet.
const char* kTinyRun =
    " run --quiet --source 'synth:room?frames=3&width=80&height=60' --set map.memory_mb=32"
    " --set map.background_voxel_m=0.04 --set map.background_resolution=128";

using test::readText;

TEST(CliRun, UnknownDetectorListsTheFoldersSearched) {
  const std::string out_dir = test::tempDir("run-nodet") + "/out";
  std::string out;
  const int code = test::runCommand("EMF_PLUGIN_PATH=/tmp/emf-plugins-a:/tmp/emf-plugins-b " +
                                        cli() + kTinyRun + " --detector nosuch --out " + out_dir,
                                    &out);
  EXPECT_EQ(code, 1) << out;
  EXPECT_NE(out.find("emf run: error: detector plugin 'nosuch' not found"), std::string::npos)
      << out;
  EXPECT_NE(out.find("/tmp/emf-plugins-a"), std::string::npos) << out;
  EXPECT_NE(out.find("/tmp/emf-plugins-b"), std::string::npos) << out;
  EXPECT_NE(out.find(std::string(EMF_TEST_BINARY_DIR) + "/plugins"), std::string::npos) << out;
  EXPECT_NE(out.find("EMF_PLUGIN_PATH"), std::string::npos) << out;  // says what to do
  EXPECT_FALSE(std::filesystem::exists(out_dir));  // failed before anything started

  EXPECT_EQ(test::runCommand(cli() + kTinyRun + " --detector /nonexistent/libx.so --out " + out_dir,
                             &out),
            1);
  EXPECT_NE(out.find("'/nonexistent/libx.so' does not exist"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(cli() + " run --detector", &out), 2);
  EXPECT_NE(out.find("--detector needs a value"), std::string::npos) << out;
}

TEST(CliRun, HelpListsTheDetectorFlags) {
  std::string out;
  ASSERT_EQ(test::runCommand(cli() + " run --help", &out), 0);
  EXPECT_NE(out.find("--detector NAME|PATH"), std::string::npos) << out;
  EXPECT_NE(out.find("--detector-config STR"), std::string::npos) << out;
}

TEST(CliRun, WritesSummaryWithObjectsArrayAndImages) {
  const std::string dir = test::tempDir("run-ok");
  const std::string out_dir = dir + "/out";
  std::string out;
  // The plugin's configuration string reaches it intact, '=' and ',' included: the masks of
  // the same synthetic room, in a folder whose name has both.
  ASSERT_EQ(
      test::runCommand(
          cli() + " synth room --frames 3 --width 80 --height 60 --out " + dir + "/seq,y=1", &out),
      0)
      << out;
  ASSERT_EQ(test::runCommand(cli() + kTinyRun + " --detector maskfile --detector-config dir=" +
                                 dir + "/seq,y=1 --set output.write_images=true --out " + out_dir,
                             &out),
            0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(readText(out_dir + "/run.json"));
  EXPECT_EQ(j["frames"], 3);
  ASSERT_TRUE(j.contains("objects")) << j.dump(2);
  EXPECT_TRUE(j["objects"].is_array());
  EXPECT_FALSE(j.contains("error"));
  EXPECT_EQ(io::readTrajectory(out_dir + "/camera.txt").size(), 3u);
  // The static room has no objects: the overlay is the colour image, one per frame, 80x60.
  for (const char* name : {"000000", "000001", "000002"}) {
    EXPECT_TRUE(std::filesystem::exists(out_dir + "/images/" + name + "-objects.png")) << name;
  }
}

TEST(CliRun, BrokenFrameKeepsTheOutputsOfTheFramesBefore) {
  const std::string dir = test::tempDir("run-broken");
  std::string out;
  ASSERT_EQ(
      test::runCommand(
          cli() + " synth room --frames 5 --width 80 --height 60 --out " + dir + "/seq", &out),
      0)
      << out;
  // Frame 3's depth image becomes garbage.
  std::vector<std::filesystem::path> depth;
  for (const auto& e : std::filesystem::directory_iterator(dir + "/seq/depth")) {
    depth.push_back(e.path());
  }
  std::sort(depth.begin(), depth.end());
  ASSERT_EQ(depth.size(), 5u);
  std::ofstream(depth[3], std::ios::trunc) << "not a png";
  const std::string out_dir = dir + "/out";
  const std::string run = std::string(kTinyRun);
  const std::string cmd = cli() + run.substr(0, run.find(" --source")) + " --source tum:" + dir +
                          "/seq" + run.substr(run.find(" --set")) + " --out " + out_dir;
  EXPECT_EQ(test::runCommand(cmd, &out), 1) << out;
  EXPECT_NE(out.find("stopped after 3 frames"), std::string::npos) << out;
  EXPECT_NE(out.find(depth[3].filename().string()), std::string::npos) << out;  // names the file
  EXPECT_EQ(io::readTrajectory(out_dir + "/camera.txt").size(), 3u);
  EXPECT_TRUE(std::filesystem::exists(out_dir + "/background.ply"));
  const nlohmann::json j = nlohmann::json::parse(readText(out_dir + "/run.json"));
  EXPECT_EQ(j["frames"], 3);
  EXPECT_NE(j["error"].get<std::string>().find("stopped after 3 frames"), std::string::npos);
}

TEST(CliRun, ABlockIndexLargerThanThePoolIsAWarning) {
  // 1024^3 voxels: 128^3 blocks, ~19 MiB of dense index outside an 8 MiB pool.
  const std::string out_dir = test::tempDir("run-index") + "/out";
  std::string out;
  ASSERT_EQ(test::runCommand(cli() +
                                 " run --quiet --source 'synth:room?frames=1&width=80&height=60'"
                                 " --set map.memory_mb=8 --set map.background_voxel_m=0.04"
                                 " --set map.background_resolution=1024 --out " +
                                 out_dir,
                             &out),
            0)
      << out;
  EXPECT_NE(out.find("MiB outside map.memory_mb (8 MiB): lower map.background_resolution (1024"),
            std::string::npos)
      << out;
  const nlohmann::json j = nlohmann::json::parse(readText(out_dir + "/run.json"));
  EXPECT_GT(j["memory"]["background_index_bytes"].get<double>(), 8.0 * (1 << 20));
}

TEST(CliRun, SigtermEndsTheRunAfterTheCurrentFrameAndKeepsItsOutputs) {
  // A long run, terminated once its fourth frame's image exists: the outputs of the frames done
  // so far are written (atomically, no temporary left), run.json says why, exit 128 + 15.
  const std::string dir = test::tempDir("run-sigterm");
  const std::string out_dir = dir + "/out";
  const std::string run = std::string(kTinyRun);
  const std::string emf_cmd = cli() + run.substr(0, run.find("frames=3")) + "frames=5000" +
                              run.substr(run.find("frames=3") + 8) +
                              " --set output.write_images=true --out " + out_dir;
  const std::string script = emf_cmd + " & pid=$!; i=0; while [ ! -e " + out_dir +
                             "/images/000003-objects.png ] && [ $i -lt 1200 ]; do sleep 0.05; "
                             "i=$((i+1)); done; kill -TERM $pid; wait $pid; echo \"rc=$?\"";
  std::ofstream(dir + "/run.sh") << script << "\n";
  std::string out;
  ASSERT_EQ(test::runCommand("sh " + dir + "/run.sh", &out), 0) << out;
  EXPECT_NE(out.find("rc=143"), std::string::npos) << out;
  EXPECT_NE(out.find("interrupted by SIGTERM after"), std::string::npos) << out;
  const size_t poses = io::readTrajectory(out_dir + "/camera.txt").size();
  EXPECT_GE(poses, 4u);
  EXPECT_LT(poses, 5000u);
  EXPECT_TRUE(std::filesystem::exists(out_dir + "/background.ply"));
  const nlohmann::json j = nlohmann::json::parse(readText(out_dir + "/run.json"));
  EXPECT_EQ(j["frames"].get<size_t>(), poses);
  EXPECT_NE(j["error"].get<std::string>().find("interrupted by SIGTERM"), std::string::npos);
  for (const auto& e : std::filesystem::directory_iterator(out_dir)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
}

TEST(CliRun, SigtermDuringStartUpStillWritesTheOutputs) {
  // SIGTERM as soon as the start-up log names the source, before the SLAM's kernels and pool
  // exist: the start-up finishes, no frame (or the few begun) runs, and the outputs are written
  // with the reason, exit 128 + 15 (before the handler covered start-up, the process died there
  // and wrote nothing).
  const std::string dir = test::tempDir("run-sigterm-start");
  const std::string out_dir = dir + "/out";
  const std::string run = std::string(kTinyRun);
  const std::string emf_cmd = "EMF_LOG_LEVEL=info " + cli() + run.substr(0, run.find("frames=3")) +
                              "frames=5000" + run.substr(run.find("frames=3") + 8) + " --out " +
                              out_dir;
  const std::string log = dir + "/stderr.txt";
  const std::string script = emf_cmd + " 2>" + log + " & pid=$!; i=0; while ! grep -q 'source:' " +
                             log + " 2>/dev/null && [ $i -lt 12000 ]; do i=$((i+1)); done; " +
                             "kill -TERM $pid; wait $pid; echo \"rc=$?\"";
  std::ofstream(dir + "/run.sh") << script << "\n";
  std::string out;
  ASSERT_EQ(test::runCommand("sh " + dir + "/run.sh", &out), 0) << out;
  EXPECT_NE(out.find("rc=143"), std::string::npos) << out << readText(log);
  const nlohmann::json j = nlohmann::json::parse(readText(out_dir + "/run.json"));
  EXPECT_NE(j["error"].get<std::string>().find("interrupted by SIGTERM"), std::string::npos);
  EXPECT_LT(j["frames"].get<size_t>(), 5000u);
  EXPECT_TRUE(std::filesystem::exists(out_dir + "/camera.txt"));
  EXPECT_TRUE(std::filesystem::exists(out_dir + "/background.ply"));
}

}  // namespace
}  // namespace emf
