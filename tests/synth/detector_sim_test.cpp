// Simulated detector: miss rate, false positives, shuffled ids, mask quality (IoU with the
// ground-truth instance masks), scores, boxes, determinism.
#include "synth/detector_sim.h"

#include <gtest/gtest.h>

#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

namespace emf::synth {
namespace {

/// Three objects of different sizes on a 320x240 instance image.
cv::Mat threeObjects() {
  cv::Mat ids = cv::Mat::zeros(240, 320, CV_16U);
  cv::rectangle(ids, cv::Rect(20, 30, 90, 70), cv::Scalar(1), cv::FILLED);
  cv::circle(ids, cv::Point(200, 80), 40, cv::Scalar(2), cv::FILLED);
  cv::ellipse(ids, cv::Point(160, 190), cv::Size(70, 25), 15, 0, 360, cv::Scalar(5), cv::FILLED);
  return ids;
}

double iou(const cv::Mat& a, const cv::Mat& b) {
  const double inter = cv::countNonZero(a & b);
  const double uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 0.0;
}

TEST(SynthDetector, StatisticsOverManyFrames) {
  const cv::Mat ids = threeObjects();
  const std::map<int, std::string> classes = {{1, "suitcase"}, {2, "sports ball"}, {5, "car"}};
  DetectorSimOptions o;
  int expected = 0, detected = 0, false_positives = 0, frames = 0, reordered = 0, multi = 0;
  double iou_sum = 0, iou_min = 1, iou_max = 0;
  std::set<std::pair<int, int>> object_to_id;
  for (int64_t f = 0; f < 800; ++f, ++frames) {
    std::vector<int> objects;
    const auto dets = simulateDetections(ids, classes, 99, f, o, &objects);
    ASSERT_EQ(dets.size(), objects.size());
    expected += 3;
    std::vector<int> true_order;
    for (size_t i = 0; i < dets.size(); ++i) {
      const auto& d = dets[i];
      EXPECT_EQ(d.id, static_cast<int>(i) + 1);
      EXPECT_GE(d.score, 0.5f);
      EXPECT_LE(d.score, 1.0f);
      ASSERT_EQ(d.mask.type(), CV_32F);
      ASSERT_EQ(d.mask.size(), ids.size());
      const cv::Mat binary = d.mask > 0.5f;
      EXPECT_EQ(cv::countNonZero(binary), cv::countNonZero(d.mask));  // values are 0 or 1
      EXPECT_EQ(d.box, cv::boundingRect(binary));
      if (objects[i] == 0) {
        ++false_positives;
        EXPECT_LE(d.score, 0.75f);
        continue;
      }
      ++detected;
      true_order.push_back(objects[i]);
      object_to_id.insert({objects[i], d.id});
      EXPECT_EQ(d.class_name, classes.at(objects[i]));
      const double q = iou(binary, ids == objects[i]);
      iou_sum += q;
      iou_min = std::min(iou_min, q);
      iou_max = std::max(iou_max, q);
    }
    if (true_order.size() >= 2) {
      ++multi;
      if (!std::is_sorted(true_order.begin(), true_order.end())) ++reordered;
    }
  }
  const double miss_rate = 1.0 - static_cast<double>(detected) / expected;
  EXPECT_NEAR(miss_rate, 0.10, 0.025);  // 2400 draws: sd of the rate 0.006
  EXPECT_NEAR(static_cast<double>(false_positives) / frames, 0.15, 0.04);  // sd 0.013
  const double mean_iou = iou_sum / detected;
  EXPECT_GT(mean_iou, 0.75);  // imperfect ...
  EXPECT_LT(mean_iou, 0.97);  // ... but not perfect
  EXPECT_GT(iou_min, 0.5);
  EXPECT_LT(iou_max, 1.0);
  // Ids are shuffled: every object got several different ids, and the order is often not the
  // object order (random order of 2-3 items is sorted in 1/2 or 1/6 of the cases).
  for (int obj : {1, 2, 5}) {
    int distinct = 0;
    for (const auto& [o_id, d_id] : object_to_id) distinct += o_id == obj;
    EXPECT_GE(distinct, 3) << "object " << obj;
  }
  EXPECT_GT(static_cast<double>(reordered) / multi, 0.35);
}

TEST(SynthDetector, DeterministicPerSeedAndFrame) {
  const cv::Mat ids = threeObjects();
  const std::map<int, std::string> classes = {{1, "a"}, {2, "b"}, {5, "c"}};
  auto signature = [&](uint64_t seed, int64_t frame) {
    std::string s;
    for (const auto& d : simulateDetections(ids, classes, seed, frame, {})) {
      s += d.class_name + std::to_string(d.score) + std::to_string(cv::countNonZero(d.mask)) + ";";
    }
    return s;
  };
  EXPECT_EQ(signature(1, 30), signature(1, 30));
  int differ_seed = 0, differ_frame = 0;
  for (int64_t f = 0; f < 20; ++f) {
    differ_seed += signature(1, f) != signature(2, f);
    differ_frame += signature(1, f) != signature(1, f + 100);
  }
  EXPECT_GE(differ_seed, 18);
  EXPECT_GE(differ_frame, 18);
}

TEST(SynthDetector, TinyAndUnlistedObjectsAreNotDetected) {
  cv::Mat ids = cv::Mat::zeros(240, 320, CV_16U);
  cv::rectangle(ids, cv::Rect(10, 10, 5, 5), cv::Scalar(1), cv::FILLED);      // 25 px < 77
  cv::rectangle(ids, cv::Rect(100, 100, 60, 60), cv::Scalar(7), cv::FILLED);  // not listed
  DetectorSimOptions o;
  o.false_positive_rate = 0.0;
  o.miss_rate = 0.0;
  for (int64_t f = 0; f < 20; ++f) {
    EXPECT_TRUE(simulateDetections(ids, {{1, "cup"}}, 1, f, o).empty());
  }
}

TEST(SynthDetector, DetectionFrames) {
  DetectorSimOptions o;
  EXPECT_TRUE(isDetectionFrame(0, o));
  EXPECT_FALSE(isDetectionFrame(29, o));
  EXPECT_TRUE(isDetectionFrame(60, o));
  o.every_n_frames = 0;
  EXPECT_FALSE(isDetectionFrame(0, o));
}

}  // namespace
}  // namespace emf::synth

namespace emf::synth {
namespace {

// The gross flaws of the generated scenes' detector: each at rate 1 shows on every detection,
// at rate 0 the detections are those of the presets' detector.
TEST(SynthDetector, GrossFlawsAtTheirRates) {
  const cv::Mat ids = threeObjects();
  const std::map<int, std::string> classes = {{1, "suitcase"}, {2, "sports ball"}, {5, "car"}};
  DetectorSimOptions plain;
  plain.miss_rate = 0;
  plain.false_positive_rate = 0;
  DetectorSimOptions flawed = plain;
  flawed.confusion_rate = 1.0;
  for (int64_t f = 0; f < 20; ++f) {
    std::vector<int> objects;
    const auto a = simulateDetections(ids, classes, 3, f, plain, &objects);
    const auto b = simulateDetections(ids, classes, 3, f, flawed);
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(b[i].class_name, confusedClass(classes.at(objects[i])));
      EXPECT_EQ(cv::countNonZero(a[i].mask != b[i].mask), 0);  // the masks are untouched
    }
  }
  EXPECT_EQ(confusedClass("car"), "truck");
  EXPECT_EQ(confusedClass("toaster"), "toaster");
  DetectorSimOptions spill = plain, partial = plain;
  spill.spill_rate = 1.0;
  partial.partial_rate = 1.0;
  for (int64_t f = 0; f < 20; ++f) {
    std::vector<int> objects;
    const auto a = simulateDetections(ids, classes, 3, f, plain, &objects);
    const auto s = simulateDetections(ids, classes, 3, f, spill);
    const auto p = simulateDetections(ids, classes, 3, f, partial);
    ASSERT_EQ(a.size(), s.size());
    ASSERT_EQ(a.size(), p.size());
    for (size_t i = 0; i < a.size(); ++i) {
      const double area = cv::countNonZero(a[i].mask);
      const cv::Rect box = cv::boundingRect(a[i].mask > 0.5f);
      // Spilled: dilated by at least 6 % of the box's larger side all around.
      const double r = 0.06 * std::max(box.width, box.height);
      EXPECT_GT(cv::countNonZero(s[i].mask), area + 2.0 * r * (box.width + box.height) * 0.6);
      EXPECT_EQ(cv::countNonZero((a[i].mask > 0.5f) & (s[i].mask < 0.5f)), 0);
      // Partial: 50-80 % of the mask kept, nothing added.
      EXPECT_GE(cv::countNonZero(p[i].mask), 0.48 * area);
      EXPECT_LE(cv::countNonZero(p[i].mask), 0.82 * area);
      EXPECT_EQ(cv::countNonZero((p[i].mask > 0.5f) & (a[i].mask < 0.5f)), 0);
    }
  }
}

}  // namespace
}  // namespace emf::synth
