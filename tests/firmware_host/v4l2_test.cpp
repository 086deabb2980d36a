// The V4L2 backend: pixel-format conversions against independent references, the driver-size
// fix-ups, depth/colour pairing by timestamp, and the error messages for nodes that are missing
// or not cameras. The capture test runs against every depth-capable /dev/video* node and skips
// (with the reason) when the machine has none.
#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "common/error.h"
#include "firmware_host/v4l2/frame_pairer.h"
#include "firmware_host/v4l2/pixel_formats.h"
#include "firmware_host/v4l2/v4l2_device.h"
#include "firmware_host/v4l2/v4l2_source.h"

namespace emf::fw {
namespace {

// OpenCV's YUYV conversion uses 20-bit fixed-point BT.601 coefficients; the double-precision
// reference below may differ by one level after rounding.
constexpr double kYuyvToleranceLevels = 1.0;
// JPEG at quality 95 of a smooth test image: mean absolute error per channel, levels.
constexpr double kMjpegMeanErrorLevels = 2.0;

uint8_t clamp8(double v) {
  return static_cast<uint8_t>(std::min(255.0, std::max(0.0, std::round(v))));
}

/// ITU-R BT.601 limited range YUV -> BGR, in double precision. Luma footroom (Y < 16) is black.
cv::Vec3b referenceYuvToBgr(int y, int u, int v) {
  const double c = 1.164 * std::max(0, y - 16), d = u - 128.0, e = v - 128.0;
  return {clamp8(c + 2.018 * d), clamp8(c - 0.391 * d - 0.813 * e), clamp8(c + 1.596 * e)};
}

TEST(V4l2PixelFormats, YuyvToBgrMatchesBt601Reference) {
  const int w = 16, h = 5;
  const size_t stride = 2 * w + 8;  // padded lines, as drivers may report
  std::vector<uint8_t> buf(stride * h, 0xee);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; x += 2) {
      uint8_t* p = &buf[y * stride + 2 * x];
      p[0] = static_cast<uint8_t>(16 + 13 * x + 7 * y);  // Y0
      p[1] = static_cast<uint8_t>(40 + 11 * x);          // U
      p[2] = static_cast<uint8_t>(30 + 15 * x + 9 * y);  // Y1
      p[3] = static_cast<uint8_t>(200 - 9 * x - 5 * y);  // V
    }
  }
  cv::Mat bgr;
  yuyvToBgr(buf.data(), w, h, stride, bgr);
  ASSERT_EQ(bgr.type(), CV_8UC3);
  ASSERT_EQ(bgr.size(), cv::Size(w, h));
  double max_err = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t* p = &buf[y * stride + 2 * (x & ~1)];
      const cv::Vec3b ref = referenceYuvToBgr((x & 1) ? p[2] : p[0], p[1], p[3]);
      for (int c = 0; c < 3; ++c) {
        max_err = std::max(max_err, std::fabs(double(bgr.at<cv::Vec3b>(y, x)[c]) - ref[c]));
      }
    }
  }
  EXPECT_LE(max_err, kYuyvToleranceLevels);
}

std::vector<uint8_t> encodeJpeg(const cv::Mat& bgr) {
  std::vector<uint8_t> jpg;
  cv::imencode(".jpg", bgr, jpg, {cv::IMWRITE_JPEG_QUALITY, 95});
  return jpg;
}

/// Removes every DHT (Huffman table) segment, as many UVC cameras send MJPEG.
std::vector<uint8_t> stripHuffmanTables(const std::vector<uint8_t>& jpg) {
  std::vector<uint8_t> out(jpg.begin(), jpg.begin() + 2);
  size_t i = 2;
  while (i + 4 <= jpg.size()) {
    const uint8_t marker = jpg[i + 1];
    const size_t len = (size_t(jpg[i + 2]) << 8) | jpg[i + 3];
    if (marker == 0xda) {  // start of scan: the rest is entropy-coded data
      out.insert(out.end(), jpg.begin() + static_cast<long>(i), jpg.end());
      break;
    }
    if (marker != 0xc4) {
      out.insert(out.end(), jpg.begin() + static_cast<long>(i),
                 jpg.begin() + static_cast<long>(i + 2 + len));
    }
    i += 2 + len;
  }
  return out;
}

TEST(V4l2PixelFormats, MjpegDecodesWithAndWithoutHuffmanTables) {
  cv::Mat img(48, 64, CV_8UC3);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uchar>(4 * x), static_cast<uchar>(5 * y),
                                          static_cast<uchar>(2 * x + 2 * y));
    }
  }
  const auto jpg = encodeJpeg(img);
  const auto bare = stripHuffmanTables(jpg);
  ASSERT_LT(bare.size(), jpg.size());  // the tables really were removed
  cv::Mat full, stripped;
  ASSERT_TRUE(decodeMjpeg(jpg.data(), jpg.size(), full));
  ASSERT_TRUE(decodeMjpeg(bare.data(), bare.size(), stripped));
  EXPECT_LE(cv::norm(full, img, cv::NORM_L1) / static_cast<double>(img.total() * 3),
            kMjpegMeanErrorLevels);
  // OpenCV's encoder writes the standard tables, so the decoder's defaults reproduce them.
  EXPECT_EQ(cv::norm(full, stripped, cv::NORM_INF), 0.0);
  std::vector<uint8_t> garbage = {0xff, 0xd8, 0x00, 0x01, 0x02};
  cv::Mat out;
  EXPECT_FALSE(decodeMjpeg(garbage.data(), garbage.size(), out));
  EXPECT_FALSE(decodeMjpeg(jpg.data(), 1, out));
}

TEST(V4l2PixelFormats, Depth16ToMetresWithPaddedStride) {
  const int w = 5, h = 3;
  const size_t stride = 2 * w + 6;
  std::vector<uint8_t> buf(stride * h, 0xab);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint16_t v = static_cast<uint16_t>(x == y ? 0 : 1000 * (y + 1) + 37 * x);
      buf[y * stride + 2 * x] = static_cast<uint8_t>(v & 0xff);  // little-endian (V4L2)
      buf[y * stride + 2 * x + 1] = static_cast<uint8_t>(v >> 8);
    }
  }
  cv::Mat depth;
  depth16ToMetres(buf.data(), w, h, stride, 0.001, depth);
  ASSERT_EQ(depth.type(), CV_32FC1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (x == y) {
        EXPECT_TRUE(std::isnan(depth.at<float>(y, x)));
      } else {
        EXPECT_EQ(depth.at<float>(y, x), static_cast<float>((1000 * (y + 1) + 37 * x) * 0.001));
      }
    }
  }
  EXPECT_EQ(fourccName(V4L2_PIX_FMT_Z16), "Z16 ");
  EXPECT_EQ(fourccName(V4L2_PIX_FMT_MJPEG), "MJPG");
}

TEST(V4l2Device, DefensiveFormatFixUps) {
  V4l2Format f;
  f.width = 640;
  f.height = 480;
  f.bytes_per_line = 0;  // buggy driver
  f.size_image = 100;
  const V4l2Format g = fixUpFormat(f, 2);
  EXPECT_EQ(g.bytes_per_line, 1280u);
  EXPECT_EQ(g.size_image, 1280u * 480u);
  f.bytes_per_line = 1536;  // padded lines are kept
  f.size_image = 0;
  EXPECT_EQ(fixUpFormat(f, 2).bytes_per_line, 1536u);
  EXPECT_EQ(fixUpFormat(f, 2).size_image, 1536u * 480u);
  EXPECT_EQ(fixUpFormat(f, 0).size_image, 1u);  // compressed: whatever the driver says, >= 1
}

TimedImage at(double t, int64_t seq) {
  TimedImage i;
  i.timestamp_s = t;
  i.sequence = seq;
  i.image = cv::Mat(1, 1, CV_8UC1, cv::Scalar(static_cast<double>(seq % 256)));
  return i;
}

std::vector<PairedFrame> drain(FramePairer& p) {
  std::vector<PairedFrame> out;
  PairedFrame f;
  while (p.pop(&f)) out.push_back(f);
  return out;
}

TEST(FramePairer, SameRateWithOffsetPairsEachDepthWithItsColour) {
  FramePairer p(0.02);
  std::vector<PairedFrame> got;
  for (int i = 0; i < 10; ++i) {
    p.addDepth(at(i / 30.0, i));
    p.addColor(at(i / 30.0 + 0.006, 100 + i));  // colour 6 ms late
    for (auto& f : drain(p)) got.push_back(f);
  }
  p.flush();
  for (auto& f : drain(p)) got.push_back(f);
  ASSERT_EQ(got.size(), 10u);
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(got[i].depth.sequence, i);
    EXPECT_EQ(got[i].color.sequence, 100 + i);
  }
  EXPECT_EQ(p.stats().paired, 10);
  EXPECT_EQ(p.stats().depth_alone, 0);
}

TEST(FramePairer, HalfRateColourGoesToNearestDepthOnce) {
  FramePairer p(0.02);
  for (int i = 0; i < 8; ++i) {
    p.addDepth(at(i / 30.0, i));
    if (i % 2 == 0) p.addColor(at(i / 30.0 + 0.001, 100 + i));
  }
  p.flush();
  const auto got = drain(p);
  ASSERT_EQ(got.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    if (i % 2 == 0) {
      EXPECT_EQ(got[i].color.sequence, 100 + i) << i;
    } else {
      EXPECT_TRUE(got[i].color.image.empty()) << i;  // 32 ms from any colour: outside window
    }
  }
  EXPECT_EQ(p.stats().paired, 4);
  EXPECT_EQ(p.stats().depth_alone, 4);
}

TEST(FramePairer, StalledColourDoesNotHoldDepthBack) {
  FramePairer p(0.02, 3);
  p.addColor(at(0.0, 100));
  for (int i = 0; i < 6; ++i) p.addDepth(at(i / 30.0, i));
  const auto got = drain(p);
  // Depth 0 pairs at once (colour at its time); depth 1..5 wait for colour, and with more than
  // 3 pending the oldest go out alone: 1 and 2 leave, 3..5 still wait.
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].color.sequence, 100);
  EXPECT_TRUE(got[1].color.image.empty());
  EXPECT_TRUE(got[2].color.image.empty());
  EXPECT_EQ(got[2].depth.sequence, 2);
}

TEST(FramePairer, DropsTimestampsGoingBackwardsAndUnusableColour) {
  FramePairer p(0.01);
  p.addDepth(at(1.0, 1));
  p.addDepth(at(0.5, 2));      // backwards: dropped
  p.addColor(at(0.90, 100));   // too early for depth 1.0
  p.addColor(at(1.004, 101));  // the match
  p.addColor(at(1.003, 102));  // backwards: dropped
  p.addColor(at(1.05, 103));   // no depth near it
  p.addDepth(at(1.2, 3));
  p.flush();
  const auto got = drain(p);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].color.sequence, 101);
  EXPECT_TRUE(got[1].color.image.empty());
  EXPECT_EQ(p.stats().out_of_order, 2);
  EXPECT_EQ(p.stats().color_unused, 2);  // 0.90 and 1.05
}

template <typename Fn>
std::string errorOf(Fn&& fn) {
  try {
    fn();
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(V4l2Errors, MissingNodesNonCamerasAndMissingIntrinsics) {
  std::string e = errorOf([] { V4l2Device("/dev/video-emf-none"); });
  EXPECT_NE(e.find("/dev/video-emf-none"), std::string::npos) << e;
  EXPECT_NE(e.find("emf devices"), std::string::npos) << e;
  e = errorOf([] { V4l2Device("/dev/null"); });
  EXPECT_NE(e.find("/dev/null is not a V4L2 device"), std::string::npos) << e;
  e = errorOf([] { V4l2Device("/etc/hostname"); });
  EXPECT_NE(e.find("is not a device node"), std::string::npos) << e;

  core::SourceOptions options;
  e = errorOf([&] { V4l2Source("v4l2:/dev/null", options); });
  EXPECT_NE(e.find("does not report intrinsics"), std::string::npos) << e;
  e = errorOf([&] { V4l2Source("v4l2:/dev/null?fx=500&fy=500", options); });
  EXPECT_NE(e.find("not a V4L2 device"), std::string::npos) << e;
  e = errorOf([&] { V4l2Source("v4l2:/dev/null?fx=500&fy=500&fsp=30", options); });
  EXPECT_NE(e.find("unknown parameter 'fsp'"), std::string::npos) << e;
  e = errorOf([&] { V4l2Source("v4l2:?fx=500&fy=500", options); });
  EXPECT_NE(e.find("no device node"), std::string::npos) << e;
}

std::vector<std::string> depthNodes() {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) != 0) continue;
    try {
      V4l2Device dev(entry.path().string());
      for (uint32_t f : dev.formats()) {
        if (f == V4L2_PIX_FMT_Z16 || f == V4L2_PIX_FMT_Y16) nodes.push_back(entry.path());
      }
    } catch (const IoError&) {
    }
  }
  return nodes;
}

TEST(V4l2Capture, StreamsDepthFromConnectedCameras) {
  const auto nodes = depthNodes();
  if (nodes.empty()) {
    GTEST_SKIP() << "no V4L2 node with Z16/Y16 depth on this machine (/dev/video*): the "
                    "conversion and pairing tests above cover the device-independent code";
  }
  for (const auto& node : nodes) {
    core::SourceOptions options;
    V4l2Source src("v4l2:" + node + "?fx=600&fy=600", options);
    double last = -1;
    for (int i = 0; i < 5; ++i) {
      core::Frame f;
      ASSERT_TRUE(src.next(f)) << node;
      EXPECT_EQ(f.depth.type(), CV_32FC1);
      EXPECT_EQ(f.depth.cols, src.intrinsics().width);
      EXPECT_GT(f.timestamp, last);
      last = f.timestamp;
    }
  }
}

}  // namespace
}  // namespace emf::fw
