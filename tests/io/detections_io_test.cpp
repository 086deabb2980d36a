// Detections on disk: masks/<timestamp>.png (uint16 ids) + masks/<timestamp>.txt.
#include "io/detections_io.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "io_test_util.h"
#include "test_support.h"

namespace emf::io {
namespace {

using testing::expectErrorContaining;
using testing::writeText;

const cv::Size kSize(40, 30);
const cv::Rect kBox1(3, 4, 10, 6);
const cv::Rect kBox2(20, 10, 5, 15);

// Two detections: id 1 in kBox1, id 2 in kBox2 minus one pixel.
cv::Mat twoDetectionIds() {
  cv::Mat ids(kSize, CV_16UC1, cv::Scalar(0));
  ids(kBox1).setTo(1);
  ids(kBox2).setTo(2);
  ids.at<uint16_t>(kBox2.y, kBox2.x) = 0;
  return ids;
}

struct Files {
  std::string dir, png, txt;
};

Files writeFrame(const cv::Mat& ids, const std::string& txt, const std::string& stamp = "1.5") {
  Files f;
  f.dir = test::tempDir("det") + "/masks";
  f.png = f.dir + "/" + stamp + ".png";
  f.txt = f.dir + "/" + stamp + ".txt";
  writeText(f.txt, txt);
  EXPECT_TRUE(cv::imwrite(f.png, ids));
  return f;
}

TEST(DetectionsIo, ReadsIdsClassesScoresBoxesAndMasks) {
  const Files f = writeFrame(twoDetectionIds(),
                             "# det_id class_name score\n2 car 0.75\n"
                             "1 teddy_bear 0.9\n");
  const auto dets = readFrameDetections(f.dir, "1.5", kSize);
  ASSERT_TRUE(dets.has_value());
  ASSERT_EQ(dets->size(), 2u);
  const core::Detection& d1 = (*dets)[0];
  EXPECT_EQ(d1.id, 1);
  EXPECT_EQ(d1.class_name, "teddy bear");
  EXPECT_FLOAT_EQ(d1.score, 0.9f);
  EXPECT_EQ(d1.box, kBox1);
  ASSERT_EQ(d1.mask.type(), CV_32FC1);
  ASSERT_EQ(d1.mask.size(), kSize);
  EXPECT_EQ(cv::sum(d1.mask)[0], kBox1.area());
  EXPECT_EQ(cv::countNonZero(d1.mask), kBox1.area());  // so every mask value is 0 or 1
  const core::Detection& d2 = (*dets)[1];
  EXPECT_EQ(d2.class_name, "car");
  EXPECT_EQ(d2.box, kBox2);  // the missing corner pixel does not shrink the box
  EXPECT_EQ(cv::sum(d2.mask)[0], kBox2.area() - 1);
  EXPECT_EQ(d2.mask.at<float>(kBox2.y, kBox2.x), 0.f);
  EXPECT_EQ(d2.mask.at<float>(kBox2.y + 1, kBox2.x), 1.f);
}

TEST(DetectionsIo, UnlabelledAndEmptyFrames) {
  const std::string dir = test::tempDir("det");
  EXPECT_FALSE(readFrameDetections(dir, "1.5", kSize).has_value());
  const Files f = writeFrame(cv::Mat(kSize, CV_16UC1, cv::Scalar(0)), "# nothing found\n");
  const auto dets = readFrameDetections(f.dir, "1.5", kSize);
  ASSERT_TRUE(dets.has_value());
  EXPECT_TRUE(dets->empty());
}

TEST(DetectionsIo, InconsistentFilesAreErrorsNamingThem) {
  const cv::Mat ids = twoDetectionIds();
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.png, "pixels with id 2", f.txt, "no line for detection 2"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n2 car 0.5\n3 dog 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt + ":3", "detection 3 has no pixels"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n2 car 1.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt + ":2", "score 1.5 is outside [0, 1]"});
  }
  {
    const Files f = writeFrame(ids, "1 cup high\n2 car 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt + ":1", "score 'high' is not a number"});
  }
  {
    const Files f = writeFrame(ids, "1 ice cream 0.5\n2 car 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt + ":1", "expected 3 fields", "'_' for spaces"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n1 car 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt + ":2", "listed twice"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n2 car 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", cv::Size(64, 48)); },
                          {f.png, "is 40x30 but the depth image is 64x48"});
  }
  {
    cv::Mat ids8;
    ids.convertTo(ids8, CV_8U);
    const Files f = writeFrame(ids8, "1 cup 0.5\n2 car 0.5\n");
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.png, "8-bit 1-channel", "16-bit single-channel"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n2 car 0.5\n");
    std::filesystem::remove(f.txt);
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.txt, "does not exist"});
  }
  {
    const Files f = writeFrame(ids, "1 cup 0.5\n2 car 0.5\n");
    std::filesystem::remove(f.png);
    expectErrorContaining([&] { readFrameDetections(f.dir, "1.5", kSize); },
                          {f.png, "does not exist"});
  }
}

}  // namespace
}  // namespace emf::io
