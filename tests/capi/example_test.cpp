// examples/track_objects (a C program using only emf.h) run as a user would: against a TUM
// folder written by `emf synth` and against the virtual OpenNI2 device serving the same folder.
// The printed camera poses are parsed and compared with the folder's ground truth; printed
// object poses must be rigid transforms.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "io/trajectory.h"
#include "test_support.h"

namespace emf {
namespace {

/// Absolute camera position error without alignment over the short sequence (as the SLAM and
/// C API tests).
constexpr double kPoseToleranceM = 0.03;
constexpr double kRotationToleranceDeg = 2.0;
/// Timestamps are printed and written with 6 decimals.
constexpr double kStampToleranceS = 1e-5;
/// Rotation matrices printed with 6 decimals are orthonormal to this.
constexpr double kRotationPrintTolerance = 1e-4;
constexpr int kFrames = 16;
constexpr const char* kConfig =
    "map: {memory_mb: 64, background_voxel_m: 0.02, background_resolution: 256}";

struct Printed {
  struct Frame {
    long index = -1;
    double t = 0;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  };
  std::vector<Frame> frames;
  std::vector<Eigen::Isometry3d> objects;
  std::string end_line;
};

Eigen::Isometry3d readPose(std::istringstream& in) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) in >> T.matrix()(r, c);
  }
  return T;
}

Printed parse(const std::string& out) {
  Printed p;
  std::istringstream lines(out);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream in(line);
    std::string word;
    in >> word;
    if (word == "frame") {
      Printed::Frame f;
      std::string source, t, lost, latency, label;
      in >> f.index >> source >> t >> lost >> latency >> label;
      EXPECT_EQ(t.rfind("t=", 0), 0u) << line;
      EXPECT_EQ(label, "T_world_camera=") << line;
      f.t = std::stod(t.substr(2));
      f.T = readPose(in);
      EXPECT_FALSE(in.fail()) << line;
      p.frames.push_back(f);
    } else if (word == "object") {
      std::string id, cls, state, label;
      in >> id >> cls >> state >> label;
      EXPECT_EQ(label, "T_world_object=") << line;
      p.objects.push_back(readPose(in));
      EXPECT_FALSE(in.fail()) << line;
    } else if (word == "end") {
      p.end_line = line;
    }
  }
  return p;
}

/// `emf synth <preset>` as a TUM folder of kFrames frames at 160x120 (simulated detections in
/// masks/).
std::string writeFolder(const std::string& preset = "room") {
  const std::string dir = test::tempDir("example-" + preset);
  std::string out;
  const int rc = test::runCommand(std::string(EMF_CLI_PATH) + " synth " + preset + " --out " + dir +
                                      " --frames " + std::to_string(kFrames) +
                                      " --width 160 --height 120 --seed 3 --force",
                                  &out);
  EXPECT_EQ(rc, 0) << out;
  return dir;
}

/// Compares every printed camera pose with the ground truth relative to the first camera.
void expectPoses(const Printed& p, const std::string& dir) {
  const io::Trajectory gt = io::readTrajectory(dir + "/groundtruth.txt");
  ASSERT_EQ(gt.size(), static_cast<size_t>(kFrames));
  const Eigen::Isometry3d T_first_world = gt.poses.front().inverse();
  for (size_t i = 0; i < p.frames.size(); ++i) {
    const auto& f = p.frames[i];
    EXPECT_EQ(f.index, static_cast<long>(i));
    size_t k = gt.size();
    for (size_t j = 0; j < gt.size(); ++j) {
      if (std::abs(gt.stamps[j] - f.t) < kStampToleranceS) k = j;
    }
    ASSERT_LT(k, gt.size()) << "printed timestamp " << f.t << " is not in the folder";
    EXPECT_EQ(k, i) << "frames are printed in order, none lost";
    const Eigen::Isometry3d T_gt = T_first_world * gt.poses[k];
    const double te = (f.T.translation() - T_gt.translation()).norm();
    const double re =
        Eigen::AngleAxisd(f.T.linear().transpose() * T_gt.linear()).angle() * 180.0 / M_PI;
    EXPECT_LT(te, kPoseToleranceM) << "frame " << i;
    EXPECT_LT(re, kRotationToleranceDeg) << "frame " << i;
  }
  for (const auto& T : p.objects) {
    EXPECT_LT((T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm(),
              kRotationPrintTolerance);
  }
}

TEST(Example, TracksADatasetFolder) {
  const std::string dir = writeFolder();
  std::string out;
  const int rc =
      test::runCommand(std::string(EMF_EXAMPLE_PATH) + " tum:" + dir + " '" + kConfig + "'", &out);
  ASSERT_EQ(rc, 0) << out;
  const Printed p = parse(out);
  ASSERT_EQ(p.frames.size(), static_cast<size_t>(kFrames)) << out;
  expectPoses(p, dir);
  EXPECT_EQ(p.end_line,
            "end frames=16 produced=16 dropped=0 callbacks=16 "
            "status=EMF_ERROR_END_OF_STREAM")
      << out;
}

// The cars preset: moving objects with detections in masks/ replayed by the maskfile plugin
// (frame 0). The camera poses must be right; both cars are created on the first frame and
// printed, with rigid poses, on every frame.
TEST(Example, TracksTheCarsDataset) {
  const std::string dir = writeFolder("cars");
  std::string out;
  // 16 frames hold one detection frame: the cars are reported from their first detection.
  const std::string config =
      std::string(kConfig) + "\ndetector: {plugin: maskfile}\nobjects: {confirm_detections: 1}";
  const int rc =
      test::runCommand(std::string(EMF_EXAMPLE_PATH) + " tum:" + dir + " '" + config + "'", &out);
  ASSERT_EQ(rc, 0) << out;
  const Printed p = parse(out);
  ASSERT_EQ(p.frames.size(), static_cast<size_t>(kFrames)) << out;
  expectPoses(p, dir);
  EXPECT_EQ(p.objects.size(), static_cast<size_t>(2 * kFrames)) << out;
  size_t cars = 0;
  for (size_t pos = out.find("class=car"); pos != std::string::npos;
       pos = out.find("class=car", pos + 1)) {
    ++cars;
  }
  EXPECT_EQ(cars, p.objects.size()) << out;
}

#ifdef EMF_HAVE_OPENNI2  // built with EMF_WITH_OPENNI2 (the default)
TEST(Example, TracksTheVirtualOpenni2Device) {
  const std::string dir = writeFolder();
  std::ifstream calib(dir + "/calibration.txt");
  double fx, fy, cx, cy;
  calib >> fx >> fy >> cx >> cy;
  ASSERT_FALSE(calib.fail());
  // On-demand playback (speed=0) is lossless; the folder's calibration replaces the intrinsics
  // OpenNI2 derives from the field of view.
  std::ostringstream uri;
  uri.precision(10);
  uri << "openni2:emf-virtual://" << dir << ";speed=0?fx=" << fx << "&fy=" << fy << "&cx=" << cx
      << "&cy=" << cy << "&max_frames=" << kFrames;
  std::string out;
  const int rc = test::runCommand(
      std::string(EMF_EXAMPLE_PATH) + " '" + uri.str() + "' '" + kConfig + "'", &out);
  ASSERT_EQ(rc, 0) << out;
  const Printed p = parse(out);
  ASSERT_EQ(p.frames.size(), static_cast<size_t>(kFrames)) << out;
  expectPoses(p, dir);
  EXPECT_NE(p.end_line.find("status=EMF_ERROR_END_OF_STREAM"), std::string::npos) << out;
}

#endif

TEST(Example, BadSourceIsAClearErrorAndExitCode1) {
  std::string out;
  const int rc = test::runCommand(std::string(EMF_EXAMPLE_PATH) + " tum:/nonexistent/emf-x", &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("error: EMF_ERROR_IO"), std::string::npos) << out;
  EXPECT_NE(out.find("/nonexistent/emf-x"), std::string::npos) << out;
  EXPECT_EQ(test::runCommand(std::string(EMF_EXAMPLE_PATH), &out), 2) << out;
}

}  // namespace
}  // namespace emf
