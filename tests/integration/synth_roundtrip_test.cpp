// The synthetic world through the writers and back through the readers: every preset -> TUM
// folder -> tum: reader, and synth -> KLG -> klg: reader. Depth must come back bit-exactly
// (after the format's quantisation), poses and detections as written.
#include <cmath>

#include "core/frame_source.h"
#include "io/klg.h"
#include "io/tum_writer.h"
#include "sources/open_source.h"
#include "test_support.h"

namespace emf::io {
namespace {

constexpr double kPoseTolerance = 1e-6;  // TUM files carry 9 decimals; pose interpolation exact

/// Depth as a writer with `scale` units per metre stores it (0 = invalid -> NaN).
cv::Mat quantised(const cv::Mat& depth_m, double scale) {
  cv::Mat out(depth_m.size(), CV_32F);
  for (int y = 0; y < depth_m.rows; ++y) {
    for (int x = 0; x < depth_m.cols; ++x) {
      const float d = depth_m.at<float>(y, x);
      const double units = std::isfinite(d) && d > 0 ? std::round(d * scale) : 0.0;
      out.at<float>(y, x) =
          (units <= 0 || units > 65535) ? std::nanf("") : static_cast<float>(units / scale);
    }
  }
  return out;
}

/// Bitwise equality of two depth images, NaN == NaN. Returns the number of differing pixels.
int depthMismatches(const cv::Mat& a, const cv::Mat& b) {
  int bad = 0;
  for (int y = 0; y < a.rows; ++y) {
    for (int x = 0; x < a.cols; ++x) {
      const float u = a.at<float>(y, x), v = b.at<float>(y, x);
      if (std::isnan(u) != std::isnan(v) || (!std::isnan(u) && u != v)) ++bad;
    }
  }
  return bad;
}

class SynthRoundTrip : public ::testing::TestWithParam<std::string> {};

TEST_P(SynthRoundTrip, TumFolderReadsBackExactly) {
  const std::string preset = GetParam();
  const std::string dir = test::tempDir("roundtrip-" + preset);
  core::SourceOptions options;
  // Detections every 4 frames so a short sequence carries some.
  auto synth = sources::openSource("synth:" + preset + "?frames=9&width=160&height=120&det_every=4",
                                   options);
  std::vector<core::Frame> frames;
  {
    TumWriter writer(dir, synth->intrinsics());
    core::Frame f;
    while (synth->next(f)) {
      writer.write(f);
      frames.push_back(f);
    }
    writer.finish();
  }
  auto tum = sources::openSource("tum:" + dir, options);  // calibration.txt, depth scale 5000
  EXPECT_EQ(tum->intrinsics().width, 160);
  EXPECT_NEAR(tum->intrinsics().fx, synth->intrinsics().fx, 1e-6);
  core::Frame r;
  size_t i = 0, with_detections = 0;
  while (tum->next(r)) {
    ASSERT_LT(i, frames.size());
    const core::Frame& w = frames[i];
    EXPECT_EQ(r.timestamp_text, w.timestamp_text);
    EXPECT_EQ(depthMismatches(r.depth, quantised(w.depth, 5000.0)), 0) << "frame " << i;
    ASSERT_TRUE(r.T_world_camera_gt && w.T_world_camera_gt);
    EXPECT_TRUE(r.T_world_camera_gt->isApprox(*w.T_world_camera_gt, kPoseTolerance))
        << "frame " << i;
    EXPECT_EQ(r.detections.has_value(), w.detections.has_value()) << "frame " << i;
    if (r.detections && w.detections) {
      ++with_detections;
      // Overlapping masks share one id image (the higher score wins), so a read detection is
      // the written one with the same id, minus what higher-scoring ones cover.
      ASSERT_LE(r.detections->size(), w.detections->size());
      for (const core::Detection& a : *r.detections) {
        const core::Detection* b = nullptr;
        for (const core::Detection& c : *w.detections) {
          if (c.id == a.id) b = &c;
        }
        ASSERT_NE(b, nullptr) << "frame " << i << " detection " << a.id;
        EXPECT_EQ(a.class_name, b->class_name);
        EXPECT_NEAR(a.score, b->score, 1e-6);
        const cv::Mat read = a.mask > 0.5f, written = b->mask >= 0.5f;
        EXPECT_GT(cv::countNonZero(read), 0);
        EXPECT_EQ(cv::countNonZero(read & ~written), 0) << "read pixels outside the written mask";
      }
    }
    ++i;
  }
  EXPECT_EQ(i, frames.size());
  EXPECT_GE(with_detections, 2u);
}

INSTANTIATE_TEST_SUITE_P(Presets, SynthRoundTrip,
                         ::testing::Values("room", "cars", "occlusion", "enter"));

TEST(SynthKlg, RoundTripIsBitExactAtMillimetres) {
  const std::string path = test::tempDir("klg") + "/cars.klg";
  core::SourceOptions options;
  auto synth = sources::openSource("synth:cars?frames=6&width=160&height=120", options);
  std::vector<core::Frame> frames;
  {
    KlgWriter writer(path);
    core::Frame f;
    while (synth->next(f)) {
      writer.write(f);
      frames.push_back(f);
    }
    writer.close();
  }
  const core::Intrinsics k = synth->intrinsics();
  auto klg =
      sources::openSource("klg:" + path + "?width=160&height=120&fx=" + std::to_string(k.fx) +
                              "&fy=" + std::to_string(k.fy) + "&cx=" + std::to_string(k.cx) +
                              "&cy=" + std::to_string(k.cy),
                          options);
  core::Frame r;
  size_t i = 0;
  while (klg->next(r)) {
    ASSERT_LT(i, frames.size());
    EXPECT_EQ(depthMismatches(r.depth, quantised(frames[i].depth, 1000.0)), 0) << "frame " << i;
    EXPECT_NEAR(r.timestamp, frames[i].timestamp, 1e-6);
    EXPECT_EQ(r.color.size(), frames[i].color.size());
    ++i;
  }
  EXPECT_EQ(i, frames.size());
}

}  // namespace
}  // namespace emf::io
