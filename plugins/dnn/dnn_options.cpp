#include "dnn_options.h"

#include <dlfcn.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace emf_dnn {
namespace {

constexpr const char* kKeys =
    "model, layout, input, classes, score, nms, mask_threshold, target, max_detections, "
    "mask_values, threads";

[[noreturn]] void configError(const std::string& message) {
  throw DnnError(EMF_ERROR_CONFIG, "dnn: " + message);
}

float parseFraction(const std::string& key, const std::string& value, bool open_interval) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(value.c_str(), &end);
  const bool in_range = open_interval ? (v > 0.0 && v < 1.0) : (v >= 0.0 && v <= 1.0);
  if (value.empty() || end == value.c_str() || *end != '\0' || errno != 0 || !std::isfinite(v) ||
      !in_range) {
    configError(key + "=" + value + ": expected a number in " +
                (open_interval ? "(0, 1)" : "[0, 1]"));
  }
  return static_cast<float>(v);
}

int parseInt(const std::string& key, const std::string& value, int lo, int hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(value.c_str(), &end, 10);
  if (value.empty() || end == value.c_str() || *end != '\0' || errno != 0 || v < lo || v > hi) {
    configError(key + "=" + value + ": expected an integer in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "]");
  }
  return static_cast<int>(v);
}

/// Where the installed names are relative to this plugin's shared object (so an installation
/// moved to another prefix still finds them); "" when this code is not in a shared object.
std::string besideThisLibrary(const std::string& relative) {
  static const int kAnchor = 0;
  Dl_info info{};
  if (dladdr(&kAnchor, &info) == 0 || !info.dli_fname) return "";
  const std::string self = info.dli_fname;
  const size_t slash = self.rfind('/');
  return slash == std::string::npos ? "" : self.substr(0, slash + 1) + relative;
}

}  // namespace

DnnOptions DnnOptions::parse(const std::string& config) {
  DnnOptions o;
  std::stringstream ss(config);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    const size_t eq = item.find('=');
    if (eq == std::string::npos) {
      configError("expected key=value, got '" + item + "' (keys: " + kKeys + ")");
    }
    const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "model") {
      o.model_path = value;
    } else if (key == "layout") {
      if (value == "yolov8" || value == "yolo11") {
        o.layout = Layout::kYoloV8;
      } else if (value == "maskrcnn") {
        o.layout = Layout::kMaskRcnn;
      } else {
        configError("layout=" + value + ": expected yolov8 (also YOLO11-seg) or maskrcnn");
      }
    } else if (key == "input") {
      const size_t x = value.find('x');
      if (x == std::string::npos) configError("input=" + value + ": expected WxH, e.g. 640x640");
      o.input_width_px = parseInt("input width", value.substr(0, x), 16, 8192);
      o.input_height_px = parseInt("input height", value.substr(x + 1), 16, 8192);
    } else if (key == "classes") {
      o.classes_path = value;
    } else if (key == "score") {
      o.score_threshold = parseFraction(key, value, false);
    } else if (key == "nms") {
      o.nms_iou = parseFraction(key, value, false);
    } else if (key == "mask_threshold") {
      o.mask_threshold = parseFraction(key, value, true);
    } else if (key == "target") {
      if (value == "cpu") {
        o.target = Target::kCpu;
      } else if (value == "opencl") {
        o.target = Target::kOpenCl;
      } else {
        configError("target=" + value + ": expected cpu or opencl");
      }
    } else if (key == "max_detections") {
      o.max_detections = parseInt(key, value, 1, 1000);
    } else if (key == "threads") {
      o.threads = parseInt(key, value, 0, 256);
    } else if (key == "mask_values") {
      if (value == "logits") {
        o.mask_logits = true;
      } else if (value == "probabilities") {
        o.mask_logits = false;
      } else {
        configError("mask_values=" + value + ": expected logits or probabilities");
      }
    } else {
      configError("unknown key '" + key + "' (keys: " + kKeys + ")");
    }
  }
  if (o.model_path.empty()) {
    configError(
        "no model given: set model=/path/to/model.onnx in detector.plugin_config (e.g. "
        "\"model=/data/yolov8n-seg.onnx,layout=yolov8\")");
  }
  if (o.classes_path.empty()) o.classes_path = defaultClassesPath();
  return o;
}

std::string defaultClassesPath() {
  const std::string candidates[] = {besideThisLibrary(EMF_DNN_CLASSES_FROM_PLUGIN),
                                    EMF_DNN_CLASSES_INSTALLED, EMF_DNN_CLASSES_SOURCE};
  std::string tried;
  for (const std::string& path : candidates) {
    if (path.empty()) continue;
    if (isReadableFile(path)) return path;
    tried += (tried.empty() ? "" : ", ") + path;
  }
  throw DnnError(EMF_ERROR_CONFIG, "dnn: the shipped class names are missing (looked for " + tried +
                                       "); pass classes=/path/to/names.txt (one name per line)");
}

bool isReadableFile(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec) && std::ifstream(path).good();
}

}  // namespace emf_dnn
