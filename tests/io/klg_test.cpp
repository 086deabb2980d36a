// KLG writer and reader: bit-exact depth round trip on real frames, quantisation, raw blocks,
// atomic writing and errors on truncated/mismatched files.
#include "io/klg.h"

#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "io/depth_image.h"
#include "io_test_util.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::io {
namespace {
namespace fs = std::filesystem;

using testing::expectErrorContaining;

// JPEG at quality 90 of an already-JPEG image: PSNR well above this.
constexpr double kMinJpegPsnrDb = 30.0;

const char* kIntrinsicsQuery = "?fx=585&fy=585&cx=320&cy=240";

bool sameBits(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

size_t filesIn(const std::string& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(Klg, RoundTripOfRealFramesIsBitExactForDepth) {
  // 7-Scenes depth is millimetres, the KLG unit: frames -> KLG -> frames is lossless.
  auto tum = sources::openSource(
      "tum:" + test::dataPath("redkitchen-0-299") + "?depth_scale=1000&max_frames=8",
      core::SourceOptions{});
  std::vector<core::Frame> frames;
  core::Frame f;
  while (tum->next(f)) frames.push_back(f);
  ASSERT_EQ(frames.size(), 8u);
  frames[3].color = cv::Mat();  // one frame without colour

  const std::string dir = test::tempDir("klg");
  const std::string path = dir + "/seq.klg";
  KlgWriter w(path);
  for (const auto& fr : frames) w.write(fr);
  EXPECT_FALSE(fs::exists(path)) << "visible before close()";
  w.close();
  EXPECT_EQ(filesIn(dir), 1u);

  auto klg = sources::openSource("klg:" + path + kIntrinsicsQuery, core::SourceOptions{});
  EXPECT_EQ(klg->size(), 8);
  EXPECT_EQ(klg->intrinsics().fx, 585);
  EXPECT_EQ(klg->intrinsics().width, 640);
  for (size_t i = 0; i < frames.size(); ++i) {
    ASSERT_TRUE(klg->next(f)) << i;
    EXPECT_TRUE(sameBits(f.depth, frames[i].depth)) << "frame " << i;
    EXPECT_EQ(f.timestamp_text, frames[i].timestamp_text);  // "%.6f" microseconds
    EXPECT_NEAR(f.timestamp, frames[i].timestamp, 1e-6);
    if (i == 3) {
      EXPECT_TRUE(f.color.empty());
    } else {
      ASSERT_EQ(f.color.size(), frames[i].color.size());
      EXPECT_GT(cv::PSNR(f.color, frames[i].color), kMinJpegPsnrDb) << "frame " << i;
    }
  }
  EXPECT_FALSE(klg->next(f));
}

TEST(Klg, QuantisesToMillimetresAndMarksUnrepresentableDepthInvalid) {
  core::Frame in;
  in.timestamp = 12.5;
  in.depth = cv::Mat(6, 8, CV_32FC1, cv::Scalar(1.23456f));
  in.depth.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
  in.depth.at<float>(0, 1) = -0.5f;
  in.depth.at<float>(0, 2) = 70.0f;    // > 65.535 m
  in.depth.at<float>(0, 3) = 0.0004f;  // rounds to 0 mm
  in.depth.at<float>(0, 4) = 65.535f;  // the largest representable
  const std::string path = test::tempDir("klg") + "/q.klg";
  KlgWriter w(path);
  w.write(in);
  w.close();
  auto s = sources::openSource("klg:" + path + kIntrinsicsQuery + "&width=8&height=6",
                               core::SourceOptions{});
  core::Frame out;
  ASSERT_TRUE(s->next(out));
  for (int x = 0; x < 4; ++x) EXPECT_TRUE(std::isnan(out.depth.at<float>(0, x))) << x;
  EXPECT_EQ(out.depth.at<float>(0, 4), static_cast<float>(65535 / 1000.0));
  EXPECT_EQ(out.depth.at<float>(3, 3), static_cast<float>(1235 / 1000.0));
  EXPECT_DOUBLE_EQ(out.timestamp, 12.5);
  EXPECT_TRUE(out.color.empty());
}

// Hand-written KLG with a raw (uncompressed) depth block and raw RGB colour, the other two
// encodings the format allows.
TEST(Klg, ReadsRawDepthAndRawRgbBlocks) {
  const cv::Size size(4, 3);
  cv::Mat depth_mm(size, CV_16UC1);
  for (int i = 0; i < 12; ++i) depth_mm.at<uint16_t>(i / 4, i % 4) = static_cast<uint16_t>(i * 100);
  cv::Mat rgb(size, CV_8UC3, cv::Scalar(200, 100, 50));  // R=200 G=100 B=50 in memory order
  const std::string path = test::tempDir("klg") + "/raw.klg";
  {
    std::ofstream out(path, std::ios::binary);
    const int32_t count = 1, dsize = 24, isize = 36;
    const int64_t t = 1000000;
    out.write(reinterpret_cast<const char*>(&count), 4);
    out.write(reinterpret_cast<const char*>(&t), 8);
    out.write(reinterpret_cast<const char*>(&dsize), 4);
    out.write(reinterpret_cast<const char*>(&isize), 4);
    out.write(reinterpret_cast<const char*>(depth_mm.data), 24);
    out.write(reinterpret_cast<const char*>(rgb.data), 36);
  }
  auto s = sources::openSource("klg:" + path + kIntrinsicsQuery + "&width=4&height=3",
                               core::SourceOptions{});
  core::Frame f;
  ASSERT_TRUE(s->next(f));
  EXPECT_TRUE(sameBits(f.depth, depthFromUnits(depth_mm, 1000.0)));
  EXPECT_EQ(f.color.at<cv::Vec3b>(1, 1), cv::Vec3b(50, 100, 200));  // BGR
  EXPECT_DOUBLE_EQ(f.timestamp, 1.0);
}

TEST(Klg, WriterWithoutCloseLeavesNothingAndRejectsBadFrames) {
  const std::string dir = test::tempDir("klg");
  {
    KlgWriter w(dir + "/x.klg");
    core::Frame f;
    f.depth = cv::Mat(6, 8, CV_32FC1, cv::Scalar(1.0f));
    f.timestamp = 1;
    w.write(f);
    core::Frame g = f;
    expectErrorContaining([&] { w.write(g); }, {"frame 1", "not after the previous"});
    g.timestamp = 2;
    g.depth = cv::Mat(6, 9, CV_32FC1, cv::Scalar(1.0f));
    expectErrorContaining([&] { w.write(g); }, {"9x6", "first frame's is 8x6"});
    g.depth = cv::Mat(6, 8, CV_16UC1, cv::Scalar(1));
    expectErrorContaining([&] { w.write(g); }, {"CV_32F"});
  }
  EXPECT_EQ(filesIn(dir), 0u);
}

TEST(Klg, BrokenFilesGiveErrorsNamingFrameAndOffset) {
  const std::string dir = test::tempDir("klg");
  const std::string path = dir + "/t.klg";
  {
    KlgWriter w(path);
    for (int i = 0; i < 3; ++i) {
      core::Frame f;
      f.timestamp = i;
      f.depth = cv::Mat(6, 8, CV_32FC1, cv::Scalar(1.0f + i));
      f.color = cv::Mat(6, 8, CV_8UC3, cv::Scalar(1, 2, 3));
      w.write(f);
    }
    w.close();
  }
  const std::string q = std::string(kIntrinsicsQuery) + "&width=8&height=6";
  // A recording that was not closed (count 0, as KlgWriter writes first) or a stale count: every
  // complete frame is read (they were silently ignored: 0 frames, an empty run).
  for (const int32_t count : {0, 1}) {
    const std::string open_file = dir + "/open" + std::to_string(count) + ".klg";
    fs::copy_file(path, open_file);
    {
      std::fstream patch(open_file, std::ios::in | std::ios::out | std::ios::binary);
      patch.write(reinterpret_cast<const char*>(&count), 4);
    }
    auto s = sources::openSource("klg:" + open_file + q, core::SourceOptions{});
    EXPECT_EQ(s->size(), 3) << count;
    core::Frame f;
    for (int i = 0; i < 3; ++i) {
      ASSERT_TRUE(s->next(f)) << count << " " << i;
      EXPECT_EQ(f.timestamp, i);
      EXPECT_EQ(f.depth.at<float>(0, 0), 1.0f + i);
    }
    EXPECT_FALSE(s->next(f));
  }
  // Truncated: cut the last frame in half.
  const std::string cut = dir + "/cut.klg";
  fs::copy_file(path, cut);
  fs::resize_file(cut, fs::file_size(path) - 20);
  {
    auto s = sources::openSource("klg:" + cut + q, core::SourceOptions{});
    core::Frame f;
    ASSERT_TRUE(s->next(f));
    ASSERT_TRUE(s->next(f));
    expectErrorContaining([&] { s->next(f); }, {cut, "frame 2", "bytes left in the file",
                                                "announces 3 frames", "truncated"});
  }
  // Cut inside a frame header.
  fs::resize_file(cut, 10);
  {
    auto s = sources::openSource("klg:" + cut + q, core::SourceOptions{});
    core::Frame f;
    expectErrorContaining([&] { s->next(f); },
                          {cut, "frame 0", "file ends at byte 10", "timestamp", "truncated"});
  }
  // Wrong image size for the depth blocks.
  {
    auto s = sources::openSource("klg:" + path + kIntrinsicsQuery + "&width=640&height=480", {});
    core::Frame f;
    expectErrorContaining(
        [&] { s->next(f); },
        {"frame 0 (at byte 4)", "does not decompress to 640x480", "?width=&height="});
  }
  expectErrorContaining([&] { sources::openSource("klg:" + path, core::SourceOptions{}); },
                        {"no intrinsics", "?fx=..&fy=..&cx=..&cy=.."});
  expectErrorContaining(
      [&] { sources::openSource("klg:" + dir + "/none.klg" + q, core::SourceOptions{}); },
      {"none.klg", "does not exist"});
  {
    const std::string empty = dir + "/empty.klg";
    std::ofstream(empty, std::ios::binary) << "ab";
    expectErrorContaining([&] { sources::openSource("klg:" + empty + q, core::SourceOptions{}); },
                          {"file ends at byte 2 while reading the frame count",
                           "not a KLG file (empty or truncated)"});
  }
  {
    const std::string neg = dir + "/neg.klg";
    std::ofstream out(neg, std::ios::binary);
    const int32_t count = -5;
    out.write(reinterpret_cast<const char*>(&count), 4);
    out.close();
    expectErrorContaining([&] { sources::openSource("klg:" + neg + q, core::SourceOptions{}); },
                          {"frame count -5 is negative"});
  }
}

}  // namespace
}  // namespace emf::io
