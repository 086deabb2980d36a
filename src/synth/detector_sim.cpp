#include "synth/detector_sim.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "synth/rng.h"
#include "synth/scene.h"

namespace emf::synth {
namespace {

constexpr uint64_t kDetectorStream = 0x646574656374ull;  // "detect"
// The imperfections added after the presets (confusion, spills, partial masks) draw from a
// stream of their own per object, so the presets' detections stay as they were.
constexpr uint64_t kFlawStream = 0x666c617773ull;  // "flaws"

struct Candidate {
  int object_id;
  std::string class_name;
  float score;
  cv::Mat mask;  // CV_8U 0/255
};

cv::Mat perturbMask(const cv::Mat& mask, Rng& rng, const DetectorSimOptions& o, double scale) {
  cv::Mat m = mask.clone();
  const int max_r = static_cast<int>(std::lround(o.max_boundary_px * scale));
  const int r = rng.uniformInt(-max_r, max_r);
  if (r != 0) {
    const int a = std::abs(r);
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * a + 1, 2 * a + 1});
    if (r > 0) {
      cv::dilate(m, m, kernel);
    } else {
      cv::erode(m, m, kernel);
    }
  }
  const int max_s = static_cast<int>(std::lround(o.max_shift_px * scale));
  const int dx = rng.uniformInt(-max_s, max_s), dy = rng.uniformInt(-max_s, max_s);
  if (dx != 0 || dy != 0) {
    cv::Mat shifted = cv::Mat::zeros(m.size(), m.type());
    const cv::Rect src(std::max(0, -dx), std::max(0, -dy), m.cols - std::abs(dx),
                       m.rows - std::abs(dy));
    const cv::Rect dst(std::max(0, dx), std::max(0, dy), src.width, src.height);
    if (src.width > 0 && src.height > 0) m(src).copyTo(shifted(dst));
    m = shifted;
  }
  // Ragged boundary: flip boundary pixels at random, then smooth with a 3x3 median.
  cv::Mat grown, shrunk;
  const cv::Mat k3 = cv::getStructuringElement(cv::MORPH_RECT, {3, 3});
  cv::dilate(m, grown, k3);
  cv::erode(m, shrunk, k3);
  for (int v = 0; v < m.rows; ++v) {
    const uint8_t* g = grown.ptr<uint8_t>(v);
    const uint8_t* s = shrunk.ptr<uint8_t>(v);
    uint8_t* p = m.ptr<uint8_t>(v);
    for (int u = 0; u < m.cols; ++u) {
      if (g[u] != s[u] && rng.bernoulli(o.boundary_flip_prob)) p[u] = p[u] ? 0 : 255;
    }
  }
  cv::medianBlur(m, m, 3);
  return m;
}

/// The gross flaws of one object's mask: a spill or a partial cut.
cv::Mat grossFlaws(cv::Mat mask, Rng& rng, const DetectorSimOptions& o) {
  const bool spill = rng.bernoulli(o.spill_rate);
  const bool partial = rng.bernoulli(o.partial_rate);
  const double spill_fraction = rng.uniform(0.06, 0.12);
  const double angle = rng.uniform(0.0, 6.283185307179586);
  const double keep = rng.uniform(0.5, 0.8);
  const cv::Rect box = cv::boundingRect(mask);
  if (box.area() == 0) return mask;
  if (spill) {
    const int r = std::max(1, static_cast<int>(spill_fraction * std::max(box.width, box.height)));
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  }
  if (partial) {
    // Keep the pixels on one side of a line across the box, at the `keep` quantile of their
    // projections on its normal.
    const double nx = std::cos(angle), ny = std::sin(angle);
    std::vector<double> proj;
    for (int v = box.y; v < box.y + box.height; ++v) {
      const uint8_t* m = mask.ptr<uint8_t>(v);
      for (int u = box.x; u < box.x + box.width; ++u) {
        if (m[u]) proj.push_back(u * nx + v * ny);
      }
    }
    if (proj.empty()) return mask;
    const size_t k = static_cast<size_t>(keep * (proj.size() - 1));
    std::nth_element(proj.begin(), proj.begin() + static_cast<std::ptrdiff_t>(k), proj.end());
    const double cut = proj[k];
    for (int v = 0; v < mask.rows; ++v) {
      uint8_t* m = mask.ptr<uint8_t>(v);
      for (int u = 0; u < mask.cols; ++u) {
        if (m[u] && u * nx + v * ny > cut) m[u] = 0;
      }
    }
  }
  return mask;
}

}  // namespace

std::string confusedClass(const std::string& c) {
  static const std::map<std::string, std::string> kConfusions = {
      {"car", "truck"},      {"teddy bear", "dog"},     {"cup", "bowl"},
      {"bottle", "vase"},    {"vase", "bottle"},        {"book", "laptop"},
      {"laptop", "tv"},      {"chair", "couch"},        {"suitcase", "backpack"},
      {"horse", "dog"},      {"airplane", "kite"},      {"skateboard", "surfboard"},
      {"surfboard", "skis"}, {"sports ball", "frisbee"}};
  const auto it = kConfusions.find(c);
  return it == kConfusions.end() ? c : it->second;
}

std::vector<core::Detection> simulateDetections(const cv::Mat& instance_ids,
                                                const std::map<int, std::string>& class_by_object,
                                                uint64_t seed, int64_t frame_index,
                                                const DetectorSimOptions& o,
                                                std::vector<int>* object_of_detection) {
  CV_Assert(instance_ids.type() == CV_16U);
  Rng rng(streamSeed(seed, static_cast<uint64_t>(frame_index), 0, kDetectorStream));
  const double scale = instance_ids.cols / 640.0;
  const int min_pixels = minVisiblePixels(instance_ids.cols, instance_ids.rows);
  const std::vector<int> counts = instancePixelCounts(instance_ids);

  std::vector<Candidate> found;
  for (const auto& [object_id, class_name] : class_by_object) {
    if (object_id <= 0 || static_cast<size_t>(object_id) >= counts.size() ||
        counts[static_cast<size_t>(object_id)] < min_pixels) {
      continue;
    }
    // Draw everything for this object first so a miss does not shift later objects' draws.
    const bool missed = rng.bernoulli(o.miss_rate);
    const float score = static_cast<float>(rng.uniform(o.true_score_min, 1.0));
    Rng mask_rng(rng.next());
    if (missed) continue;
    cv::Mat mask = instance_ids == object_id;
    mask = perturbMask(mask, mask_rng, o, scale);
    std::string reported = class_name;
    if (o.confusion_rate > 0 || o.spill_rate > 0 || o.partial_rate > 0) {
      Rng flaw_rng(streamSeed(seed, static_cast<uint64_t>(frame_index),
                              static_cast<uint64_t>(object_id), kFlawStream));
      if (flaw_rng.bernoulli(o.confusion_rate)) reported = confusedClass(class_name);
      mask = grossFlaws(mask, flaw_rng, o);
    }
    if (cv::countNonZero(mask) < min_pixels) continue;  // eroded away: a miss too
    found.push_back({object_id, reported, score, mask});
  }
  const bool false_positive = rng.bernoulli(o.false_positive_rate);
  Rng fp_rng(rng.next());
  if (false_positive && !o.false_positive_classes.empty()) {
    cv::Mat mask = cv::Mat::zeros(instance_ids.size(), CV_8U);
    const double w = instance_ids.cols, h = instance_ids.rows;
    // One draw per statement (rng.h), y before x: the order these detections were made with.
    const int centre_y = static_cast<int>(fp_rng.uniform(0.1, 0.9) * h);
    const int centre_x = static_cast<int>(fp_rng.uniform(0.1, 0.9) * w);
    const int axis_y = std::max(2, static_cast<int>(fp_rng.uniform(0.03, 0.1) * w));
    const int axis_x = std::max(2, static_cast<int>(fp_rng.uniform(0.03, 0.1) * w));
    const cv::Point centre(centre_x, centre_y);
    const cv::Size axes(axis_x, axis_y);
    cv::ellipse(mask, centre, axes, fp_rng.uniform(0.0, 180.0), 0.0, 360.0, cv::Scalar(255),
                cv::FILLED);
    const int c = fp_rng.uniformInt(0, static_cast<int>(o.false_positive_classes.size()) - 1);
    const float score = static_cast<float>(fp_rng.uniform(0.5, o.false_score_max));
    found.push_back({0, o.false_positive_classes[static_cast<size_t>(c)], score, mask});
  }
  // Detection ids follow a random order, as a real detector's would.
  for (size_t i = found.size(); i > 1; --i) {
    std::swap(found[i - 1], found[static_cast<size_t>(rng.uniformInt(0, static_cast<int>(i) - 1))]);
  }
  std::vector<core::Detection> detections;
  if (object_of_detection) object_of_detection->clear();
  for (size_t i = 0; i < found.size(); ++i) {
    core::Detection d;
    d.id = static_cast<int>(i) + 1;
    d.class_name = found[i].class_name;
    d.score = found[i].score;
    d.box = cv::boundingRect(found[i].mask);
    found[i].mask.convertTo(d.mask, CV_32F, 1.0 / 255.0);
    detections.push_back(std::move(d));
    if (object_of_detection) object_of_detection->push_back(found[i].object_id);
  }
  return detections;
}

}  // namespace emf::synth
