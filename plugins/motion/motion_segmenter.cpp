#include "motion_segmenter.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace emf_motion {

bool MotionOptions::parse(const std::string& config, std::string* error) {
  // Every key with its range: a fraction above 1 or an integer beyond int would silently turn a
  // rule off (min_area_px=1e12 wrapped to a negative area and disabled the size filter).
  struct Key {
    const char* name;
    double lo, hi;
    bool integer;
    double* real;
    int* whole;
  };
  const Key keys[] = {
      {"strong_residual_m", 0.0, 1.0, false, &strong_residual_m, nullptr},
      {"weak_residual_m", 0.0, 1.0, false, &weak_residual_m, nullptr},
      {"max_association", 0.0, 1.0, false, &max_association, nullptr},
      {"depth_jump_m", 0.0, 1.0, false, &depth_jump_m, nullptr},
      {"depth_jump_rel", 0.0, 1.0, false, &depth_jump_rel, nullptr},
      {"min_area_px", 1, 307200, true, nullptr, &min_area_px},
      {"max_area_fraction", 0.0, 1.0, false, &max_area_fraction, nullptr},
      {"min_consecutive", 1, 100, true, nullptr, &min_consecutive},
      {"persist_iou", 0.0, 1.0, false, &persist_iou, nullptr},
      {"open_radius_px", 0, 32, true, nullptr, &open_radius_px},
  };
  std::string names;
  for (const Key& k : keys) names += std::string(names.empty() ? "" : ", ") + k.name;
  std::stringstream ss(config);
  std::string item, seen = ",";
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      *error = "motion: expected key=value, got '" + item + "'";
      return false;
    }
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    const Key* k = nullptr;
    for (const Key& candidate : keys) {
      if (key == candidate.name) k = &candidate;
    }
    if (!k) {
      *error = "motion: unknown key '" + key + "' (" + names + ")";
      return false;
    }
    if (seen.find("," + key + ",") != std::string::npos) {
      *error = "motion: " + key + " is given twice";
      return false;
    }
    seen += key + ",";
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    char range[96];
    std::snprintf(range, sizeof(range),
                  k->integer ? "an integer in [%.0f, %.0f]" : "a number in [%g, %g]", k->lo, k->hi);
    if (end == value.c_str() || *end != '\0' || !std::isfinite(v) || v < k->lo || v > k->hi ||
        (k->integer && v != std::floor(v))) {
      *error = "motion: " + key + " needs " + range + ", got '" + value + "'";
      return false;
    }
    if (k->integer) {
      *k->whole = static_cast<int>(v);
    } else {
      *k->real = v;
    }
  }
  if (weak_residual_m > strong_residual_m) {
    *error = "motion: weak_residual_m must not exceed strong_residual_m";
    return false;
  }
  return true;
}

int scaledMinArea(const MotionOptions& o, int w, int h) {
  const double scale = static_cast<double>(w) * h / (640.0 * 480.0);
  return std::max(1, static_cast<int>(std::lround(o.min_area_px * scale)));
}

int scaledOpenRadius(const MotionOptions& o, int w) {
  if (o.open_radius_px <= 0) return 0;
  return std::max(1, static_cast<int>(std::lround(o.open_radius_px * w / 640.0)));
}

namespace {

bool validDepth(float d) { return std::isfinite(d) && d > 0.f; }

double iou(const cv::Mat& a, const cv::Mat& b) {
  const double inter = cv::countNonZero(a & b);
  const double uni = cv::countNonZero(a | b);
  return uni > 0 ? inter / uni : 0.0;
}

}  // namespace

std::vector<MotionRegion> MotionSegmenter::segment(const cv::Mat& depth, const cv::Mat& residual,
                                                   const cv::Mat& association) const {
  const int w = depth.cols, h = depth.rows;
  cv::Mat strong = cv::Mat::zeros(h, w, CV_8U), weak = cv::Mat::zeros(h, w, CV_8U);
  for (int y = 0; y < h; ++y) {
    const float* d = depth.ptr<float>(y);
    const float* r = residual.ptr<float>(y);
    const float* q = association.empty() ? nullptr : association.ptr<float>(y);
    for (int x = 0; x < w; ++x) {
      if (!validDepth(d[x]) || !std::isfinite(r[x])) continue;
      if (q && q[x] > options_.max_association) continue;
      if (r[x] > options_.weak_residual_m) weak.at<uint8_t>(y, x) = 1;
      if (r[x] > options_.strong_residual_m) strong.at<uint8_t>(y, x) = 1;
    }
  }
  const cv::Mat strong_raw = strong.clone();  // for the score, before the opening
  const int min_area = scaledMinArea(options_, w, h);
  const int open_radius = scaledOpenRadius(options_, w);
  if (open_radius > 0) {
    const int k = 2 * open_radius + 1;
    cv::morphologyEx(strong, strong, cv::MORPH_OPEN,
                     cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  // Hysteresis growth from the strong seeds into weak pixels, never across a depth jump.
  cv::Mat label = cv::Mat::zeros(h, w, CV_32S);
  std::vector<MotionRegion> regions;
  int next = 0;
  std::deque<cv::Point> queue;
  for (int y0 = 0; y0 < h; ++y0) {
    for (int x0 = 0; x0 < w; ++x0) {
      if (!strong.at<uint8_t>(y0, x0) || label.at<int>(y0, x0)) continue;
      ++next;
      int strong_count = 0, count = 0;
      queue.assign(1, cv::Point(x0, y0));
      label.at<int>(y0, x0) = next;
      while (!queue.empty()) {
        const cv::Point p = queue.front();
        queue.pop_front();
        ++count;
        strong_count += strong_raw.at<uint8_t>(p);
        const float dp = depth.at<float>(p);
        static const int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};
        for (int n = 0; n < 4; ++n) {
          const cv::Point q(p.x + kDx[n], p.y + kDy[n]);
          if (q.x < 0 || q.y < 0 || q.x >= w || q.y >= h) continue;
          if (label.at<int>(q) || !weak.at<uint8_t>(q)) continue;
          const float dq = depth.at<float>(q);
          if (std::abs(dq - dp) > options_.depth_jump_m + options_.depth_jump_rel * dp) continue;
          label.at<int>(q) = next;
          queue.push_back(q);
        }
      }
      if (count < min_area || count > options_.max_area_fraction * static_cast<double>(w) * h) {
        continue;
      }
      MotionRegion r;
      r.mask = (label == next) / 255;
      r.box = cv::boundingRect(r.mask);
      r.score = static_cast<float>(strong_count) / count;
      regions.push_back(std::move(r));
    }
  }
  return regions;
}

std::vector<MotionRegion> MotionSegmenter::update(const cv::Mat& depth, const cv::Mat& residual,
                                                  const cv::Mat& association) {
  std::vector<MotionRegion> current = segment(depth, residual, association);
  for (auto& r : current) {
    for (const auto& p : previous_) {
      if (p.mask.size() == r.mask.size() && iou(p.mask, r.mask) >= options_.persist_iou) {
        r.age = std::max(r.age, p.age + 1);
      }
    }
  }
  previous_ = current;
  std::vector<MotionRegion> out;
  for (const auto& r : current) {
    if (r.age >= options_.min_consecutive) out.push_back(r);
  }
  return out;
}

}  // namespace emf_motion
