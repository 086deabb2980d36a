// Inputs that used to pass silently or with a misleading message (issue 33's list), each tried
// through `emf` as a user runs it: the error or warning names the file, key or frame and what to
// do, and a run that can go on does.
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/trajectory.h"
#include "test_support.h"

namespace emf {
namespace {

namespace fs = std::filesystem;

const std::string kCli = EMF_CLI_PATH;
// Small and fast: 80x60, a 4 cm background, 32 MiB pool.
const std::string kSmall =
    " --quiet --set map.memory_mb=32 --set map.background_voxel_m=0.04"
    " --set map.background_resolution=128";

class BadInput : public ::testing::Test {
 protected:
  // One 8-frame synthetic room (detections on frame 0), copied per test to be broken.
  static void SetUpTestSuite() {
    root_ = test::tempDir("bad-input");
    std::string out;
    ASSERT_EQ(
        test::runCommand(
            kCli + " synth room --frames 8 --width 80 --height 60 --out " + root_ + "/seq", &out),
        0)
        << out;
  }
  // A fresh copy of the sequence named `name`.
  static std::string copy(const std::string& name) {
    const std::string dir = root_ + "/" + name;
    fs::copy(root_ + "/seq", dir, fs::copy_options::recursive);
    return dir;
  }
  // The n-th file (sorted) of `dir`/`sub` with extension `ext`.
  static std::string nth(const std::string& dir, const std::string& sub, size_t n,
                         const std::string& ext = ".png") {
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(dir + "/" + sub)) {
      if (e.path().extension() == ext) files.push_back(e.path().string());
    }
    std::sort(files.begin(), files.end());
    return files.at(n);
  }
  static int run(const std::string& args, std::string* out) {
    return test::runCommand(kCli + " run" + kSmall + " " + args, out);
  }
  static std::string root_;
};
std::string BadInput::root_;

TEST_F(BadInput, AFocalLengthNoCameraHasIsAnErrorNamingTheCalibrationFile) {
  // fx = fy = 1e7 px at 80x60: the URI and --set refuse it; the file did not (19 of 20 frames
  // "tracking lost", exit 0).
  const std::string dir = copy("calib");
  std::ofstream(dir + "/calibration.txt") << "10000000 10000000 40 30 80 60\n";
  std::string out;
  EXPECT_EQ(run("--source tum:" + dir + " --out " + dir + "/run", &out), 1) << out;
  EXPECT_NE(out.find(dir + "/calibration.txt: camera intrinsics fx=1e+07"), std::string::npos)
      << out;
  EXPECT_NE(out.find("focal lengths must be at most 100 image sides"), std::string::npos) << out;
}

TEST_F(BadInput, TheMaskfileDetectorOnAFolderWithoutMasksIsAnError) {
  std::string out;
  EXPECT_EQ(run("--source tum:" + root_ +
                    "/seq --detector maskfile --detector-config "
                    "dir=/nonexistent --out " +
                    root_ + "/run-maskfile",
                &out),
            1)
      << out;
  EXPECT_NE(out.find("'/nonexistent/masks' is not a folder: '/nonexistent' does not exist"),
            std::string::npos)
      << out;
  // The run.json of a start-up failure says so.
  const nlohmann::json j = nlohmann::json::parse(test::readText(root_ + "/run-maskfile/run.json"));
  EXPECT_EQ(j["status"], "failed");
  EXPECT_NE(j["error"].get<std::string>().find("start-up failed"), std::string::npos);
}

TEST_F(BadInput, AZeroEvalDeltaOrThresholdIsAnError) {
  std::string out;
  ASSERT_EQ(run("--source tum:" + root_ + "/seq --out " + root_ + "/run-eval", &out), 0) << out;
  for (const char* flag : {"--delta", "--max-diff"}) {
    EXPECT_EQ(test::runCommand(kCli + " eval --no-files --gt " + root_ + "/seq --est " + root_ +
                                   "/run-eval " + flag + " 0",
                               &out),
              1)
        << flag << "\n"
        << out;
    EXPECT_NE(out.find(std::string(flag) + " must be a positive number, got '0'"),
              std::string::npos)
        << out;
  }
}

TEST_F(BadInput, AnUnreadableDepthImageSaysWhyNotCorrupt) {
  // A folder where frame 3's depth PNG should be (EISDIR; permission denied reads the same way,
  // with the system's reason, but cannot be made as root).
  const std::string dir = copy("unreadable");
  const std::string depth = nth(dir, "depth", 3);
  fs::remove(depth);
  fs::create_directory(depth);
  std::string out;
  EXPECT_EQ(run("--source tum:" + dir + " --out " + dir + "/run", &out), 1) << out;
  EXPECT_NE(out.find("cannot read depth image '" + depth + "': Is a directory"), std::string::npos)
      << out;
  EXPECT_EQ(out.find("corrupt"), std::string::npos) << out;
  EXPECT_EQ(io::readTrajectory(dir + "/run/camera.txt").size(), 3u);
}

TEST_F(BadInput, ABrokenColourImageCitesRgbTxtsLine) {
  // Without associations.txt, depth.txt and rgb.txt are associated by time: the colour error
  // names rgb.txt's line (it named depth.txt's).
  const std::string dir = copy("colour");
  fs::remove(dir + "/associations.txt");
  const std::string color = nth(dir, "rgb", 2);
  std::ofstream(color, std::ios::trunc) << "garbage";
  std::string out;
  EXPECT_EQ(run("--source tum:" + dir + " --out " + dir + "/run", &out), 1) << out;
  // rgb.txt has 3 comment lines: the third image is on line 6.
  EXPECT_NE(out.find(dir + "/rgb.txt:6: cannot decode colour image '" + color + "'"),
            std::string::npos)
      << out;
}

TEST_F(BadInput, ABrokenMaskDoesNotStopARunWithoutADetector) {
  const std::string dir = copy("mask");
  const std::string mask = nth(dir, "masks", 0);
  std::ofstream(mask, std::ios::trunc) << "garbage";
  std::string out;
  EXPECT_EQ(run("--source tum:" + dir + " --out " + dir + "/run", &out), 0) << out;
  EXPECT_NE(out.find("cannot decode detection mask '" + mask + "'"), std::string::npos) << out;
  EXPECT_NE(out.find("frame 0 is read without its detections"), std::string::npos) << out;
  EXPECT_EQ(io::readTrajectory(dir + "/run/camera.txt").size(), 8u);
  // With the maskfile detector the same file is the detector's failure, counted in run.json.
  EXPECT_EQ(run("--source tum:" + dir + " --detector maskfile --out " + dir + "/run2", &out), 0)
      << out;
  const nlohmann::json j = nlohmann::json::parse(test::readText(dir + "/run2/run.json"));
  EXPECT_EQ(j["detector"]["failures"], 1) << j["detector"].dump();
}

TEST_F(BadInput, AnImageLargerThanMaxPixelsIsRefusedBeforeTheFirstFrame) {
  // 4096x2048 = 8388608 pixels > source.max_pixels (2048^2).
  std::string out;
  EXPECT_EQ(run("--source 'synth:room?frames=2&width=4096&height=2048' --out " + root_ + "/run-big",
                &out),
            1)
      << out;
  EXPECT_NE(out.find("depth images of 4096x2048 = 8388608 pixels are more than "
                     "source.max_pixels (4194304)"),
            std::string::npos)
      << out;
  // Raised, the same source opens (2 frames at 80x60 would be the same check; the key works).
  EXPECT_EQ(run("--source 'synth:room?frames=1&width=80&height=60' --set source.max_pixels=4800"
                " --out " +
                    root_ + "/run-small",
                &out),
            0)
      << out;
  EXPECT_EQ(run("--source 'synth:room?frames=1&width=80&height=60' --set source.max_pixels=4799"
                " --out " +
                    root_ + "/run-small2",
                &out),
            1)
      << out;
}

}  // namespace
}  // namespace emf
