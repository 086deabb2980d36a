// The `motion` detector: hysteresis regions of high background residual, bounded by depth
// discontinuities, reported once persistent.
#include <cmath>

#include "motion_segmenter.h"
#include "pipeline/detector_plugin.h"
#include "test_support.h"

namespace emf_motion {
namespace {

constexpr int kW = 320, kH = 240;

struct Scene {
  cv::Mat depth = cv::Mat(kH, kW, CV_32F, cv::Scalar(2.0f));
  cv::Mat residual = cv::Mat(kH, kW, CV_32F, cv::Scalar(0.002f));
  cv::Mat q0;
};

TEST(MotionSegmenter, StaticSceneHasNoRegions) {
  MotionSegmenter s({});
  Scene sc;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
  EXPECT_TRUE(s.candidates().empty());
}

TEST(MotionSegmenter, PersistentRegionIsReportedAfterMinConsecutiveCalls) {
  MotionSegmenter s({});  // min_consecutive 2
  Scene sc;
  const cv::Rect obj(100, 60, 80, 70);
  sc.residual(obj).setTo(0.08f);
  EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
  ASSERT_EQ(s.candidates().size(), 1u);
  const auto out = s.update(sc.depth, sc.residual, sc.q0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].box, obj);
  EXPECT_EQ(cv::countNonZero(out[0].mask), obj.area());
  EXPECT_FLOAT_EQ(out[0].score, 1.f);
  EXPECT_EQ(out[0].age, 2);
}

TEST(MotionSegmenter, GrowthIntoWeakPixelsStopsAtDepthDiscontinuity) {
  MotionOptions o;
  o.min_consecutive = 1;
  MotionSegmenter s(o);
  Scene sc;
  // Strong core 60x60, weak halo extending 20 px right (same depth) and 20 px down (behind a
  // 0.5 m depth jump): the region takes the right halo, not the lower one.
  sc.residual(cv::Rect(100, 60, 80, 80)).setTo(0.02f);
  sc.residual(cv::Rect(100, 60, 60, 60)).setTo(0.08f);
  sc.depth(cv::Rect(0, 120, kW, kH - 120)).setTo(2.5f);
  const auto out = s.update(sc.depth, sc.residual, sc.q0);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].box, cv::Rect(100, 60, 80, 60));
  EXPECT_NEAR(out[0].score, 3600.0 / 4800.0, 1e-6);
}

TEST(MotionSegmenter, SizeLimitsAndAssociation) {
  MotionOptions o;
  o.min_consecutive = 1;
  MotionSegmenter s(o);
  Scene sc;
  // min_area_px 1600 at 640x480 is 400 px at 320x240: 19 x 19 = 361 px is noise.
  ASSERT_EQ(scaledMinArea(o, kW, kH), 400);
  sc.residual(cv::Rect(10, 10, 19, 19)).setTo(0.08f);
  EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
  sc.residual.setTo(0.08f);  // the whole image: tracking failure, not an object
  EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
  sc.residual.setTo(0.002f);
  sc.residual(cv::Rect(100, 60, 80, 70)).setTo(0.08f);
  sc.q0 = cv::Mat(kH, kW, CV_32F, cv::Scalar(1.0f));  // explained (e.g. a disocclusion)
  EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
  sc.q0.setTo(0.1f);
  EXPECT_EQ(s.update(sc.depth, sc.residual, sc.q0).size(), 1u);
  // Invalid depth never belongs to a region.
  sc.depth(cv::Rect(100, 60, 80, 70)).setTo(std::nanf(""));
  EXPECT_TRUE(s.update(sc.depth, sc.residual, sc.q0).empty());
}

TEST(MotionSegmenter, PixelSizesScaleWithTheImage) {
  MotionOptions o;  // min_area_px 1600, open_radius_px 2 (for 640x480)
  EXPECT_EQ(scaledMinArea(o, 640, 480), 1600);
  EXPECT_EQ(scaledMinArea(o, 1280, 960), 6400);
  EXPECT_EQ(scaledMinArea(o, 160, 120), 100);
  EXPECT_EQ(scaledOpenRadius(o, 640), 2);
  EXPECT_EQ(scaledOpenRadius(o, 1280), 4);
  EXPECT_EQ(scaledOpenRadius(o, 160), 1);  // never below 1 unless configured off
  o.open_radius_px = 0;
  EXPECT_EQ(scaledOpenRadius(o, 1280), 0);
  o.min_area_px = 0;
  EXPECT_EQ(scaledMinArea(o, 160, 120), 1);
  // The same 30 x 30 px region is noise at 640x480 (< 1600 px) and a region at 320x240 (> 400).
  for (const int w : {640, 320}) {
    MotionOptions one;
    one.min_consecutive = 1;
    MotionSegmenter s(one);
    const int h = w * 3 / 4;
    cv::Mat depth(h, w, CV_32F, cv::Scalar(2.0f)), residual(h, w, CV_32F, cv::Scalar(0.002f));
    residual(cv::Rect(10, 10, 30, 30)).setTo(0.08f);
    EXPECT_EQ(s.update(depth, residual, cv::Mat()).size(), w == 640 ? 0u : 1u) << w;
  }
}

TEST(MotionSegmenter, MovingRegionKeepsItsAge) {
  MotionSegmenter s({});
  Scene sc;
  for (int i = 0; i < 4; ++i) {
    sc.residual.setTo(0.002f);
    sc.residual(cv::Rect(100 + 5 * i, 60, 80, 70)).setTo(0.08f);  // drifts 5 px per call
    const auto out = s.update(sc.depth, sc.residual, sc.q0);
    EXPECT_EQ(out.size(), i == 0 ? 0u : 1u) << "call " << i;
    if (!out.empty()) {
      EXPECT_EQ(out[0].age, i + 1);
    }
  }
}

TEST(MotionOptionsTest, ParsesAndRejects) {
  MotionOptions o;
  std::string e;
  EXPECT_TRUE(o.parse("min_area_px=2500,strong_residual_m=0.05", &e)) << e;
  EXPECT_EQ(o.min_area_px, 2500);
  EXPECT_DOUBLE_EQ(o.strong_residual_m, 0.05);
  EXPECT_FALSE(o.parse("min_aera_px=3", &e));
  EXPECT_NE(e.find("unknown key 'min_aera_px'"), std::string::npos) << e;
  EXPECT_FALSE(o.parse("min_area_px=abc", &e));
  EXPECT_FALSE(o.parse("weak_residual_m=0.5", &e));
  // Values that would turn a rule off or wrap (min_area_px=1e12 became a negative area and
  // disabled the size filter): each refused, naming the key and its range.
  const std::pair<const char*, const char*> bad[] = {
      {"min_area_px=1e12", "min_area_px needs an integer in [1, 307200], got '1e12'"},
      {"min_consecutive=1e10", "min_consecutive needs an integer in [1, 100]"},
      {"min_consecutive=2.5", "min_consecutive needs an integer"},
      {"persist_iou=5", "persist_iou needs a number in [0, 1], got '5'"},
      {"max_association=7", "max_association needs a number in [0, 1]"},
      {"max_area_fraction=1.5", "max_area_fraction needs a number in [0, 1]"},
      {"open_radius_px=1e6", "open_radius_px needs an integer in [0, 32]"},
      {"min_area_px=5,min_area_px=7", "min_area_px is given twice"}};
  for (const auto& [config, expected] : bad) {
    MotionOptions fresh;
    EXPECT_FALSE(fresh.parse(config, &e)) << config;
    EXPECT_NE(e.find(expected), std::string::npos) << config << " -> " << e;
  }
}

TEST(MotionPlugin, ThroughTheHost) {
  emf::core::Intrinsics k;
  k.fx = k.fy = 300;
  k.cx = kW / 2.0;
  k.cy = kH / 2.0;
  k.width = kW;
  k.height = kH;
  auto p = emf::pipeline::DetectorPlugin::load("motion", {EMF_PLUGIN_BUILD_DIR},
                                               "min_consecutive=1", "", k);
  emf::core::Frame f;
  f.depth = cv::Mat(kH, kW, CV_32F, cv::Scalar(2.0f));
  f.timestamp_text = "0.0";
  const auto no_feedback = p->detect(f);
  EXPECT_NE(no_feedback.error.find("no residual image"), std::string::npos) << no_feedback.error;
  cv::Mat residual(kH, kW, CV_32F, cv::Scalar(0.001f));
  residual(cv::Rect(50, 40, 60, 50)).setTo(0.1f);
  const auto out = p->detect(f, nullptr, &residual);
  ASSERT_TRUE(out.error.empty()) << out.error;
  ASSERT_EQ(out.detections.size(), 1u);
  EXPECT_EQ(out.detections[0].class_name, "moving");
  EXPECT_EQ(out.detections[0].box, cv::Rect(50, 40, 60, 50));
  EXPECT_DOUBLE_EQ(cv::sum(out.detections[0].mask)[0], 3000.0);
  EXPECT_THROW(
      emf::pipeline::DetectorPlugin::load("motion", {EMF_PLUGIN_BUILD_DIR}, "bogus=1", "", k),
      emf::pipeline::PluginError);
}

}  // namespace
}  // namespace emf_motion
