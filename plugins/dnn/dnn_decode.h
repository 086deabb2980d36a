// The `dnn` detector's work outside the network: letterbox preprocessing, recognising the
// output layout, decoding boxes and scores, per-class NMS and mask assembly. Pure functions on
// cv::Mat, so tests and bench/dnn_bench run them on synthetic tensors without a model.
//
// Coordinates: "input" = the network input (letterboxed, input pixels), "image" = the colour
// image, "depth" = the depth image the masks are reported in (the colour image is assumed
// registered to depth: same field of view, possibly another resolution). Continuous pixel
// coordinates: pixel u covers [u, u + 1), its centre is u + 0.5.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "dnn_options.h"

namespace emf_dnn {

/// Grey value of the letterbox padding (as the YOLO training pipelines use).
constexpr int kLetterboxPad = 114;

/// How an image is letterboxed into the network input: scaled by one factor (aspect kept),
/// centred, padded with kLetterboxPad.
struct Letterbox {
  cv::Size image;                   // colour image size, pixels
  cv::Size input;                   // network input size, pixels
  cv::Size resized;                 // the scaled image inside the input, input pixels
  int pad_x = 0, pad_y = 0;         // left and top padding, input pixels
  double scale_x = 1, scale_y = 1;  // input pixels per image pixel (resized / image)
};

/// The letterbox of an `image`-sized picture into an `input`-sized network input.
Letterbox computeLetterbox(cv::Size image, cv::Size input);

/// Letterboxes `bgr` (CV_8UC3) into *letterboxed (input size, BGR) and writes the network blob
/// *blob: 1x3xHxW CV_32F, RGB, values in [0, 1]. Buffers are reused between calls.
void makeInputBlob(const cv::Mat& bgr, const Letterbox& lb, cv::Mat* letterboxed, cv::Mat* blob);

/// x_depth = a_x * x_input + b_x (continuous coordinates; same for y): where a network-input
/// point lands in the depth image, undoing the letterbox and the colour-to-depth resize.
struct InputToDepth {
  double a_x = 1, b_x = 0, a_y = 1, b_y = 0;
};
InputToDepth inputToDepth(const Letterbox& lb, cv::Size depth_size);

/// Thresholds of the decoding (see DnnOptions for the keys).
struct DecodeParams {
  float score_threshold = 0.25f;
  float nms_iou = 0.45f;
  float mask_threshold = 0.5f;
  int max_detections = 100;
  bool mask_logits = true;  // maskrcnn masks are logits (true) or probabilities (false)
};

/// One decoded instance, in depth-image pixels.
struct Instance {
  int class_id = 0;     // index into the class names
  float score = 0;      // [0, 1]
  cv::Rect box;         // inside the depth image, non-empty
  cv::Mat probability;  // CV_32F depth size, foreground probability in [0, 1], 0 outside box
  cv::Mat mask;         // CV_8U depth size, 1 where probability >= mask_threshold
};

/// Depth-size mask buffers recycled between frames: a buffer comes back zero everywhere while
/// clearing only the box last written into it, so a frame with 20 instances neither allocates
/// nor clears 20 full images. Not thread-safe (one per detector).
class MaskPool {
 public:
  /// Zeroed buffers of `size`: *probability CV_32F, *mask CV_8U.
  void acquire(cv::Size size, cv::Mat* probability, cv::Mat* mask);
  /// Takes back the buffers of `inst` (non-zero only inside inst->box) when nothing else
  /// references them; leaves inst's Mats empty.
  void recycle(Instance* inst);
  size_t size() const { return free_.size(); }

 private:
  struct Entry {
    cv::Mat probability, mask;
    cv::Rect dirty;  // the only region that may be non-zero
  };
  static constexpr size_t kMaxBuffers = 64;
  std::vector<Entry> free_;
};

/// A network output with the name the model gives it.
struct NamedOutput {
  std::string name;
  cv::Mat value;
};

/// The YOLOv8/YOLO11-seg tensors: predictions [1, 4 + nc + nm, N] (cx, cy, w, h in input
/// pixels, nc class scores in [0, 1], nm mask coefficients) and prototypes [1, nm, mh, mw].
struct YoloTensors {
  cv::Mat predictions;
  cv::Mat prototypes;
};

/// The Mask R-CNN tensors: boxes [N, 4] (x1, y1, x2, y2 in input pixels), labels [N] (indices
/// into the class names), scores [N] in [0, 1], masks [N, 1, mh, mw] covering each box (logits
/// or probabilities). OpenCV returns [N] tensors as [N, 1].
struct MaskRcnnTensors {
  cv::Mat boxes, labels, scores, masks;
};

/// "[1, 116, 8400]".
std::string shapeText(const cv::Mat& m);

/// Picks the YOLO tensors out of `outputs` and checks their shapes against `num_classes` names
/// (from `classes_source`, for the message). Throws DnnError (EMF_ERROR_CONFIG) saying what
/// both layouts expect and what was found, or that the class counts differ.
YoloTensors identifyYolo(const std::vector<NamedOutput>& outputs, int num_classes,
                         const std::string& classes_source);

/// Picks the Mask R-CNN tensors out of `outputs` (by name: box, label/class, score, mask; by
/// shape for boxes and masks). Throws DnnError (EMF_ERROR_CONFIG) like identifyYolo.
MaskRcnnTensors identifyMaskRcnn(const std::vector<NamedOutput>& outputs);

/// Indices of `boxes` kept by per-class NMS (cv::dnn::NMSBoxes on each class), best score
/// first, at most max_detections.
std::vector<int> nmsPerClass(const std::vector<cv::Rect2d>& boxes, const std::vector<float>& scores,
                             const std::vector<int>& class_ids, float score_threshold,
                             float nms_iou, int max_detections);

/// Decodes the YOLO layout into instances in the depth image (score threshold, per-class NMS,
/// coefficients x prototypes, bilinear resampling of the logits at the depth pixel centres,
/// sigmoid, crop to the box). Instances whose box or mask is empty in the depth image are
/// dropped. Mask buffers come from `pool` when given.
std::vector<Instance> decodeYolo(const YoloTensors& t, int num_classes, const DecodeParams& p,
                                 const Letterbox& lb, cv::Size depth_size,
                                 MaskPool* pool = nullptr);

/// Decodes the Mask R-CNN layout like decodeYolo (each mask covers its box). Throws DnnError
/// (EMF_ERROR_CONFIG) when a kept label is not an index into the `num_classes` names.
std::vector<Instance> decodeMaskRcnn(const MaskRcnnTensors& t, int num_classes,
                                     const DecodeParams& p, const Letterbox& lb,
                                     cv::Size depth_size, MaskPool* pool = nullptr);

}  // namespace emf_dnn
