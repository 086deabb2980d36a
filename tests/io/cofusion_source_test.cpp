// The Co-Fusion folder reader on a folder generated here (EXR depth through Debian's OpenCV).
#include "io/cofusion_source.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "io/depth_image.h"
#include "io_test_util.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::io {
namespace {
namespace fs = std::filesystem;

using testing::expectErrorContaining;
using testing::writeText;

const cv::Size kSize(16, 12);

cv::Mat depthOf(int frame) {
  cv::Mat d(kSize, CV_32FC1);
  for (int y = 0; y < d.rows; ++y) {
    for (int x = 0; x < d.cols; ++x) d.at<float>(y, x) = 0.5f + 0.01f * x + 0.1f * y + frame;
  }
  d.at<float>(0, 0) = 0.f;    // invalid
  d.at<float>(0, 1) = 1e10f;  // renderer "no hit"
  d.at<float>(0, 2) = -1.f;   // invalid
  return d;
}

// Color0001..0003.png, Depth0001..0003.exr in depth_subdir, calibration.txt, masks_id/Mask0002.png.
std::string makeFolder(const std::string& depth_subdir = "") {
  enableOpenExr();
  const std::string dir = test::tempDir("cofusion");
  fs::create_directories(dir + "/" + depth_subdir);
  fs::create_directories(dir + "/masks_id");
  for (int i = 1; i <= 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%04d", i);
    EXPECT_TRUE(cv::imwrite(dir + "/Color" + name + ".png",
                            cv::Mat(kSize, CV_8UC3, cv::Scalar(i, 2 * i, 3 * i))));
    EXPECT_TRUE(cv::imwrite(dir + "/" + depth_subdir + "/Depth" + name + ".exr", depthOf(i),
                            {cv::IMWRITE_EXR_TYPE, cv::IMWRITE_EXR_TYPE_FLOAT}));
  }
  cv::Mat ids(kSize, CV_8UC1, cv::Scalar(0));
  ids(cv::Rect(4, 4, 5, 3)).setTo(2);
  EXPECT_TRUE(cv::imwrite(dir + "/masks_id/Mask0002.png", ids));
  writeText(dir + "/calibration.txt", "20 21 8 6 16 12\n");
  return dir;
}

TEST(CoFusionSource, ReadsExrDepthColourAndInstanceIds) {
  for (const char* sub : {"", "depth_noise"}) {
    const std::string dir = makeFolder(sub);
    auto s = sources::openSource("cofusion:" + dir, core::SourceOptions{});
    EXPECT_EQ(s->size(), 3);
    EXPECT_EQ(s->intrinsics().fx, 20);
    EXPECT_EQ(s->intrinsics().fy, 21);
    EXPECT_EQ(s->intrinsics().width, 16);
    core::Frame f;
    for (int i = 1; i <= 3; ++i) {
      ASSERT_TRUE(s->next(f)) << i;
      EXPECT_EQ(f.index, i - 1);
      EXPECT_DOUBLE_EQ(f.timestamp, (i - 1) / 30.0);
      ASSERT_EQ(f.depth.type(), CV_32FC1);
      const cv::Mat expected = depthOf(i);
      int mismatches = 0;
      for (int y = 0; y < kSize.height; ++y) {
        for (int x = 0; x < kSize.width; ++x) {
          const float e = expected.at<float>(y, x), d = f.depth.at<float>(y, x);
          const bool invalid = y == 0 && x < 3;
          mismatches += invalid ? !std::isnan(d) : d != e;  // float EXR is lossless
        }
      }
      EXPECT_EQ(mismatches, 0) << "frame " << i;
      EXPECT_EQ(f.color.at<cv::Vec3b>(5, 5), cv::Vec3b(i, 2 * i, 3 * i));
      if (i == 2) {
        ASSERT_EQ(f.instance_ids.type(), CV_16UC1);
        EXPECT_EQ(cv::countNonZero(f.instance_ids == 2), 15);
        EXPECT_EQ(cv::countNonZero(f.instance_ids), 15);
      } else {
        EXPECT_TRUE(f.instance_ids.empty());
      }
    }
    EXPECT_FALSE(s->next(f));
  }
}

TEST(CoFusionSource, ErrorsNameTheFiles) {
  {
    const std::string dir = makeFolder();
    fs::remove(dir + "/Color0002.png");
    expectErrorContaining([&] { sources::openSource("cofusion:" + dir, core::SourceOptions{}); },
                          {"Depth0002.exr", "no colour image"});
  }
  {
    const std::string dir = makeFolder();
    writeText(dir + "/Depth0002.exr", "not an exr");
    auto s = sources::openSource("cofusion:" + dir, core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    expectErrorContaining([&] { s->next(f); }, {"cannot decode depth EXR", "Depth0002.exr"});
  }
  {
    const std::string dir = makeFolder();
    fs::remove(dir + "/calibration.txt");
    expectErrorContaining([&] { sources::openSource("cofusion:" + dir, core::SourceOptions{}); },
                          {"no intrinsics", "calibration.txt"});
    auto s = sources::openSource("cofusion:" + dir + "?fx=1&fy=2&cx=3&cy=4&fps=10",
                                 core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    ASSERT_TRUE(s->next(f));
    EXPECT_DOUBLE_EQ(f.timestamp, 0.1);
  }
  {
    const std::string dir = test::tempDir("cofusion");
    expectErrorContaining([&] { sources::openSource("cofusion:" + dir, core::SourceOptions{}); },
                          {"not a Co-Fusion folder", "Depth####.exr"});
  }
  {
    // The same number padded twice: one file would have been dropped without a word.
    const std::string dir = makeFolder();
    fs::copy_file(dir + "/Depth0003.exr", dir + "/Depth3.exr");
    expectErrorContaining([&] { sources::openSource("cofusion:" + dir, core::SourceOptions{}); },
                          {"Depth3.exr", "Depth0003.exr", "both have number 3"});
  }
}

TEST(CoFusionSource, AGapInTheNumberingIsAGapInTime) {
  // Frames 1 and 3: 2 / 30 s apart, as recorded (they were 1 / 30 s apart).
  const std::string dir = makeFolder();
  fs::remove(dir + "/Depth0002.exr");
  fs::remove(dir + "/Color0002.png");
  auto s = sources::openSource("cofusion:" + dir, core::SourceOptions{});
  EXPECT_EQ(s->size(), 2);
  core::Frame f;
  ASSERT_TRUE(s->next(f));
  EXPECT_DOUBLE_EQ(f.timestamp, 0.0);
  ASSERT_TRUE(s->next(f));
  EXPECT_EQ(f.index, 1);
  EXPECT_DOUBLE_EQ(f.timestamp, 2 / 30.0);
  EXPECT_EQ(f.color.at<cv::Vec3b>(5, 5), cv::Vec3b(3, 6, 9));
}

}  // namespace
}  // namespace emf::io
