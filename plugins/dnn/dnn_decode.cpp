#include "dnn_decode.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <map>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

namespace emf_dnn {
namespace {

constexpr const char* kLayoutsExpected =
    "layout=yolov8 expects 2 outputs, [1, 4+nc+nm, N] (cx, cy, w, h, nc class scores, nm mask "
    "coefficients) and [1, nm, mh, mw] (mask prototypes); layout=maskrcnn expects 4 outputs "
    "named boxes [N, 4], labels [N], scores [N], masks [N, 1, mh, mw]";

[[noreturn]] void shapeError(const std::string& what, const std::vector<NamedOutput>& outputs) {
  std::string found;
  for (const auto& o : outputs) {
    found += (found.empty() ? "" : ", ") + ("'" + o.name + "' " + shapeText(o.value));
  }
  throw DnnError(EMF_ERROR_CONFIG, what + "; " + kLayoutsExpected + "; found " +
                                       std::to_string(outputs.size()) + " output" +
                                       (outputs.size() == 1 ? "" : "s") + ": " + found);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Number of values of an [N] tensor (OpenCV gives [N, 1], [1, N] or [N]), or -1.
int vectorLength(const cv::Mat& m) {
  if (m.dims == 1) return m.size[0];
  if (m.dims == 2 && m.size[1] == 1) return m.size[0];
  if (m.dims == 2 && m.size[0] == 1) return m.size[1];
  return -1;
}

/// A float copy of an [N] tensor as a row, whatever its depth.
std::vector<float> vectorValues(const cv::Mat& m) {
  cv::Mat f;
  m.reshape(1, 1).convertTo(f, CV_32F);
  return std::vector<float>(f.begin<float>(), f.end<float>());
}

/// One axis of the bilinear sampling: neighbours i0, i1 and weight f of i1 at index `x` in
/// [0, n), the border replicated.
struct Tap {
  int i0 = 0, i1 = 0;
  float f = 0;
};
Tap tap(double x, int n) {
  if (!(x > 0.0)) return {0, 0, 0.f};  // also NaN
  if (x >= n - 1) return {n - 1, n - 1, 0.f};
  const int i0 = static_cast<int>(x);
  return {i0, i0 + 1, static_cast<float>(x - i0)};
}

/// Fills inst->probability/mask inside inst->box by bilinear sampling of `values` (CV_32F,
/// border replicated) at the depth pixel centres: for depth pixel u, src index
/// x = m_x * u + c_x (same for y), pixel centres of `values` at integer indices. `logits`
/// applies the sigmoid after sampling; probabilities are clamped to [0, 1] (NaN -> 0) for the
/// host. The mapping is axis-aligned, so the taps are computed once per column and per row.
/// Returns false (buffers handed back) when no pixel reaches mask_threshold.
bool sampleMask(const cv::Mat& values, double m_x, double c_x, double m_y, double c_y, bool logits,
                float mask_threshold, cv::Size depth_size, MaskPool* pool, Instance* inst) {
  const cv::Rect& box = inst->box;
  std::vector<Tap> cols(static_cast<size_t>(box.width));
  for (int i = 0; i < box.width; ++i) cols[i] = tap(m_x * (box.x + i) + c_x, values.cols);
  cv::Mat roi(box.size(), CV_32F);
  const float sign = logits ? -1.f : 1.f;  // logits: sample -x, then exp, then 1 / (1 + .)
  for (int j = 0; j < box.height; ++j) {
    const Tap r = tap(m_y * (box.y + j) + c_y, values.rows);
    const float* row0 = values.ptr<float>(r.i0);
    const float* row1 = values.ptr<float>(r.i1);
    float* out = roi.ptr<float>(j);
    for (int i = 0; i < box.width; ++i) {
      const Tap& c = cols[static_cast<size_t>(i)];
      const float a = row0[c.i0] + (row0[c.i1] - row0[c.i0]) * c.f;
      const float b = row1[c.i0] + (row1[c.i1] - row1[c.i0]) * c.f;
      out[i] = sign * (a + (b - a) * r.f);
    }
  }
  if (logits) cv::exp(roi, roi);  // vectorised
  if (pool) {
    pool->acquire(depth_size, &inst->probability, &inst->mask);
  } else {
    inst->probability = cv::Mat::zeros(depth_size, CV_32F);
    inst->mask = cv::Mat::zeros(depth_size, CV_8U);
  }
  int in_mask = 0;
  for (int j = 0; j < box.height; ++j) {
    const float* v = roi.ptr<float>(j);
    float* prob = inst->probability.ptr<float>(box.y + j) + box.x;
    uint8_t* mask = inst->mask.ptr<uint8_t>(box.y + j) + box.x;
    for (int i = 0; i < box.width; ++i) {
      float p = logits ? 1.f / (1.f + v[i]) : v[i];
      p = p >= 0.f ? std::min(p, 1.f) : 0.f;  // NaN -> 0
      prob[i] = p;
      mask[i] = p >= mask_threshold ? 1 : 0;
      in_mask += mask[i];
    }
  }
  if (in_mask > 0) return true;
  if (pool) {
    pool->recycle(inst);
  } else {
    inst->probability.release();
    inst->mask.release();
  }
  return false;
}

/// The depth-pixel box of an input-pixel box (corners rounded), clipped to the image.
cv::Rect depthBox(double x1, double y1, double x2, double y2, const InputToDepth& m,
                  cv::Size depth_size) {
  auto clampRound = [](double v, int hi) {
    if (!std::isfinite(v)) return 0;
    return static_cast<int>(std::lround(std::min(std::max(v, 0.0), static_cast<double>(hi))));
  };
  const int u0 = clampRound(m.a_x * x1 + m.b_x, depth_size.width);
  const int v0 = clampRound(m.a_y * y1 + m.b_y, depth_size.height);
  const int u1 = clampRound(m.a_x * x2 + m.b_x, depth_size.width);
  const int v1 = clampRound(m.a_y * y2 + m.b_y, depth_size.height);
  return cv::Rect(u0, v0, std::max(0, u1 - u0), std::max(0, v1 - v0));
}

}  // namespace

void MaskPool::acquire(cv::Size size, cv::Mat* probability, cv::Mat* mask) {
  for (size_t i = free_.size(); i-- > 0;) {
    Entry& e = free_[i];
    if (e.probability.size() != size) continue;
    e.probability(e.dirty).setTo(0);
    e.mask(e.dirty).setTo(0);
    *probability = std::move(e.probability);
    *mask = std::move(e.mask);
    free_.erase(free_.begin() + static_cast<std::ptrdiff_t>(i));
    return;
  }
  *probability = cv::Mat::zeros(size, CV_32F);
  *mask = cv::Mat::zeros(size, CV_8U);
}

void MaskPool::recycle(Instance* inst) {
  auto sole = [](const cv::Mat& m) { return m.u != nullptr && m.u->refcount == 1; };
  const cv::Rect whole(0, 0, inst->probability.cols, inst->probability.rows);
  if (free_.size() < kMaxBuffers && sole(inst->probability) && sole(inst->mask) &&
      inst->probability.type() == CV_32F && inst->mask.type() == CV_8U &&
      inst->probability.isContinuous() && inst->mask.size() == inst->probability.size()) {
    free_.push_back({std::move(inst->probability), std::move(inst->mask), inst->box & whole});
  }
  inst->probability.release();
  inst->mask.release();
}

Letterbox computeLetterbox(cv::Size image, cv::Size input) {
  if (image.width <= 0 || image.height <= 0 || input.width <= 0 || input.height <= 0) {
    throw DnnError(EMF_ERROR_INVALID_ARGUMENT, "dnn: empty image or network input size");
  }
  Letterbox lb;
  lb.image = image;
  lb.input = input;
  const double r = std::min(static_cast<double>(input.width) / image.width,
                            static_cast<double>(input.height) / image.height);
  lb.resized.width = std::clamp(static_cast<int>(std::lround(image.width * r)), 1, input.width);
  lb.resized.height = std::clamp(static_cast<int>(std::lround(image.height * r)), 1, input.height);
  lb.pad_x = (input.width - lb.resized.width) / 2;
  lb.pad_y = (input.height - lb.resized.height) / 2;
  lb.scale_x = static_cast<double>(lb.resized.width) / image.width;
  lb.scale_y = static_cast<double>(lb.resized.height) / image.height;
  return lb;
}

void makeInputBlob(const cv::Mat& bgr, const Letterbox& lb, cv::Mat* letterboxed, cv::Mat* blob) {
  CV_Assert(bgr.type() == CV_8UC3 && bgr.size() == lb.image);
  letterboxed->create(lb.input, CV_8UC3);
  const cv::Rect inner(lb.pad_x, lb.pad_y, lb.resized.width, lb.resized.height);
  // Pad only the borders; the inner part is written by the resize (or the copy).
  const cv::Scalar pad(kLetterboxPad, kLetterboxPad, kLetterboxPad);
  (*letterboxed)(cv::Rect(0, 0, lb.input.width, inner.y)).setTo(pad);
  (*letterboxed)(cv::Rect(0, inner.br().y, lb.input.width, lb.input.height - inner.br().y))
      .setTo(pad);
  (*letterboxed)(cv::Rect(0, inner.y, inner.x, inner.height)).setTo(pad);
  (*letterboxed)(cv::Rect(inner.br().x, inner.y, lb.input.width - inner.br().x, inner.height))
      .setTo(pad);
  cv::Mat dst = (*letterboxed)(inner);
  if (inner.size() == bgr.size()) {
    bgr.copyTo(dst);
  } else {
    cv::resize(bgr, dst, inner.size(), 0, 0, cv::INTER_LINEAR);
  }
  cv::dnn::blobFromImage(*letterboxed, *blob, 1.0 / 255.0, cv::Size(), cv::Scalar(),
                         /*swapRB=*/true, /*crop=*/false, CV_32F);
}

InputToDepth inputToDepth(const Letterbox& lb, cv::Size depth_size) {
  // x_image = (x_input - pad_x) / scale_x;  x_depth = x_image * depth_width / image_width.
  InputToDepth m;
  const double kx = static_cast<double>(depth_size.width) / lb.image.width;
  const double ky = static_cast<double>(depth_size.height) / lb.image.height;
  m.a_x = kx / lb.scale_x;
  m.b_x = -lb.pad_x * m.a_x;
  m.a_y = ky / lb.scale_y;
  m.b_y = -lb.pad_y * m.a_y;
  return m;
}

std::string shapeText(const cv::Mat& m) {
  std::string s = "[";
  for (int i = 0; i < m.dims; ++i) s += (i ? ", " : "") + std::to_string(m.size[i]);
  return s + "]";
}

YoloTensors identifyYolo(const std::vector<NamedOutput>& outputs, int num_classes,
                         const std::string& classes_source) {
  YoloTensors t;
  int n3 = 0, n4 = 0;
  for (const auto& o : outputs) {
    if (o.value.dims == 3 && o.value.size[0] == 1) {
      t.predictions = o.value;
      ++n3;
    } else if (o.value.dims == 4 && o.value.size[0] == 1) {
      t.prototypes = o.value;
      ++n4;
    }
  }
  if (outputs.size() != 2 || n3 != 1 || n4 != 1) {
    std::string what = "the model's outputs do not match layout=yolov8";
    if (outputs.size() == 1 && n3 == 1) {
      what += " (one [1, 4+nc, N] output is a detection-only model: export the -seg variant)";
    } else if (outputs.size() == 4) {
      what += " (4 outputs: is it a Mask R-CNN model? set layout=maskrcnn)";
    }
    shapeError(what, outputs);
  }
  for (const cv::Mat* m : {&t.predictions, &t.prototypes}) {
    if (m->type() != CV_32F) {
      shapeError(
          "the model's outputs are not 32-bit float (type " + std::to_string(m->type()) + ")",
          outputs);
    }
  }
  const int channels = t.predictions.size[1];
  const int nm = t.prototypes.size[1];
  const int model_classes = channels - 4 - nm;
  if (model_classes <= 0) {
    shapeError("output [1, " + std::to_string(channels) + ", N] has too few channels for 4 box " +
                   "values and " + std::to_string(nm) + " mask coefficients (prototypes have " +
                   std::to_string(nm) + " channels)",
               outputs);
  }
  if (model_classes != num_classes) {
    throw DnnError(EMF_ERROR_CONFIG,
                   "the model has " + std::to_string(model_classes) + " classes (output " +
                       shapeText(t.predictions) + " = 4 box values + " +
                       std::to_string(model_classes) + " class scores + " + std::to_string(nm) +
                       " mask coefficients), but the class names " + classes_source + " list " +
                       std::to_string(num_classes) + ": pass classes= a file with " +
                       std::to_string(model_classes) + " names, one per line, in training order");
  }
  return t;
}

MaskRcnnTensors identifyMaskRcnn(const std::vector<NamedOutput>& outputs) {
  if (outputs.size() != 4) {
    std::string what = "the model's outputs do not match layout=maskrcnn";
    if (outputs.size() == 2) what += " (2 outputs: is it a YOLO-seg model? set layout=yolov8)";
    shapeError(what, outputs);
  }
  MaskRcnnTensors t;
  std::vector<bool> used(outputs.size(), false);
  auto take = [&](cv::Mat* dst, size_t i) {
    if (!dst->empty()) return;
    *dst = outputs[i].value;
    used[i] = true;
  };
  for (size_t i = 0; i < outputs.size(); ++i) {
    const std::string n = lower(outputs[i].name);
    if (n.find("box") != std::string::npos) {
      take(&t.boxes, i);
    } else if (n.find("label") != std::string::npos || n.find("class") != std::string::npos) {
      take(&t.labels, i);
    } else if (n.find("score") != std::string::npos) {
      take(&t.scores, i);
    } else if (n.find("mask") != std::string::npos) {
      take(&t.masks, i);
    }
  }
  // Unnamed boxes and masks are unambiguous by shape; labels and scores are not.
  for (size_t i = 0; i < outputs.size(); ++i) {
    if (used[i]) continue;
    const cv::Mat& v = outputs[i].value;
    if (v.dims == 4 || (v.dims == 3 && v.size[0] > 1 && t.masks.empty())) {
      take(&t.masks, i);
    } else if (v.dims == 2 && v.size[1] == 4) {
      take(&t.boxes, i);
    }
  }
  if (t.boxes.empty() || t.labels.empty() || t.scores.empty() || t.masks.empty()) {
    shapeError(
        "cannot tell the maskrcnn outputs apart: name them boxes, labels, scores and masks when "
        "exporting (torch.onnx.export(..., output_names=[\"boxes\", \"labels\", \"scores\", "
        "\"masks\"]))",
        outputs);
  }
  const int n = t.boxes.dims == 2 ? t.boxes.size[0] : -1;
  const bool boxes_ok = t.boxes.dims == 2 && t.boxes.size[1] == 4;
  const bool masks_ok = (t.masks.dims == 4 && t.masks.size[0] == n && t.masks.size[1] == 1) ||
                        (t.masks.dims == 3 && t.masks.size[0] == n);
  if (!boxes_ok || !masks_ok || vectorLength(t.labels) != n || vectorLength(t.scores) != n) {
    shapeError("the model's outputs do not match layout=maskrcnn (boxes " + shapeText(t.boxes) +
                   ", labels " + shapeText(t.labels) + ", scores " + shapeText(t.scores) +
                   ", masks " + shapeText(t.masks) + ")",
               outputs);
  }
  if (t.boxes.type() != CV_32F || t.scores.type() != CV_32F || t.masks.type() != CV_32F) {
    shapeError("maskrcnn boxes, scores and masks must be 32-bit float", outputs);
  }
  return t;
}

std::vector<int> nmsPerClass(const std::vector<cv::Rect2d>& boxes, const std::vector<float>& scores,
                             const std::vector<int>& class_ids, float score_threshold,
                             float nms_iou, int max_detections) {
  std::map<int, std::vector<int>> by_class;
  for (size_t i = 0; i < boxes.size(); ++i) by_class[class_ids[i]].push_back(static_cast<int>(i));
  std::vector<int> kept;
  std::vector<cv::Rect2d> class_boxes;
  std::vector<float> class_scores;
  std::vector<int> class_kept;
  for (const auto& [cls, members] : by_class) {
    (void)cls;
    class_boxes.clear();
    class_scores.clear();
    for (int i : members) {
      class_boxes.push_back(boxes[i]);
      class_scores.push_back(scores[i]);
    }
    cv::dnn::NMSBoxes(class_boxes, class_scores, score_threshold, nms_iou, class_kept);
    for (int k : class_kept) kept.push_back(members[k]);
  }
  // Best first; ties by index so the order does not depend on the class grouping.
  std::sort(kept.begin(), kept.end(),
            [&](int a, int b) { return scores[a] != scores[b] ? scores[a] > scores[b] : a < b; });
  if (static_cast<int>(kept.size()) > max_detections) kept.resize(max_detections);
  return kept;
}

std::vector<Instance> decodeYolo(const YoloTensors& t, int num_classes, const DecodeParams& p,
                                 const Letterbox& lb, cv::Size depth_size, MaskPool* pool) {
  const int channels = t.predictions.size[1], n = t.predictions.size[2];
  const int nm = t.prototypes.size[1], mh = t.prototypes.size[2], mw = t.prototypes.size[3];
  CV_Assert(channels == 4 + num_classes + nm && t.predictions.isContinuous() &&
            t.prototypes.isContinuous());
  const float* pred = t.predictions.ptr<float>();
  auto row = [&](int c) { return pred + static_cast<size_t>(c) * n; };

  // Best score per anchor over the class rows (vectorised); the arg max only for the few
  // anchors above the threshold.
  const cv::Mat class_scores(num_classes, n, CV_32F, const_cast<float*>(row(4)));
  cv::Mat best_row;
  cv::reduce(class_scores, best_row, 0, cv::REDUCE_MAX);
  const float* best = best_row.ptr<float>();
  std::vector<cv::Rect2d> boxes;
  std::vector<float> scores;
  std::vector<int> classes, anchors;
  const float *cx = row(0), *cy = row(1), *w = row(2), *h = row(3);
  for (int i = 0; i < n; ++i) {
    if (!(best[i] >= p.score_threshold) || !(w[i] > 0.f) || !(h[i] > 0.f)) continue;
    int best_class = 0;
    for (int c = 1; c < num_classes; ++c) {
      if (row(4 + c)[i] > row(4 + best_class)[i]) best_class = c;
    }
    boxes.emplace_back(cx[i] - 0.5 * w[i], cy[i] - 0.5 * h[i], w[i], h[i]);
    scores.push_back(std::min(best[i], 1.f));
    classes.push_back(best_class);
    anchors.push_back(i);
  }
  const std::vector<int> kept =
      nmsPerClass(boxes, scores, classes, p.score_threshold, p.nms_iou, p.max_detections);

  // Depth pixel u -> prototype index: x_proto = (x_input) * mw / input_width, centre-aligned.
  const InputToDepth m = inputToDepth(lb, depth_size);
  const double rx = static_cast<double>(mw) / lb.input.width;
  const double ry = static_cast<double>(mh) / lb.input.height;
  const double mx = rx / m.a_x, my = ry / m.a_y;  // proto pixels per depth pixel
  const double cx0 = (0.5 - m.b_x) / m.a_x * rx - 0.5, cy0 = (0.5 - m.b_y) / m.a_y * ry - 0.5;

  std::vector<Instance> out;
  cv::Mat logits;
  for (int k : kept) {
    Instance inst;
    inst.class_id = classes[k];
    inst.score = scores[k];
    const cv::Rect2d& b = boxes[k];
    inst.box = depthBox(b.x, b.y, b.x + b.width, b.y + b.height, m, depth_size);
    if (inst.box.empty()) continue;
    // The prototype pixels the box samples (one extra on each side for the interpolation).
    const int px0 = std::clamp(static_cast<int>(std::floor(mx * inst.box.x + cx0)), 0, mw - 1);
    const int py0 = std::clamp(static_cast<int>(std::floor(my * inst.box.y + cy0)), 0, mh - 1);
    const int px1 =
        std::clamp(static_cast<int>(std::floor(mx * inst.box.br().x + cx0)) + 1, 0, mw - 1);
    const int py1 =
        std::clamp(static_cast<int>(std::floor(my * inst.box.br().y + cy0)) + 1, 0, mh - 1);
    const cv::Rect region(px0, py0, px1 - px0 + 1, py1 - py0 + 1);
    logits.create(region.size(), CV_32F);
    logits.setTo(0);
    for (int j = 0; j < nm; ++j) {
      const float coefficient = row(4 + num_classes + j)[anchors[k]];
      const cv::Mat plane(
          mh, mw, CV_32F,
          const_cast<float*>(t.prototypes.ptr<float>()) + static_cast<size_t>(j) * mh * mw);
      cv::scaleAdd(plane(region), coefficient, logits, logits);
    }
    if (sampleMask(logits, mx, cx0 - region.x, my, cy0 - region.y, /*logits=*/true,
                   p.mask_threshold, depth_size, pool, &inst)) {
      out.push_back(std::move(inst));
    }
  }
  return out;
}

std::vector<Instance> decodeMaskRcnn(const MaskRcnnTensors& t, int num_classes,
                                     const DecodeParams& p, const Letterbox& lb,
                                     cv::Size depth_size, MaskPool* pool) {
  const int n = t.boxes.size[0];
  const int mh = t.masks.size[t.masks.dims - 2], mw = t.masks.size[t.masks.dims - 1];
  const std::vector<float> labels = vectorValues(t.labels), scores_all = vectorValues(t.scores);
  cv::Mat boxes_f = t.boxes.reshape(1, n);
  std::vector<cv::Rect2d> boxes;
  std::vector<float> scores;
  std::vector<int> classes, index;
  for (int i = 0; i < n; ++i) {
    const float* b = boxes_f.ptr<float>(i);
    if (!(scores_all[i] >= p.score_threshold) || !(b[2] > b[0]) || !(b[3] > b[1])) continue;
    const float label = labels[i];
    if (!(label >= 0.f) || label != std::floor(label) || label >= static_cast<float>(num_classes)) {
      throw DnnError(EMF_ERROR_CONFIG,
                     "maskrcnn detection " + std::to_string(i) + " has label " +
                         std::to_string(label) + ", not an index into the " +
                         std::to_string(num_classes) +
                         " class names (torchvision COCO models use 91 category ids with "
                         "__background__ = 0: pass classes= a file listing all of them)");
    }
    boxes.emplace_back(b[0], b[1], b[2] - b[0], b[3] - b[1]);
    scores.push_back(std::min(scores_all[i], 1.f));
    classes.push_back(static_cast<int>(label));
    index.push_back(i);
  }
  const std::vector<int> kept =
      nmsPerClass(boxes, scores, classes, p.score_threshold, p.nms_iou, p.max_detections);
  const InputToDepth m = inputToDepth(lb, depth_size);
  std::vector<Instance> out;
  for (int k : kept) {
    Instance inst;
    inst.class_id = classes[k];
    inst.score = scores[k];
    const cv::Rect2d& b = boxes[k];
    inst.box = depthBox(b.x, b.y, b.x + b.width, b.y + b.height, m, depth_size);
    if (inst.box.empty()) continue;
    // Depth pixel u -> mask index: (x_input(u + 0.5) - x1) * mw / box_width - 0.5.
    const double sx = mw / b.width, sy = mh / b.height;
    const double mx = sx / m.a_x, my = sy / m.a_y;
    const double cx0 = ((0.5 - m.b_x) / m.a_x - b.x) * sx - 0.5;
    const double cy0 = ((0.5 - m.b_y) / m.a_y - b.y) * sy - 0.5;
    const cv::Mat mask(
        mh, mw, CV_32F,
        const_cast<float*>(t.masks.ptr<float>()) + static_cast<size_t>(index[k]) * mh * mw);
    if (sampleMask(mask, mx, cx0, my, cy0, p.mask_logits, p.mask_threshold, depth_size, pool,
                   &inst)) {
      out.push_back(std::move(inst));
    }
  }
  return out;
}

}  // namespace emf_dnn
