// The TUM folder reader on every TUM-layout folder of ../shared/data, the fr1-xyz pair loader,
// association without associations.txt, detections, and error messages on broken folders.
#include "io/tum_source.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "io/depth_image.h"
#include "io/trajectory.h"
#include "io_test_util.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::io {
namespace {
namespace fs = std::filesystem;

using testing::expectErrorContaining;
using testing::writeText;

// Compares a converted depth image with the raw uint16 PNG it came from: NaN exactly where the
// raw value is 0, else exactly float(raw / scale). Returns the number of valid pixels.
int expectDepthMatchesRaw(const cv::Mat& depth, const std::string& png, double scale) {
  const cv::Mat raw = cv::imread(png, cv::IMREAD_UNCHANGED);
  EXPECT_EQ(raw.type(), CV_16UC1) << png;
  EXPECT_EQ(depth.type(), CV_32FC1);
  EXPECT_EQ(depth.size(), raw.size());
  int valid = 0, mismatches = 0;
  for (int y = 0; y < raw.rows; ++y) {
    for (int x = 0; x < raw.cols; ++x) {
      const uint16_t r = raw.at<uint16_t>(y, x);
      const float d = depth.at<float>(y, x);
      if (r == 0) {
        mismatches += !std::isnan(d);
      } else {
        ++valid;
        mismatches += d != static_cast<float>(r / scale);
      }
    }
  }
  EXPECT_EQ(mismatches, 0) << png;
  return valid;
}

// Reads every frame of a TUM folder and checks it against its files.
void checkWholeFolder(const std::string& dir, const std::string& uri_query, double scale,
                      size_t expected_frames, const core::Intrinsics& expected_k) {
  const std::string uri = "tum:" + dir + uri_query;
  auto source = sources::openSource(uri, core::SourceOptions{});
  EXPECT_EQ(source->size(), static_cast<int64_t>(expected_frames));
  const core::Intrinsics k = source->intrinsics();
  EXPECT_EQ(k.fx, expected_k.fx);
  EXPECT_EQ(k.fy, expected_k.fy);
  EXPECT_EQ(k.cx, expected_k.cx);
  EXPECT_EQ(k.cy, expected_k.cy);
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);

  // The listing the reader should follow.
  std::vector<std::vector<std::string>> assoc;
  {
    std::ifstream in(dir + "/associations.txt");
    std::string a, b, c, d;
    while (in >> a >> b >> c >> d) assoc.push_back({a, b, c, d});
  }
  ASSERT_EQ(assoc.size(), expected_frames);
  const Trajectory gt = readTrajectory(dir + "/groundtruth.txt");

  core::Frame f;
  size_t n = 0;
  while (source->next(f)) {
    ASSERT_LT(n, expected_frames);
    EXPECT_EQ(f.index, static_cast<int64_t>(n));
    EXPECT_EQ(f.timestamp_text, assoc[n][2]);
    EXPECT_EQ(f.timestamp, std::stod(assoc[n][2]));
    EXPECT_EQ(f.rgb_timestamp, std::stod(assoc[n][0]));
    // Check every pixel on the first, a middle and the last frame (the rest: type and size).
    if (n == 0 || n == expected_frames / 2 || n + 1 == expected_frames) {
      EXPECT_GT(expectDepthMatchesRaw(f.depth, dir + "/" + assoc[n][3], scale), 100000);
    }
    EXPECT_EQ(f.depth.type(), CV_32FC1);
    EXPECT_EQ(f.depth.size(), cv::Size(640, 480));
    EXPECT_EQ(f.color.type(), CV_8UC3);
    EXPECT_EQ(f.color.size(), cv::Size(640, 480));
    // The folders' ground truth has the frames' timestamps: the exact pose.
    ASSERT_TRUE(f.T_world_camera_gt.has_value()) << n;
    const size_t g = static_cast<size_t>(
        std::lower_bound(gt.stamps.begin(), gt.stamps.end(), f.timestamp) - gt.stamps.begin());
    ASSERT_LT(g, gt.size());
    EXPECT_EQ(gt.stamps[g], f.timestamp);
    EXPECT_EQ(f.T_world_camera_gt->matrix(), gt.poses[g].matrix());
    EXPECT_FALSE(f.detections.has_value());
    ++n;
  }
  EXPECT_EQ(n, expected_frames);
  EXPECT_FALSE(source->next(f));
}

TEST(TumSource, ReadsAllOfRedkitchen) {
  core::Intrinsics k;
  k.fx = k.fy = 585;
  k.cx = 320;
  k.cy = 240;
  checkWholeFolder(test::dataPath("redkitchen-0-299"), "?depth_scale=1000", 1000.0, 300, k);
}

TEST(TumSource, ReadsAllOfFr3CabinetKeyframes) {
  core::Intrinsics k;
  k.fx = 535.4;
  k.fy = 539.2;
  k.cx = 320.1;
  k.cy = 247.6;
  checkWholeFolder(test::dataPath("tum-fr3-cabinet-keyframes"), "", 5000.0, 58, k);
}

// Every depth image of the real TUM-layout folders, read at its own scale and at the other
// common one: the scale check must stay silent on the right scale and speak on the wrong one.
int framesWarned(const std::string& dir, double scale) {
  int warned = 0;
  for (const auto& e : fs::directory_iterator(dir + "/depth")) {
    const cv::Mat units = readDepthUnits(e.path().string(), "test");
    const std::string w = depthScaleWarning(units, scale);
    if (!w.empty()) {
      ++warned;
      EXPECT_NE(w.find("?depth_scale="), std::string::npos) << w;
    }
  }
  return warned;
}

TEST(DepthScaleWarning, SilentAtTheRightScaleOnRealFramesAndSpeaksAtTheWrongOne) {
  const std::string kitchen = test::dataPath("redkitchen-0-299");  // millimetres
  EXPECT_EQ(framesWarned(kitchen, 1000.0), 0);
  EXPECT_EQ(framesWarned(kitchen, 5000.0), 300);
  const std::string cabinet = test::dataPath("tum-fr3-cabinet-keyframes");  // TUM, 5000
  EXPECT_EQ(framesWarned(cabinet, 5000.0), 0);
  // TUM units read as millimetres put this cabinet at 5-10 m, which a sensor can see: only a
  // median beyond 10 m is called implausible.
  const cv::Mat far(480, 640, CV_16UC1, cv::Scalar(12000));
  EXPECT_NE(depthScaleWarning(far, 1000.0).find("add ?depth_scale=5000"), std::string::npos);
  EXPECT_EQ(depthScaleWarning(far, 5000.0), "");
  // The message names the depth found and the key to set.
  const cv::Mat mm = readDepthUnits(kitchen + "/depth/000000.png", "test");
  EXPECT_NE(depthScaleWarning(mm, 5000.0).find("add ?depth_scale=1000"), std::string::npos);
  // Too few valid pixels to judge: silent.
  cv::Mat sparse(480, 640, CV_16UC1, cv::Scalar(0));
  sparse(cv::Rect(0, 0, 10, 10)).setTo(700);
  EXPECT_EQ(depthScaleWarning(sparse, 5000.0), "");
  sparse(cv::Rect(0, 0, 64, 48)).setTo(700);
  EXPECT_NE(depthScaleWarning(sparse, 5000.0), "");
}

TEST(TumSource, QueryOverridesCalibrationAndLimitsFrames) {
  auto s = sources::openSource("tum:" + test::dataPath("tum-fr3-cabinet-keyframes") +
                                   "?fx=500&fy=501&cx=300&cy=200&max_frames=3",
                               core::SourceOptions{});
  EXPECT_EQ(s->intrinsics().fx, 500);
  EXPECT_EQ(s->intrinsics().cy, 200);
  EXPECT_EQ(s->size(), 3);
  core::Frame f;
  int n = 0;
  while (s->next(f)) ++n;
  EXPECT_EQ(n, 3);
  EXPECT_NE(s->describe().find(", 3 frames 640x480, ground truth"), std::string::npos)
      << s->describe();
}

TEST(TumPairs, LoadsBothFr1XyzCases) {
  const std::string root = test::dataPath("tum-fr1-xyz-pairs");
  // case_1 poses: prev t = (1.3160 0.6254 1.6302), curr t = (1.3303 0.6256 1.6464).
  const double case1_dist =
      Eigen::Vector3d(1.3303 - 1.3160, 0.6256 - 0.6254, 1.6464 - 1.6302).norm();
  for (const char* name : {"case_1", "case_2"}) {
    const TumPairCase c = loadTumPairCase(root + "/" + name, root + "/kinect_params.txt");
    EXPECT_EQ(c.intrinsics.fx, 525);
    EXPECT_EQ(c.intrinsics.fy, 525);
    EXPECT_EQ(c.intrinsics.cx, 319.5);
    EXPECT_EQ(c.intrinsics.cy, 239.5);
    EXPECT_EQ(c.intrinsics.width, 640);
    EXPECT_EQ(c.intrinsics.height, 480);
    EXPECT_GT(expectDepthMatchesRaw(c.prev.depth, root + "/" + name + "/dep_prev.png", 5000), 1000);
    EXPECT_GT(expectDepthMatchesRaw(c.curr.depth, root + "/" + name + "/dep_curr.png", 5000), 1000);
    EXPECT_EQ(c.prev.color.type(), CV_8UC3);
    const Eigen::Isometry3d T = c.T_prev_curr();
    // Relative pose: its translation, rotated back to the world, is the position difference.
    const Eigen::Vector3d d_world = c.prev.T_world_camera_gt->rotation() * T.translation();
    EXPECT_LT((d_world -
               (c.curr.T_world_camera_gt->translation() - c.prev.T_world_camera_gt->translation()))
                  .norm(),
              1e-12);
    if (std::string(name) == "case_1") {
      EXPECT_NEAR(T.translation().norm(), case1_dist, 1e-12);
    }
  }
  expectErrorContaining([&] { loadTumPairCase(root + "/case_9", root + "/kinect_params.txt"); },
                        {"case_9", "not a folder"});
}

// ---- generated folders ------------------------------------------------------------------------

const cv::Size kSmall(8, 6);

// A small TUM folder: frames with depth value 1000 * (i + 1) units (0 in the top-left pixel),
// plain colour, rgb/depth lists with the given timestamps (strings), calibration.txt.
struct MiniFolder {
  std::string dir;
  explicit MiniFolder(const std::vector<std::string>& depth_stamps,
                      const std::vector<std::string>& rgb_stamps, bool calibration = true) {
    dir = test::tempDir("tum");
    fs::create_directories(dir + "/depth");
    fs::create_directories(dir + "/rgb");
    std::string depth_txt = "# depth maps\n# timestamp filename\n", rgb_txt = "# colour\n";
    for (size_t i = 0; i < depth_stamps.size(); ++i) {
      cv::Mat d(kSmall, CV_16UC1, cv::Scalar(static_cast<double>(1000 * (i + 1))));
      d.at<uint16_t>(0, 0) = 0;
      EXPECT_TRUE(cv::imwrite(dir + "/depth/" + depth_stamps[i] + ".png", d));
      depth_txt += depth_stamps[i] + " depth/" + depth_stamps[i] + ".png\n";
    }
    for (size_t i = 0; i < rgb_stamps.size(); ++i) {
      cv::Mat c(kSmall, CV_8UC3, cv::Scalar(10.0 * static_cast<double>(i), 20, 30));
      EXPECT_TRUE(cv::imwrite(dir + "/rgb/" + rgb_stamps[i] + ".png", c));
      rgb_txt += rgb_stamps[i] + " rgb/" + rgb_stamps[i] + ".png\n";
    }
    writeText(dir + "/depth.txt", depth_txt);
    writeText(dir + "/rgb.txt", rgb_txt);
    if (calibration) writeText(dir + "/calibration.txt", "10 11 4 3 8 6\n");
  }
};

TEST(TumSource, AssociatesLikeAssociatePyWithoutAssociationsFile) {
  // Candidates within 0.02 s: (1.000, 1.011) .011, (1.020, 1.011) .009, (1.020, 1.035) .015,
  // (1.040, 1.035) .005. Greedy by difference: (1.040, 1.035), then (1.020, 1.011); 1.000 and
  // 1.100 stay without colour and are skipped.
  MiniFolder m({"1.000", "1.020", "1.040", "1.100"}, {"1.011", "1.035"});
  TumSource s(m.dir, core::SourceOptions{});
  ASSERT_EQ(s.entries().size(), 2u);
  EXPECT_EQ(s.entries()[0].depth_stamp_text, "1.020");
  EXPECT_EQ(s.entries()[0].rgb_file, "rgb/1.011.png");
  EXPECT_EQ(s.entries()[1].depth_stamp_text, "1.040");
  EXPECT_EQ(s.entries()[1].rgb_file, "rgb/1.035.png");
  core::Frame f;
  ASSERT_TRUE(s.next(f));
  EXPECT_TRUE(std::isnan(f.depth.at<float>(0, 0)));
  EXPECT_EQ(f.depth.at<float>(1, 1), static_cast<float>(2000 / 5000.0));
  EXPECT_EQ(f.rgb_timestamp, 1.011);
  EXPECT_EQ(f.color.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 20, 30));
  ASSERT_TRUE(s.next(f));
  EXPECT_EQ(f.depth.at<float>(5, 7), static_cast<float>(3000 / 5000.0));
  EXPECT_EQ(f.color.at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
  EXPECT_FALSE(s.next(f));
  EXPECT_EQ(s.intrinsics().fx, 10);
  EXPECT_EQ(s.intrinsics().cy, 3);
}

TEST(TumSource, AttachesDetectionsAndInterpolatedGroundTruth) {
  MiniFolder m({"1.000000", "1.033333"}, {"1.000000", "1.033333"});
  cv::Mat ids(kSmall, CV_16UC1, cv::Scalar(0));
  ids(cv::Rect(2, 1, 3, 2)).setTo(1);
  fs::create_directories(m.dir + "/masks");
  ASSERT_TRUE(cv::imwrite(m.dir + "/masks/1.033333.png", ids));
  writeText(m.dir + "/masks/1.033333.txt", "1 sports_ball 0.8\n");
  // Ground truth at 1.015 and 1.04: frame 1 (1.033333) is interpolated; frame 0 (1.0) has only
  // the 1.015 pose within 0.02 s: nearest.
  writeText(m.dir + "/groundtruth.txt", "1.015 0 0 0 0 0 0 1\n1.04 2 0 0 0 0 0 1\n");
  auto s = sources::openSource("tum:" + m.dir, core::SourceOptions{});
  core::Frame f0, f1;
  ASSERT_TRUE(s->next(f0));
  ASSERT_TRUE(s->next(f1));
  EXPECT_FALSE(f0.detections.has_value());
  ASSERT_TRUE(f1.detections.has_value());
  ASSERT_EQ(f1.detections->size(), 1u);
  EXPECT_EQ((*f1.detections)[0].class_name, "sports ball");
  EXPECT_EQ((*f1.detections)[0].box, cv::Rect(2, 1, 3, 2));
  ASSERT_TRUE(f0.T_world_camera_gt.has_value());
  EXPECT_EQ(f0.T_world_camera_gt->translation().x(), 0.0);
  ASSERT_TRUE(f1.T_world_camera_gt.has_value());
  EXPECT_NEAR(f1.T_world_camera_gt->translation().x(), 2 * (1.033333 - 1.015) / 0.025, 1e-9);
}

bool anyContains(const std::vector<std::string>& texts, const std::string& part) {
  for (const auto& t : texts) {
    if (t.find(part) != std::string::npos) return true;
  }
  return false;
}

TEST(TumSource, WarnsWhenMasksMatchNoFrameOrTheDepthScaleLooksWrong) {
  // Lists written with 7 decimals while depth.txt has 6: no frame would get a detection.
  const std::string kNoMatch = "none is named after a frame's depth timestamp";
  MiniFolder m({"1.000000", "1.033333"}, {"1.000000", "1.033333"});
  fs::create_directories(m.dir + "/masks");
  cv::Mat ids(kSmall, CV_16UC1, cv::Scalar(1));
  ASSERT_TRUE(cv::imwrite(m.dir + "/masks/1.0333330.png", ids));
  writeText(m.dir + "/masks/1.0333330.txt", "1 cup 0.8\n");
  {
    TumSource s(m.dir, core::SourceOptions{});
    EXPECT_TRUE(anyContains(s.openWarnings(), kNoMatch));
    EXPECT_TRUE(anyContains(s.openWarnings(), "first frame: '1.000000.txt'"));
  }
  // One list that matches a frame: no warning.
  ASSERT_TRUE(cv::imwrite(m.dir + "/masks/1.033333.png", ids));
  writeText(m.dir + "/masks/1.033333.txt", "1 cup 0.8\n");
  EXPECT_FALSE(anyContains(TumSource(m.dir, core::SourceOptions{}).openWarnings(), kNoMatch));
  // The 7-Scenes millimetres read at the default 5000 units per metre, and at their own scale.
  const std::string kitchen = test::dataPath("redkitchen-0-299");
  core::SourceOptions options;
  options.max_frames = 1;
  EXPECT_TRUE(anyContains(TumSource(kitchen, options).openWarnings(), "?depth_scale=1000"));
  options.depth_scale = 1000;
  EXPECT_TRUE(TumSource(kitchen, options).openWarnings().empty());
}

TEST(TumSource, BrokenFoldersGiveErrorsNamingFileAndLine) {
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    fs::remove(m.dir + "/depth/2.0.png");
    auto s = sources::openSource("tum:" + m.dir, core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    expectErrorContaining([&] { s->next(f); },
                          {m.dir + "/depth.txt:4", "depth/2.0.png", "does not exist"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    ASSERT_TRUE(cv::imwrite(m.dir + "/depth/2.0.png", cv::Mat(kSmall, CV_8UC1, cv::Scalar(9))));
    auto s = sources::openSource("tum:" + m.dir, core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    expectErrorContaining([&] { s->next(f); },
                          {"depth.txt:4", "8-bit 1-channel", "expected a 16-bit single-channel"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    ASSERT_TRUE(cv::imwrite(m.dir + "/depth/2.0.png", cv::Mat(4, 4, CV_16UC1, cv::Scalar(9))));
    auto s = sources::openSource("tum:" + m.dir, core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    expectErrorContaining([&] { s->next(f); }, {"depth.txt:4", "is 4x4", "8x6", "same size"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/depth.txt", "2.0 depth/2.0.png\n1.0 depth/1.0.png\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/depth.txt:2", "not after the previous one"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/rgb.txt", "1.0 rgb/1.0.png\n2.O rgb/2.0.png\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/rgb.txt:2", "timestamp '2.O' is not a number"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/rgb.txt", "1.0 rgb/1.0.png extra\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/rgb.txt:1", "expected 2 fields"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/groundtruth.txt", "# gt\n1.0 0 0 0 0 0 0 1\n2.0 0 NaN 0 0 0 0 1\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/groundtruth.txt:3", "NaN"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/associations.txt", "1.0 rgb/1.0.png 1.0\n");
    expectErrorContaining(
        [&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
        {m.dir + "/associations.txt:1", "expected 4 fields", "t_rgb rgb_file t_depth depth_file"});
  }
  {
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"}, /*calibration=*/false);
    expectErrorContaining(
        [&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
        {"no intrinsics", "calibration.txt", "?fx=..&fy=..&cx=..&cy=..", "not guessed"});
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir + "?fx=500&fy=500&cx=4", {}); },
                          {"missing: cy"});
    auto s =
        sources::openSource("tum:" + m.dir + "?fx=500&fy=501&cx=4&cy=3", core::SourceOptions{});
    EXPECT_EQ(s->intrinsics().fy, 501);
  }
  {
    // A principal point far off the 8x6 image is not a camera (the map's ray walks would be
    // unbounded): the error names the file.
    MiniFolder m({"1.0", "2.0"}, {"1.0", "2.0"});
    writeText(m.dir + "/calibration.txt", "10 11 1e9 3 8 6\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/calibration.txt", "cx=1e+09", "principal point"});
    writeText(m.dir + "/calibration.txt", "0.1 11 4 3 8 6\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {m.dir + "/calibration.txt", "1/20 of the image side"});
  }
  {
    MiniFolder m({"1.0"}, {"1.0"});
    writeText(m.dir + "/calibration.txt", "10 11 4 3 640 480\n");
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {"calibration.txt", "640x480", "8x6"});
  }
  {
    const std::string dir = test::tempDir("tum");
    expectErrorContaining([&] { sources::openSource("tum:" + dir, core::SourceOptions{}); },
                          {"not a TUM RGB-D folder", "associations.txt nor depth.txt"});
  }
  {
    // No rgb frame near any depth frame: said so (it used to say depth.txt is empty).
    MiniFolder m({"1.000", "2.000"}, {"5.000"});
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir, core::SourceOptions{}); },
                          {"none of the 2 depth frames", "rgb.txt", "same clock"});
    // A 0 s association window could never match (associate.py compares with <).
    expectErrorContaining([&] { sources::openSource("tum:" + m.dir + "?max_time_diff_s=0", {}); },
                          {"max_time_diff_s"});
  }
}

}  // namespace
}  // namespace emf::io
