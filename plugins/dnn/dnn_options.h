// Options of the `dnn` detector plugin, parsed from its configuration string
// ("key=value,key=value"; docs/plugins.md#configuration lists the keys).
#pragma once

#include <stdexcept>
#include <string>

#include "emf/emf_types.h"

namespace emf_dnn {

/// Everything the plugin reports as a failure: a message saying what is wrong and what to do,
/// and the status the ABI returns with it. The plugin's one error type (caught at the ABI).
class DnnError : public std::runtime_error {
 public:
  DnnError(emf_status status, const std::string& message)
      : std::runtime_error(message), status_(status) {}
  emf_status status() const { return status_; }

 private:
  emf_status status_;
};

/// How the model's outputs are laid out (docs/plugins.md#output-layouts).
enum class Layout {
  kYoloV8,   // output0 [1, 4 + nc + nm, N], output1 [1, nm, mh, mw] (YOLOv8/YOLO11-seg)
  kMaskRcnn  // boxes [N, 4], labels [N], scores [N], masks [N, 1, mh, mw] per box
};

/// What the network computes on.
enum class Target { kCpu, kOpenCl };

struct DnnOptions {
  std::string model_path;           // `model`: the .onnx file (required)
  Layout layout = Layout::kYoloV8;  // `layout`: yolov8 (also YOLO11-seg) | maskrcnn
  int input_width_px = 640;         // `input`: WxH network input size, pixels [16, 8192]
  int input_height_px = 640;
  std::string classes_path;       // `classes`: class names, one per line ("" = shipped COCO names)
  float score_threshold = 0.25f;  // `score`: minimum class score [0, 1]
  float nms_iou = 0.45f;          // `nms`: per-class NMS IoU threshold [0, 1]
  float mask_threshold = 0.5f;    // `mask_threshold`: probability of a mask pixel (0, 1)
  Target target = Target::kCpu;   // `target`: cpu | opencl
  int max_detections = 100;       // `max_detections`: kept per frame after NMS [1, 1000]
  bool mask_logits = true;        // `mask_values`: logits | probabilities (maskrcnn masks)
  /// `threads`: OpenCV's worker threads for the network (cv::setNumThreads, process-wide: in
  /// emf's own process it also sets them for emf's OpenCV calls) [0, 256]; 0 = OpenCV's
  /// default (one per core). Fewer leave cores to the SLAM while a detection runs.
  int threads = 0;

  /// Parses `config` ("key=value,..."; empty items are ignored). Throws DnnError
  /// (EMF_ERROR_CONFIG) naming the key, the bad value and the accepted range.
  static DnnOptions parse(const std::string& config);
};

/// The shipped COCO class names (conf/coco.names): the installed copy, else the source tree's.
/// Throws DnnError when neither exists.
std::string defaultClassesPath();

/// A regular file this process can open (a folder is not: an ifstream on one opens on Linux).
bool isReadableFile(const std::string& path);

}  // namespace emf_dnn
