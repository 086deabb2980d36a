#include "pipeline/detector_plugin.h"

#include <dlfcn.h>

#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>

#include "common/log.h"
#include "common/status_name.h"

namespace emf::pipeline {
namespace fs = std::filesystem;

namespace {

constexpr size_t kErrorCapacity = 1024;
constexpr int32_t kMaxDetections = 4096;

// Fields the host reads from each plugin struct (a smaller struct_size is an older/broken one).
constexpr size_t kMinApiSize = offsetof(emf_detector_api, destroy) + sizeof(void*);
// Plugins whose struct_size reaches this have the (later) flags field.
constexpr size_t kApiSizeWithFlags = offsetof(emf_detector_api, flags) + sizeof(uint32_t);
constexpr size_t kMinResultSize = offsetof(emf_detection_result, detections) + sizeof(void*);
constexpr size_t kMinDetectionSize =
    offsetof(emf_detection, mask_probability) + sizeof(const float*);
// A bound on a newer header's emf_detection: a larger detections[0].struct_size is garbage.
constexpr size_t kMaxDetectionSize = 4096;

emf_image imageView(const cv::Mat* m, emf_pixel_format format) {
  emf_image img{};
  img.struct_size = sizeof(emf_image);
  img.format = format;
  if (m && !m->empty()) {
    img.width = m->cols;
    img.height = m->rows;
    img.stride_bytes = m->step[0];
    img.data = m->data;
  }
  return img;
}

}  // namespace

std::string resolvePluginPath(const std::string& name_or_path,
                              const std::vector<std::string>& search_path) {
  if (name_or_path.empty()) throw PluginError("no detector plugin name or path given");
  const bool is_path =
      name_or_path.find('/') != std::string::npos || fs::path(name_or_path).extension() == ".so";
  if (is_path) {
    if (!fs::exists(name_or_path)) {
      throw PluginError("detector plugin file '" + name_or_path +
                            "' does not exist (give an existing .so path or a plugin name)",
                        EMF_ERROR_NOT_FOUND);
    }
    return name_or_path;
  }
  std::string searched;
  for (const auto& dir : search_path) {
    for (const std::string& file :
         {"libemf_detector_" + name_or_path + ".so", name_or_path + ".so"}) {
      const fs::path p = fs::path(dir) / file;
      if (fs::exists(p)) return p.string();
    }
    searched += "\n  " + dir;
  }
  throw PluginError(
      "detector plugin '" + name_or_path + "' not found (looked for libemf_detector_" +
          name_or_path + ".so in:" + (searched.empty() ? " no folders" : searched) +
          "\n); add its folder to detector.search_path or EMF_PLUGIN_PATH, or give a path",
      EMF_ERROR_NOT_FOUND);
}

std::unique_ptr<DetectorPlugin> DetectorPlugin::load(const std::string& name_or_path,
                                                     const std::vector<std::string>& search_path,
                                                     const std::string& config,
                                                     const std::string& source_uri,
                                                     const core::Intrinsics& intrinsics) {
  const std::string path = resolvePluginPath(name_or_path, search_path);
  std::unique_ptr<DetectorPlugin> p(new DetectorPlugin());
  p->path_ = path;
  p->intrinsics_ = intrinsics;
  dlerror();
  p->handle_ = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!p->handle_) {
    const char* e = dlerror();
    throw PluginError("cannot load detector plugin " + path + ": " + (e ? e : "unknown error"),
                      EMF_ERROR_IO);
  }
  void* sym = dlsym(p->handle_, EMF_DETECTOR_ENTRY_SYMBOL);
  if (!sym) {
    throw PluginError("detector plugin " + path +
                          " does not export " EMF_DETECTOR_ENTRY_SYMBOL
                          " (is it an emf detector plugin? build it against include/emf/"
                          "emf_detector.h and export the entry with EMF_DETECTOR_EXPORT)",
                      EMF_ERROR_IO);
  }
  emf_detector_entry_fn entry = nullptr;
  static_assert(sizeof(entry) == sizeof(sym), "function and object pointers differ in size");
  std::memcpy(&entry, &sym, sizeof(entry));
  const emf_detector_api* api = entry(EMF_DETECTOR_ABI_VERSION);
  if (!api) {
    throw PluginError("detector plugin " + path + " refused host ABI version " +
                          std::to_string(EMF_DETECTOR_ABI_VERSION) +
                          " (rebuild the plugin against this emf's emf_detector.h)",
                      EMF_ERROR_VERSION_MISMATCH);
  }
  if (api->abi_version != EMF_DETECTOR_ABI_VERSION) {
    throw PluginError("detector plugin " + path + " has ABI version " +
                          std::to_string(api->abi_version) + ", this emf needs " +
                          std::to_string(EMF_DETECTOR_ABI_VERSION) +
                          " (rebuild the plugin against this emf's emf_detector.h)",
                      EMF_ERROR_VERSION_MISMATCH);
  }
  if (api->struct_size < kMinApiSize) {
    throw PluginError("detector plugin " + path + ": emf_detector_api.struct_size is " +
                          std::to_string(api->struct_size) + ", expected at least " +
                          std::to_string(kMinApiSize) + " (plugin built against a broken header?)",
                      EMF_ERROR_VERSION_MISMATCH);
  }
  if (!api->create || !api->detect || !api->release || !api->destroy) {
    throw PluginError(
        "detector plugin " + path + ": function table has a NULL create/detect/release/destroy",
        EMF_ERROR_VERSION_MISMATCH);
  }
  p->api_ = api;
  p->name_ = api->name ? api->name : fs::path(path).stem().string();
  emf_detector_create_info info{};
  info.struct_size = sizeof(info);
  info.config = config.c_str();
  info.source_uri = source_uri.c_str();
  info.intrinsics = {intrinsics.fx, intrinsics.fy,    intrinsics.cx,
                     intrinsics.cy, intrinsics.width, intrinsics.height};
  char error[kErrorCapacity] = {0};
  const emf_status s = api->create(&info, &p->instance_, error, sizeof(error));
  error[kErrorCapacity - 1] = '\0';
  if (s != EMF_OK || !p->instance_) {
    p->instance_ = nullptr;
    throw PluginError("detector plugin '" + p->name_ + "' (" + path +
                          ") failed to create with config '" + config +
                          "': " + (error[0] ? error : "no message") + " [" + statusName(s) + "]",
                      s < 0 && s != EMF_ERROR_INTERNAL ? s : EMF_ERROR_CONFIG);
  }
  logInfo("detector plugin '", p->name_, "' loaded from ", path);
  return p;
}

DetectorPlugin::~DetectorPlugin() {
  if (api_ && instance_) api_->destroy(instance_);
  if (handle_) dlclose(handle_);
}

bool DetectorPlugin::newObjectsOnly() const {
  return api_ && api_->struct_size >= kApiSizeWithFlags &&
         (api_->flags & EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY) != 0;
}

bool DetectorPlugin::readsFeedback() const {
  if (!api_) return false;
  if (api_->struct_size < kApiSizeWithFlags) return true;
  return (api_->flags & EMF_DETECTOR_FLAG_READS_FEEDBACK) != 0;
}

DetectorOutput DetectorPlugin::detect(const core::Frame& frame,
                                      const cv::Mat* background_association,
                                      const cv::Mat* residual) {
  DetectorOutput out;
  out.new_objects_only = newObjectsOnly();
  const std::string who = "detector '" + name_ + "' frame " + std::to_string(frame.index);
  emf_detector_frame f{};
  f.struct_size = sizeof(f);
  f.frame_index = frame.index;
  f.timestamp = frame.timestamp;
  f.timestamp_text = frame.timestamp_text.c_str();
  f.depth = imageView(&frame.depth, EMF_PIXEL_DEPTH_F32);
  f.color = imageView(&frame.color, EMF_PIXEL_BGR8);
  f.background_association = imageView(background_association, EMF_PIXEL_F32);
  f.residual = imageView(residual, EMF_PIXEL_F32);
  const int width = frame.depth.cols, height = frame.depth.rows;

  emf_detection_result* result = nullptr;
  char error[kErrorCapacity] = {0};
  const emf_status s = api_->detect(instance_, &f, &result, error, sizeof(error));
  error[kErrorCapacity - 1] = '\0';
  struct Releaser {
    const emf_detector_api* api;
    emf_detector* inst;
    emf_detection_result* r;
    ~Releaser() {
      if (r) api->release(inst, r);
    }
  } releaser{api_, instance_, result};
  if (s != EMF_OK) {
    out.error =
        who + ": detect failed: " + (error[0] ? error : "no message") + " [" + statusName(s) + "]";
    if (log_problems_) logWarning(out.error, "; continuing without detections");
    return out;
  }
  if (!result) return out;  // nothing detected
  if (result->struct_size < kMinResultSize || result->count < 0 || result->count > kMaxDetections ||
      (result->count > 0 && !result->detections)) {
    out.error = who + ": malformed emf_detection_result (struct_size " +
                std::to_string(result->struct_size) + ", count " + std::to_string(result->count) +
                ")";
    if (log_problems_) logWarning(out.error, "; continuing without detections");
    return out;
  }
  // The entries lie detections[0].struct_size bytes apart (a plugin built against a newer header
  // has a larger emf_detection); every entry must say the same size.
  const size_t stride = result->count > 0 ? result->detections[0].struct_size : 0;
  if (result->count > 0 && (stride < kMinDetectionSize || stride > kMaxDetectionSize ||
                            stride % alignof(emf_detection) != 0)) {
    out.error = who + ": malformed emf_detection_result: detections[0].struct_size " +
                std::to_string(stride) + " is not a multiple of " +
                std::to_string(alignof(emf_detection)) + " in [" +
                std::to_string(kMinDetectionSize) + ", " + std::to_string(kMaxDetectionSize) + "]";
    if (log_problems_) logWarning(out.error, "; continuing without detections");
    return out;
  }
  const auto* base = reinterpret_cast<const unsigned char*>(result->detections);
  for (int32_t i = 0; i < result->count; ++i) {
    const emf_detection& d =
        *reinterpret_cast<const emf_detection*>(base + static_cast<size_t>(i) * stride);
    const std::string tag = who + " detection " + std::to_string(i);
    auto reject = [&](const std::string& why) {
      out.rejected.push_back(tag + ": " + why + " — dropped");
      if (log_problems_) logWarning(out.rejected.back());
    };
    if (d.struct_size != stride) {
      reject("struct_size " + std::to_string(d.struct_size) + " differs from detections[0]'s " +
             std::to_string(stride) + " (all entries must have the same size)");
      continue;
    }
    if (!d.class_name || !d.class_name[0]) {
      reject("empty class name");
      continue;
    }
    if (!std::isfinite(d.score) || d.score < 0.f || d.score > 1.f) {
      reject("score " + std::to_string(d.score) + " is not in [0, 1]");
      continue;
    }
    if (d.box_width <= 0 || d.box_height <= 0 || d.box_x < 0 || d.box_y < 0 ||
        d.box_x + static_cast<int64_t>(d.box_width) > width ||
        d.box_y + static_cast<int64_t>(d.box_height) > height) {
      reject("box (" + std::to_string(d.box_x) + ", " + std::to_string(d.box_y) + ", " +
             std::to_string(d.box_width) + " x " + std::to_string(d.box_height) +
             ") is not inside the " + std::to_string(width) + "x" + std::to_string(height) +
             " image");
      continue;
    }
    if (d.mask_width != width || d.mask_height != height) {
      reject("mask is " + std::to_string(d.mask_width) + "x" + std::to_string(d.mask_height) +
             ", the depth image is " + std::to_string(width) + "x" + std::to_string(height));
      continue;
    }
    if (!d.mask && !d.mask_probability) {
      reject("neither mask nor mask_probability is set");
      continue;
    }
    core::Detection det;
    det.id = static_cast<int>(out.detections.size()) + 1;
    det.class_name = d.class_name;
    det.score = d.score;
    det.box = cv::Rect(d.box_x, d.box_y, d.box_width, d.box_height);
    det.mask.create(height, width, CV_32F);
    bool bad_value = false;
    if (d.mask_probability) {
      for (int y = 0; y < height && !bad_value; ++y) {
        const float* src = d.mask_probability + static_cast<size_t>(y) * width;
        float* dst = det.mask.ptr<float>(y);
        for (int x = 0; x < width; ++x) {
          const float v = src[x];
          if (!std::isfinite(v) || v < 0.f || v > 1.f) {
            bad_value = true;
            break;
          }
          dst[x] = v;
        }
      }
    } else {
      for (int y = 0; y < height; ++y) {
        const uint8_t* src = d.mask + static_cast<size_t>(y) * width;
        float* dst = det.mask.ptr<float>(y);
        for (int x = 0; x < width; ++x) dst[x] = src[x] ? 1.f : 0.f;
      }
    }
    if (bad_value) {
      reject("mask_probability has values outside [0, 1] or NaN");
      continue;
    }
    out.detections.push_back(std::move(det));
  }
  return out;
}

}  // namespace emf::pipeline
