// Process isolation of detector plugins (detector.isolation: process): the test plugin "faulty"
// segfaults, aborts, hangs or returns a garbage pointer on chosen frames; the child dies, the
// call reports it, the SLAM side goes on, and the child comes back after the back-off.
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "io/trajectory.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/isolated_detector.h"
#include "pipeline/plugin_search_path.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

// Under AddressSanitizer the child's own SEGV handler would turn the crash into "exit code 1":
// let the signal through, as in a release build (the child inherits this environment).
const bool kChildSignalsPass = [] {
  const char* asan = std::getenv("ASAN_OPTIONS");
  const std::string options = std::string(asan ? asan : "") + ":handle_segv=0:handle_abort=0";
  return setenv("ASAN_OPTIONS", options.c_str(), 1) == 0;
}();

const std::string kFaulty = std::string(EMF_TEST_PLUGIN_DIR) + "/libemf_detector_test_faulty.so";
// Generous for ASan builds; the hang test uses its own short deadline.
constexpr double kDeadlineS = 30.0;
constexpr double kLoadS = 60.0;

core::Frame frame(int64_t index) {
  core::Frame f;
  f.index = index;
  f.timestamp = 0.1 * static_cast<double>(index);
  f.timestamp_text = std::to_string(f.timestamp);
  f.depth = cv::Mat(60, 80, CV_32F, cv::Scalar(1.5f));
  f.color = cv::Mat(60, 80, CV_8UC3, cv::Scalar(10, 20, 30));
  return f;
}

std::unique_ptr<IsolatedDetector> start(const std::string& config, double deadline_s = kDeadlineS) {
  return std::make_unique<IsolatedDetector>(detectorHostPath(), kFaulty, config, "synth:test",
                                            test::camera80x60(), deadline_s, kLoadS);
}

// The faulty plugin's one detection: "cup", 0.9, box (20, 10, 40, 20), mask = the box.
void expectTheCup(const DetectorOutput& out) {
  ASSERT_TRUE(out.error.empty()) << out.error;
  ASSERT_EQ(out.detections.size(), 1u);
  const core::Detection& d = out.detections[0];
  EXPECT_EQ(d.class_name, "cup");
  EXPECT_FLOAT_EQ(d.score, 0.9f);
  EXPECT_EQ(d.box, cv::Rect(20, 10, 40, 20));
  ASSERT_EQ(d.mask.type(), CV_32F);
  EXPECT_EQ(cv::countNonZero(d.mask), 40 * 20);
  EXPECT_EQ(d.mask.at<float>(15, 30), 1.f);
  EXPECT_EQ(d.mask.at<float>(5, 30), 0.f);
}

TEST(Isolation, DetectionsAreTheSameAsInProcess) {
  ASSERT_TRUE(kChildSignalsPass);
  auto isolated = start("");
  auto in_process = DetectorPlugin::load(kFaulty, {}, "", "synth:test", test::camera80x60());
  const DetectorOutput a = isolated->detect(frame(0));
  const DetectorOutput b = in_process->detect(frame(0));
  expectTheCup(a);
  ASSERT_EQ(b.detections.size(), 1u);
  EXPECT_EQ(cv::norm(a.detections[0].mask, b.detections[0].mask, cv::NORM_INF), 0.0);
  EXPECT_EQ(isolated->name(), in_process->name());
}

// detector.nice: the plugin's process runs at that niceness (field 19 of /proc/<pid>/stat).
TEST(Isolation, TheChildRunsAtDetectorNice) {
  IsolatedDetector isolated(detectorHostPath(), kFaulty, "", "synth:test", test::camera80x60(),
                            kDeadlineS, kLoadS, 19);
  expectTheCup(isolated.detect(frame(0)));
  std::ifstream stat("/proc/" + std::to_string(isolated.childPid()) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  ASSERT_NE(text.rfind(')'), std::string::npos) << text;
  // After "pid (comm)": state is field 3, nice field 19.
  std::istringstream fields(text.substr(text.rfind(')') + 2));
  std::string field;
  for (int i = 3; i <= 19; ++i) fields >> field;
  EXPECT_EQ(field, "19") << text;
}

TEST(Isolation, ASegfaultIsReportedAndTheChildComesBackAfterTheBackOff) {
  auto d = start("segfault=2");
  expectTheCup(d->detect(frame(1)));
  const pid_t first = d->childPid();
  const DetectorOutput crash = d->detect(frame(2));
  EXPECT_TRUE(crash.detections.empty());
  EXPECT_NE(crash.error.find("frame 2: the detector process crashed (killed by SIGSEGV)"),
            std::string::npos)
      << crash.error;
  EXPECT_NE(crash.error.find("restarting it in 0.5 s"), std::string::npos) << crash.error;
  // Within the back-off: no child, no detections, said so.
  const DetectorOutput down = d->detect(frame(3));
  EXPECT_NE(down.error.find("the detector process is down"), std::string::npos) << down.error;
  std::this_thread::sleep_for(std::chrono::duration<double>(IsolatedDetector::kFirstRestartS));
  expectTheCup(d->detect(frame(4)));
  EXPECT_NE(d->childPid(), first);
  EXPECT_EQ(d->counters().crashes, 1);
  EXPECT_EQ(d->counters().restarts, 1);
}

TEST(Isolation, AnAbortAndAGarbagePointerAreCrashesToo) {
  auto d = start("abort=1,garbage=3");
  const DetectorOutput abort_out = d->detect(frame(1));
  EXPECT_NE(abort_out.error.find("crashed (killed by SIGABRT)"), std::string::npos)
      << abort_out.error;
  std::this_thread::sleep_for(std::chrono::duration<double>(IsolatedDetector::kFirstRestartS));
  expectTheCup(d->detect(frame(2)));
  // Reading the garbage detections pointer crashes the host's validation, in the child.
  const DetectorOutput garbage = d->detect(frame(3));
  EXPECT_NE(garbage.error.find("crashed (killed by SIGSEGV)"), std::string::npos) << garbage.error;
  EXPECT_EQ(d->counters().crashes, 2);
}

TEST(Isolation, AHangPastTheDeadlineIsKilled) {
  auto d = start("hang=1", 0.3);
  const DetectorOutput hang = d->detect(frame(1));
  EXPECT_TRUE(hang.detections.empty());
  EXPECT_NE(hang.error.find("gave no result within detector.deadline_s (0.3 s) and was killed"),
            std::string::npos)
      << hang.error;
  EXPECT_EQ(d->counters().timeouts, 1);
  EXPECT_EQ(d->childPid(), -1);
}

TEST(Isolation, ThePluginsOwnLoadErrorReachesTheCaller) {
  try {
    start("bogus=1");
    FAIL() << "no error";
  } catch (const PluginError& e) {
    EXPECT_NE(std::string(e.what()).find("test plugin: unknown config 'bogus=1'"),
              std::string::npos)
        << e.what();
    EXPECT_EQ(e.status(), EMF_ERROR_CONFIG);
  }
}

TEST(Isolation, AutoIsolatesPluginsLoadedByPathOnly) {
  DetectorOptions o;
  EXPECT_TRUE(usesProcess(o, kFaulty));
  const std::string bundled = resolvePluginPath("maskfile", modulePluginFolders());
  EXPECT_FALSE(usesProcess(o, bundled));
  o.isolation = DetectorIsolation::kProcess;
  EXPECT_TRUE(usesProcess(o, bundled));
  o.isolation = DetectorIsolation::kNone;
  EXPECT_FALSE(usesProcess(o, kFaulty));
}

TEST(Isolation, EmfRunCompletesThroughACrashingPluginAndReportsIt) {
  // The plugin loaded by path runs in its own process (detector.isolation: auto) on every frame
  // and segfaults on frame 1. The run processes every frame; run.json counts the crash. (Which
  // later fault frames find the child up depends on the machine's speed: the kinds are covered
  // one by one above.)
  const std::string dir = test::tempDir("isolation-run");
  std::string out;
  const int rc = test::runCommand(
      std::string(EMF_CLI_PATH) +
          " run --quiet --source 'synth:room?frames=40&width=80&height=60' --set "
          "map.memory_mb=32 --set map.background_voxel_m=0.04 --set "
          "map.background_resolution=128 --set detector.every_n_frames=1 --detector " +
          kFaulty + " --detector-config segfault=1 --out " + dir,
      &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("frame 1: the detector process crashed (killed by SIGSEGV)"),
            std::string::npos)
      << out;
  const nlohmann::json j = nlohmann::json::parse(test::readText(dir + "/run.json"));
  const nlohmann::json& det = j["detector"];
  EXPECT_EQ(det["isolation"], "process");
  EXPECT_EQ(det["crashes"], 1) << det.dump(2);
  EXPECT_EQ(det["runs"], 40);
  EXPECT_GE(det["failures"].get<int>(), 1);
  EXPECT_GE(det["detections"].get<int>(), 1);  // frame 0, before the crash
  EXPECT_EQ(j["frames"], 40);
  EXPECT_EQ(io::readTrajectory(dir + "/camera.txt").size(), 40u);
}

}  // namespace
}  // namespace emf::pipeline
