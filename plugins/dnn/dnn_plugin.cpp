// `dnn` detector plugin: runs an ONNX instance-segmentation model (YOLOv8/YOLO11-seg or the
// Mask R-CNN layout) through OpenCV's DNN module and reports each instance with its box, class,
// score, binary mask and per-pixel foreground probability, in depth-image pixels.
// Config: "model=/path/m.onnx,layout=yolov8|maskrcnn,input=640x640,classes=/path/names,
// score=0.25,nms=0.45,mask_threshold=0.5,target=cpu|opencl,max_detections=100,
// mask_values=logits|probabilities" (docs/plugins.md#the-dnn-plugin).
// Needs colour: emf_detector_frame.color (BGR8, registered to depth).
#include <emf/emf_detector.h>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "dnn_detector.h"

namespace {
/// Everything one detect() result owns until release().
struct Result {
  emf_detection_result result{};
  std::vector<emf_detection> detections;
  std::vector<emf_dnn::Instance> instances;  // owns the masks the detections point into
};
}  // namespace

struct emf_detector {
  std::unique_ptr<emf_dnn::DnnDetector> dnn;
  std::map<emf_detection_result*, std::unique_ptr<Result>> live;  // results not yet released
};

namespace {

void setError(char* error, size_t size, const std::string& msg) {
  if (error && size) std::snprintf(error, size, "%s", msg.c_str());
}

cv::Mat view(const emf_image& img, int type) {
  if (!img.data || img.width <= 0 || img.height <= 0) return cv::Mat();
  return cv::Mat(img.height, img.width, type, const_cast<void*>(img.data),
                 img.stride_bytes ? img.stride_bytes : static_cast<size_t>(cv::Mat::AUTO_STEP));
}

emf_status create(const emf_detector_create_info* info, emf_detector** out, char* error,
                  size_t error_size) {
  try {
    if (!info || !out) {
      setError(error, error_size, "dnn: NULL argument");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    const emf_dnn::DnnOptions options =
        emf_dnn::DnnOptions::parse(info->config ? info->config : "");
    auto d = std::make_unique<emf_detector>();
    d->dnn = std::make_unique<emf_dnn::DnnDetector>(options);
    *out = d.release();
    return EMF_OK;
  } catch (const emf_dnn::DnnError& e) {
    setError(error, error_size, e.what());
    return e.status();
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("dnn: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

emf_status detect(emf_detector* det, const emf_detector_frame* frame, emf_detection_result** out,
                  char* error, size_t error_size) {
  try {
    if (!det || !frame || !out) {
      setError(error, error_size, "dnn: NULL argument");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    *out = nullptr;
    const std::string who = "dnn: frame " + std::to_string(frame->frame_index);
    const cv::Mat color = view(frame->color, CV_8UC3);
    if (color.empty()) {
      setError(error, error_size,
               who +
                   " has no colour image: the dnn detector needs BGR8 colour registered to "
                   "depth (use a source with colour, or another detector)");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    if (frame->color.format != EMF_PIXEL_BGR8) {
      setError(error, error_size,
               who + ": colour pixel format " + std::to_string(frame->color.format) +
                   " is not EMF_PIXEL_BGR8");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    if (frame->depth.width <= 0 || frame->depth.height <= 0) {
      setError(error, error_size, who + " has no depth image (masks are reported at its size)");
      return EMF_ERROR_INVALID_ARGUMENT;
    }
    const cv::Size depth_size(frame->depth.width, frame->depth.height);
    auto r = std::make_unique<Result>();
    r->instances = det->dnn->detect(color, depth_size);
    if (r->instances.empty()) return EMF_OK;
    const auto& names = det->dnn->classNames();
    for (const auto& inst : r->instances) {
      emf_detection d{};
      d.struct_size = sizeof(d);
      d.class_name = names[static_cast<size_t>(inst.class_id)].c_str();
      d.score = inst.score;
      d.box_x = inst.box.x;
      d.box_y = inst.box.y;
      d.box_width = inst.box.width;
      d.box_height = inst.box.height;
      d.mask_width = depth_size.width;
      d.mask_height = depth_size.height;
      d.mask = inst.mask.ptr<uint8_t>();
      d.mask_probability = inst.probability.ptr<float>();
      r->detections.push_back(d);
    }
    r->result.struct_size = sizeof(r->result);
    r->result.count = static_cast<int32_t>(r->detections.size());
    r->result.detections = r->detections.data();
    emf_detection_result* handle = &r->result;
    det->live.emplace(handle, std::move(r));
    *out = handle;
    return EMF_OK;
  } catch (const emf_dnn::DnnError& e) {
    setError(error, error_size, e.what());
    return e.status();
  } catch (const cv::Exception& e) {
    setError(error, error_size, std::string("dnn: OpenCV failed: ") + e.what());
    return EMF_ERROR_INTERNAL;
  } catch (const std::exception& e) {
    setError(error, error_size, std::string("dnn: ") + e.what());
    return EMF_ERROR_INTERNAL;
  }
}

void release(emf_detector* det, emf_detection_result* result) {
  if (!det || !result) return;
  const auto it = det->live.find(result);
  if (it == det->live.end()) return;
  det->dnn->recycle(&it->second->instances);  // the mask buffers serve the next frames
  det->live.erase(it);
}

void destroy(emf_detector* det) { delete det; }

const emf_detector_api kApi = {
    sizeof(emf_detector_api),
    EMF_DETECTOR_ABI_VERSION,
    "dnn",
    "ONNX instance segmentation (YOLOv8/YOLO11-seg, Mask R-CNN) through OpenCV DNN",
    create,
    detect,
    release,
    destroy,
    0u};

}  // namespace

extern "C" EMF_DETECTOR_EXPORT const emf_detector_api* emf_detector_entry(uint32_t host_abi) {
  return host_abi == EMF_DETECTOR_ABI_VERSION ? &kApi : nullptr;
}
