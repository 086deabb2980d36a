// Ground truth of the generated test models (make_test_models.py writes <model>.json beside each
// .onnx) and the expected boxes and masks it implies in a depth image of any size.
#pragma once

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace emf_dnn_test {

/// Folder of the generated models (CMake builds them before the tests).
inline std::string modelDir() { return EMF_DNN_TEST_MODEL_DIR; }
inline std::string modelPath(const std::string& name) { return modelDir() + "/" + name; }

struct TruthObject {
  int class_id = 0;
  std::string class_name;
  float score = 0;
  cv::Rect2d box;  // frame (colour) pixels, [x1, x2) x [y1, y2)
  std::vector<cv::Rect2d> add, sub;
};

struct Truth {
  cv::Size frame;  // colour image size the objects are defined in
  cv::Size input;  // network input size
  std::vector<TruthObject> objects;
};

inline cv::Rect2d rectOf(const nlohmann::json& r) {
  const double x1 = r.at(0), y1 = r.at(1), x2 = r.at(2), y2 = r.at(3);
  return cv::Rect2d(x1, y1, x2 - x1, y2 - y1);
}

inline Truth loadTruth(const std::string& json_name) {
  std::ifstream in(modelPath(json_name));
  if (!in) throw std::runtime_error("missing " + modelPath(json_name));
  const nlohmann::json j = nlohmann::json::parse(in);
  Truth t;
  t.frame = cv::Size(j.at("frame").at(0), j.at("frame").at(1));
  t.input = cv::Size(j.at("input").at(0), j.at("input").at(1));
  for (const auto& o : j.at("objects")) {
    TruthObject obj;
    obj.class_id = o.at("class_id");
    obj.class_name = o.at("class_name");
    obj.score = o.at("score");
    obj.box = rectOf(o.at("box"));
    for (const auto& r : o.at("add")) obj.add.push_back(rectOf(r));
    if (o.contains("sub")) {
      for (const auto& r : o.at("sub")) obj.sub.push_back(rectOf(r));
    }
    t.objects.push_back(obj);
  }
  return t;
}

inline bool inRect(const cv::Rect2d& r, double x, double y) {
  return x >= r.x && x < r.x + r.width && y >= r.y && y < r.y + r.height;
}

/// The object's box in depth pixels (frame box scaled to the depth size).
inline cv::Rect2d expectedBox(const Truth& t, const TruthObject& o, cv::Size depth) {
  const double sx = static_cast<double>(depth.width) / t.frame.width;
  const double sy = static_cast<double>(depth.height) / t.frame.height;
  return cv::Rect2d(o.box.x * sx, o.box.y * sy, o.box.width * sx, o.box.height * sy);
}

/// The object's mask in a depth image: a pixel belongs when its centre, mapped to the frame,
/// is in the shape and in the box.
inline cv::Mat expectedMask(const Truth& t, const TruthObject& o, cv::Size depth) {
  cv::Mat m = cv::Mat::zeros(depth, CV_8U);
  const double sx = static_cast<double>(t.frame.width) / depth.width;
  const double sy = static_cast<double>(t.frame.height) / depth.height;
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const double x = (u + 0.5) * sx, y = (v + 0.5) * sy;
      if (!inRect(o.box, x, y)) continue;
      bool in = false;
      for (const auto& r : o.add) in = in || inRect(r, x, y);
      for (const auto& r : o.sub) in = in && !inRect(r, x, y);
      m.at<uint8_t>(v, u) = in ? 1 : 0;
    }
  }
  return m;
}

/// Intersection over union of two masks (non-zero = in).
inline double maskIou(const cv::Mat& a, const cv::Mat& b) {
  const cv::Mat a8 = a != 0, b8 = b != 0;
  const double inter = cv::countNonZero(a8 & b8), uni = cv::countNonZero(a8 | b8);
  return uni > 0 ? inter / uni : 0.0;
}

/// A colour frame (BGR8) with some structure; the test models ignore the pixels.
inline cv::Mat syntheticColor(cv::Size size, int seed) {
  cv::Mat c(size, CV_8UC3);
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      c.at<cv::Vec3b>(y, x) = cv::Vec3b(static_cast<uint8_t>((x + seed * 7) % 256),
                                        static_cast<uint8_t>((y * 2 + seed) % 256),
                                        static_cast<uint8_t>((x ^ y) % 256));
    }
  }
  return c;
}

}  // namespace emf_dnn_test
