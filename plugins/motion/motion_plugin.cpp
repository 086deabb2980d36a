// `motion` detector plugin: proposes regions the SLAM explains badly as new objects (class
// "moving"), so moving things no trained detector knows still get their own volume. Needs the
// host's feedback images (emf_detector_frame.residual, and background_association when given).
// Config: "key=value,..." of MotionOptions (motion_segmenter.h), e.g. "min_area_px=2500".
#include <emf/emf_detector.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "motion_segmenter.h"

namespace {
struct Result {
  emf_detection_result result{};
  std::vector<emf_detection> detections;
  std::vector<cv::Mat> masks;
};
}  // namespace

struct emf_detector {
  std::unique_ptr<emf_motion::MotionSegmenter> segmenter;
  std::map<emf_detection_result*, std::unique_ptr<Result>> live;
};

namespace {

void setError(char* error, size_t size, const std::string& msg) {
  if (error && size) std::snprintf(error, size, "%s", msg.c_str());
}

cv::Mat view(const emf_image& img, int type) {
  if (!img.data) return cv::Mat();
  return cv::Mat(img.height, img.width, type, const_cast<void*>(img.data),
                 img.stride_bytes ? img.stride_bytes : static_cast<size_t>(cv::Mat::AUTO_STEP));
}

emf_status create(const emf_detector_create_info* info, emf_detector** out, char* error,
                  size_t error_size) {
  try {
    emf_motion::MotionOptions o;
    std::string msg;
    if (!o.parse(info && info->config ? info->config : "", &msg)) {
      setError(error, error_size, msg);
      return EMF_ERROR_CONFIG;
    }
    auto d = std::make_unique<emf_detector>();
    d->segmenter = std::make_unique<emf_motion::MotionSegmenter>(o);
    *out = d.release();
    return EMF_OK;
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("motion: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

emf_status detect(emf_detector* det, const emf_detector_frame* frame, emf_detection_result** out,
                  char* error, size_t error_size) {
  try {
    *out = nullptr;
    const cv::Mat depth = view(frame->depth, CV_32F);
    const cv::Mat residual = view(frame->residual, CV_32F);
    if (depth.empty()) {
      setError(error, error_size, "motion: frame has no depth image");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    if (residual.empty()) {
      setError(error, error_size,
               "motion: the host gave no residual image (emf_detector_frame.residual); the motion "
               "detector needs the SLAM's feedback");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    const cv::Mat q0 = view(frame->background_association, CV_32F);
    const auto regions = det->segmenter->update(depth, residual, q0);
    if (regions.empty()) return EMF_OK;
    auto r = std::make_unique<Result>();
    for (const auto& region : regions) {
      r->masks.push_back(region.mask.clone());
      emf_detection d{};
      d.struct_size = sizeof(d);
      d.class_name = "moving";
      d.score = region.score;
      d.box_x = region.box.x;
      d.box_y = region.box.y;
      d.box_width = region.box.width;
      d.box_height = region.box.height;
      d.mask_width = depth.cols;
      d.mask_height = depth.rows;
      d.mask = r->masks.back().data;
      r->detections.push_back(d);
    }
    r->result.struct_size = sizeof(r->result);
    r->result.count = static_cast<int32_t>(r->detections.size());
    r->result.detections = r->detections.data();
    emf_detection_result* handle = &r->result;
    det->live.emplace(handle, std::move(r));
    *out = handle;
    return EMF_OK;
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("motion: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

void release(emf_detector* det, emf_detection_result* result) {
  if (det && result) det->live.erase(result);
}

void destroy(emf_detector* det) { delete det; }

const emf_detector_api kApi = {
    sizeof(emf_detector_api),
    EMF_DETECTOR_ABI_VERSION,
    "motion",
    "proposes badly explained, persistent regions as moving objects",
    create,
    detect,
    release,
    destroy,
    EMF_DETECTOR_FLAG_NEW_OBJECTS_ONLY | EMF_DETECTOR_FLAG_READS_FEEDBACK};

}  // namespace

extern "C" EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi) {
  return host_abi == EMF_DETECTOR_ABI_VERSION ? &kApi : nullptr;
}
