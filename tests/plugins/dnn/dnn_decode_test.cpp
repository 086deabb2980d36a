// The `dnn` plugin's pre- and post-processing on synthetic tensors (no model): letterbox
// geometry and blob, coordinate mapping, per-class NMS, YOLO and Mask R-CNN decoding with exact
// expected boxes, masks and probabilities, layout recognition errors, options and class names.
#include "dnn_decode.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <opencv2/imgproc.hpp>

#include "dnn_detector.h"
#include "dnn_options.h"
#include "test_support.h"

namespace emf_dnn {
namespace {

constexpr double kCoordTolerance = 1e-9;  // closed-form coordinate maps
constexpr float kBlobTolerance = 1e-6f;   // pixel / 255 in the blob
constexpr float kProbTolerance = 1e-5f;   // float sampling vs the double reference
constexpr int kNumClasses = 3, kNm = 2;

float sigmoid(float x) { return 1.f / (1.f + std::exp(-x)); }

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const DnnError& e) {
    return e.what();
  }
  return "";
}

TEST(DnnLetterbox, KeepsAspectAndCentres) {
  Letterbox lb = computeLetterbox({640, 480}, {640, 640});
  EXPECT_EQ(lb.resized, cv::Size(640, 480));
  EXPECT_EQ(lb.pad_x, 0);
  EXPECT_EQ(lb.pad_y, 80);
  EXPECT_DOUBLE_EQ(lb.scale_x, 1.0);
  lb = computeLetterbox({1280, 720}, {640, 640});
  EXPECT_EQ(lb.resized, cv::Size(640, 360));
  EXPECT_EQ(lb.pad_y, 140);
  EXPECT_DOUBLE_EQ(lb.scale_y, 0.5);
  lb = computeLetterbox({300, 500}, {640, 640});
  EXPECT_EQ(lb.resized, cv::Size(384, 640));
  EXPECT_EQ(lb.pad_x, 128);
  EXPECT_EQ(lb.pad_y, 0);
  EXPECT_THROW(computeLetterbox({0, 480}, {640, 640}), DnnError);
}

TEST(DnnLetterbox, BlobIsRgbOverPadding) {
  cv::Mat bgr(48, 64, CV_8UC3);
  cv::randu(bgr, 0, 256);
  const Letterbox lb = computeLetterbox(bgr.size(), {64, 64});
  cv::Mat letterboxed, blob;
  makeInputBlob(bgr, lb, &letterboxed, &blob);
  ASSERT_EQ(blob.dims, 4);
  EXPECT_EQ(blob.size[0], 1);
  EXPECT_EQ(blob.size[1], 3);
  EXPECT_EQ(blob.size[2], 64);
  EXPECT_EQ(blob.size[3], 64);
  auto at = [&](int c, int y, int x) { return blob.ptr<float>(0, c)[y * 64 + x]; };
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(at(c, 0, 0), kLetterboxPad / 255.f, kBlobTolerance);
    EXPECT_NEAR(at(c, 7, 63), kLetterboxPad / 255.f, kBlobTolerance);
    EXPECT_NEAR(at(c, 56, 10), kLetterboxPad / 255.f, kBlobTolerance);
    for (const cv::Point p : {cv::Point(0, 0), cv::Point(63, 47), cv::Point(17, 30)}) {
      // Blob channel c is RGB; the image is BGR.
      EXPECT_NEAR(at(c, p.y + 8, p.x), bgr.at<cv::Vec3b>(p)[2 - c] / 255.f, kBlobTolerance);
    }
  }
  // A 2x larger image is resized into the same area.
  cv::Mat big;
  cv::resize(bgr, big, {128, 96}, 0, 0, cv::INTER_NEAREST);
  makeInputBlob(big, computeLetterbox(big.size(), {64, 64}), &letterboxed, &blob);
  EXPECT_NEAR(at(0, 7, 5), kLetterboxPad / 255.f, kBlobTolerance);
  EXPECT_NEAR(at(0, 8, 5), bgr.at<cv::Vec3b>(0, 5)[2] / 255.f, 3.f / 255.f);
}

TEST(DnnLetterbox, InputToDepthUndoesLetterboxAndColourResize) {
  const Letterbox lb = computeLetterbox({640, 480}, {640, 640});
  InputToDepth m = inputToDepth(lb, {640, 480});
  EXPECT_NEAR(m.a_x * 0 + m.b_x, 0, kCoordTolerance);
  EXPECT_NEAR(m.a_y * 80 + m.b_y, 0, kCoordTolerance);
  EXPECT_NEAR(m.a_y * 560 + m.b_y, 480, kCoordTolerance);
  m = inputToDepth(lb, {320, 240});
  EXPECT_NEAR(m.a_x * 640 + m.b_x, 320, kCoordTolerance);
  EXPECT_NEAR(m.a_y * 320 + m.b_y, 120, kCoordTolerance);
  const Letterbox wide = computeLetterbox({1280, 720}, {640, 640});  // scale 0.5, pad_y 140
  m = inputToDepth(wide, {640, 360});
  EXPECT_NEAR(m.a_x * 100 + m.b_x, 100, kCoordTolerance);
  EXPECT_NEAR(m.a_y * 240 + m.b_y, 100, kCoordTolerance);
}

TEST(DnnNms, SuppressesWithinAClassOnly) {
  const std::vector<cv::Rect2d> boxes = {{0, 0, 100, 100},   {5, 5, 100, 100}, {2, 2, 100, 100},
                                         {300, 300, 50, 50}, {0, 0, 100, 100}, {400, 0, 10, 10}};
  const std::vector<float> scores = {0.9f, 0.8f, 0.7f, 0.6f, 0.85f, 0.1f};
  const std::vector<int> classes = {0, 0, 1, 0, 2, 0};
  // Box 1 overlaps box 0 (same class): gone. Boxes 2 and 4 overlap too but are other classes.
  // Box 5 is below the score threshold.
  EXPECT_EQ(nmsPerClass(boxes, scores, classes, 0.25f, 0.45f, 100), (std::vector<int>{0, 4, 2, 3}));
  EXPECT_EQ(nmsPerClass(boxes, scores, classes, 0.25f, 0.45f, 2), (std::vector<int>{0, 4}));
  EXPECT_EQ(nmsPerClass(boxes, scores, classes, 0.25f, 0.99f, 100),
            (std::vector<int>{0, 4, 1, 2, 3}));
}

/// Synthetic YOLO tensors: input 64x64 (frame 64x48 -> pad_y 8), prototypes 16x16 (4 input
/// pixels each), nc = 3, nm = 2, 4 anchors.
struct YoloCase {
  cv::Mat pred = cv::Mat(std::vector<int>{1, 4 + kNumClasses + kNm, 4}, CV_32F, cv::Scalar(0));
  cv::Mat protos = cv::Mat(std::vector<int>{1, kNm, 16, 16}, CV_32F, cv::Scalar(0));
  float& p(int c, int i) { return pred.ptr<float>(0, c)[i]; }
  cv::Mat plane(int k) { return cv::Mat(16, 16, CV_32F, protos.ptr<float>(0, k)); }
  void anchor(int i, cv::Rect2d box_input, int cls, float score, float c0, float c1) {
    p(0, i) = static_cast<float>(box_input.x + box_input.width / 2);
    p(1, i) = static_cast<float>(box_input.y + box_input.height / 2);
    p(2, i) = static_cast<float>(box_input.width);
    p(3, i) = static_cast<float>(box_input.height);
    p(4 + cls, i) = score;
    p(4 + kNumClasses, i) = c0;
    p(4 + kNumClasses + 1, i) = c1;
  }
};

/// Reference: bilinear interpolation of `plane` at index (x, y) (pixel centres at integers),
/// border replicated.
double bilinear(const cv::Mat& plane, double x, double y) {
  auto at = [&](int yy, int xx) {
    return static_cast<double>(
        plane.at<float>(std::clamp(yy, 0, plane.rows - 1), std::clamp(xx, 0, plane.cols - 1)));
  };
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  return (1 - fy) * ((1 - fx) * at(y0, x0) + fx * at(y0, x0 + 1)) +
         fy * ((1 - fx) * at(y0 + 1, x0) + fx * at(y0 + 1, x0 + 1));
}

/// Reference probability of a YoloCase instance (frame 64x48 = depth, input 64x64, pad_y 8,
/// prototypes 16x16): sigmoid(sum_k c_k * P_k) sampled at each depth pixel centre inside `box`.
cv::Mat referenceYoloProbability(YoloCase& yc, float c0, float c1, const cv::Rect& box) {
  cv::Mat p = cv::Mat::zeros(48, 64, CV_32F);
  for (int v = box.y; v < box.br().y; ++v) {
    for (int u = box.x; u < box.br().x; ++u) {
      const double x = (u + 0.5) / 4.0 - 0.5, y = (v + 0.5 + 8.0) / 4.0 - 0.5;
      const double logit = c0 * bilinear(yc.plane(0), x, y) + c1 * bilinear(yc.plane(1), x, y);
      p.at<float>(v, u) = static_cast<float>(1.0 / (1.0 + std::exp(-logit)));
    }
  }
  return p;
}

/// Object 1: a square prototype shape; object 2: a ramp; plus a suppressed duplicate and a
/// candidate below the score threshold.
YoloCase squareAndRampCase() {
  YoloCase yc;
  // Prototype 0: logit 3 on proto pixels x 2..7, y 4..9 (input x 8..32, y 16..40), else -3.
  yc.plane(0).setTo(-3.f);
  yc.plane(0)(cv::Rect(2, 4, 6, 6)).setTo(3.f);
  // Prototype 1: a ramp (object 2's mask is a part of its box).
  for (int x = 0; x < 16; ++x) yc.plane(1).col(x).setTo(static_cast<float>(x - 12));
  // Object 1: box input (8, 16)-(40, 40) = frame (8, 8)-(40, 32), class 2, mask = proto 0
  // (the shape ends at x = 32, inside the box).
  yc.anchor(0, {8, 16, 32, 24}, 2, 0.9f, 1.f, 0.f);
  // Object 2: box input (44, 20)-(60, 50), class 0, mask = 0.5 * proto 0 + proto 1.
  yc.anchor(1, {44, 20, 16, 30}, 0, 0.7f, 0.5f, 1.f);
  // Same class as object 1, overlapping: suppressed. Below threshold: ignored.
  yc.anchor(2, {9, 17, 32, 24}, 2, 0.5f, 1.f, 0.f);
  yc.anchor(3, {0, 8, 64, 48}, 1, 0.2f, 0.f, 1.f);
  return yc;
}

TEST(DnnDecodeYolo, BoxesMasksAndProbabilities) {
  YoloCase yc = squareAndRampCase();
  const Letterbox lb = computeLetterbox({64, 48}, {64, 64});
  DecodeParams params;
  const auto out = decodeYolo({yc.pred, yc.protos}, kNumClasses, params, lb, {64, 48});
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].class_id, 2);
  EXPECT_FLOAT_EQ(out[0].score, 0.9f);
  EXPECT_EQ(out[0].box, cv::Rect(8, 8, 32, 24));
  EXPECT_EQ(out[1].class_id, 0);
  EXPECT_FLOAT_EQ(out[1].score, 0.7f);
  EXPECT_EQ(out[1].box, cv::Rect(44, 12, 16, 30));
  const float coeffs[2][2] = {{1.f, 0.f}, {0.5f, 1.f}};
  for (int i = 0; i < 2; ++i) {
    SCOPED_TRACE("instance " + std::to_string(i));
    const cv::Mat ref = referenceYoloProbability(yc, coeffs[i][0], coeffs[i][1], out[i].box);
    double max_diff = 0;
    cv::minMaxLoc(cv::abs(out[i].probability - ref), nullptr, &max_diff);
    EXPECT_LE(max_diff, kProbTolerance);
    const cv::Mat ref_mask = ref >= params.mask_threshold;
    EXPECT_EQ(cv::countNonZero((out[i].mask != 0) != ref_mask), 0);
  }
  // Object 1 is the 24x24 square frame x 8..32, y 8..32, its corners rounded off by the
  // bilinear interpolation (corner pixel: 3 * (0.625^2 - (1 - 0.625^2)) < 0).
  EXPECT_EQ(cv::countNonZero(out[0].mask), 24 * 24 - 4);
  EXPECT_EQ(cv::countNonZero(out[0].mask(cv::Rect(8, 8, 24, 24))), 24 * 24 - 4);
  // Probabilities are passed on: sigmoid(3) deep inside, not 1; 0 outside the box.
  EXPECT_NEAR(out[0].probability.at<float>(20, 20), sigmoid(3.f), kProbTolerance);
  EXPECT_EQ(out[0].probability.at<float>(20, 45), 0.f);
  // Object 2's ramp crosses 0.5 inside the box: only part of it is mask.
  const int n2 = cv::countNonZero(out[1].mask);
  EXPECT_GT(n2, 0);
  EXPECT_LT(n2, out[1].box.area());
}

/// Boxes partly outside the image, an all-negative mask and a box in the padding.
YoloCase clipCase() {
  YoloCase yc;
  yc.plane(0).setTo(4.f);
  yc.plane(1).setTo(-4.f);
  // Box sticking out of the image on the left and into the bottom padding: clipped.
  yc.anchor(0, {-10, 30, 30, 40}, 1, 0.8f, 1.f, 0.f);
  // Mask all below threshold: dropped. Box entirely in the top padding: dropped.
  yc.anchor(1, {40, 20, 10, 10}, 0, 0.9f, 0.f, 1.f);
  yc.anchor(2, {40, 0, 10, 6}, 2, 0.95f, 1.f, 0.f);
  return yc;
}

TEST(DnnDecodeYolo, ClipsBoxesAndDropsEmptyMasks) {
  YoloCase yc = clipCase();
  const auto out = decodeYolo({yc.pred, yc.protos}, kNumClasses, {},
                              computeLetterbox({64, 48}, {64, 64}), {64, 48});
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].box, cv::Rect(0, 22, 20, 26));
  EXPECT_EQ(cv::countNonZero(out[0].mask), 20 * 26);
}

TEST(DnnMaskPool, RecycledBuffersComeBackZero) {
  MaskPool pool;
  Instance a;
  a.box = cv::Rect(2, 3, 4, 5);
  pool.acquire({16, 12}, &a.probability, &a.mask);
  ASSERT_EQ(a.probability.size(), cv::Size(16, 12));
  EXPECT_EQ(cv::countNonZero(a.probability), 0);
  a.probability(a.box).setTo(0.7f);
  a.mask(a.box).setTo(1);
  const float* data = a.probability.ptr<float>();
  pool.recycle(&a);
  EXPECT_TRUE(a.probability.empty());
  EXPECT_EQ(pool.size(), 1u);
  Instance b;
  pool.acquire({16, 12}, &b.probability, &b.mask);
  EXPECT_EQ(b.probability.ptr<float>(), data);  // the same buffer, cleared
  EXPECT_EQ(cv::countNonZero(b.probability), 0);
  EXPECT_EQ(cv::countNonZero(b.mask), 0);
  EXPECT_EQ(pool.size(), 0u);
  // A buffer still referenced elsewhere is not taken back.
  b.box = cv::Rect(0, 0, 16, 12);
  const cv::Mat kept = b.probability;
  pool.recycle(&b);
  EXPECT_EQ(pool.size(), 0u);
  // Decoding into recycled buffers gives what fresh buffers give.
  YoloCase first = squareAndRampCase(), second = clipCase();
  const Letterbox lb = computeLetterbox({64, 48}, {64, 64});
  auto warm = decodeYolo({first.pred, first.protos}, kNumClasses, {}, lb, {64, 48}, &pool);
  ASSERT_EQ(warm.size(), 2u);
  for (auto& inst : warm) pool.recycle(&inst);
  EXPECT_EQ(pool.size(), 2u);
  const auto pooled =
      decodeYolo({second.pred, second.protos}, kNumClasses, {}, lb, {64, 48}, &pool);
  const auto fresh = decodeYolo({second.pred, second.protos}, kNumClasses, {}, lb, {64, 48});
  ASSERT_EQ(pooled.size(), 1u);
  ASSERT_EQ(fresh.size(), 1u);
  EXPECT_EQ(cv::countNonZero(pooled[0].probability != fresh[0].probability), 0);
  EXPECT_EQ(cv::countNonZero(pooled[0].mask != fresh[0].mask), 0);
}

TEST(DnnIdentify, YoloShapesAndClassCount) {
  YoloCase yc;
  const auto t = identifyYolo({{"output1", yc.protos}, {"output0", yc.pred}}, kNumClasses, "'x'");
  EXPECT_EQ(t.predictions.dims, 3);
  EXPECT_EQ(t.prototypes.dims, 4);
  const std::string mismatch = errorOf([&] {
    identifyYolo({{"output0", yc.pred}, {"output1", yc.protos}}, 80, "'c'");
  });
  EXPECT_NE(mismatch.find("the model has 3 classes (output [1, 9, 4] = 4 box values + 3 class "
                          "scores + 2 mask coefficients), but the class names 'c' list 80"),
            std::string::npos)
      << mismatch;
  const std::string one = errorOf([&] { identifyYolo({{"output0", yc.pred}}, kNumClasses, ""); });
  EXPECT_NE(one.find("found 1 output: 'output0' [1, 9, 4]"), std::string::npos) << one;
  const cv::Mat flat(std::vector<int>{1, 9}, CV_32F, cv::Scalar(0));
  const std::string wrong = errorOf([&] {
    identifyYolo({{"a", flat}, {"b", yc.protos}}, kNumClasses, "");
  });
  EXPECT_NE(wrong.find("do not match layout=yolov8"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("'a' [1, 9], 'b' [1, 2, 16, 16]"), std::string::npos) << wrong;
}

struct MaskRcnnCase {
  cv::Mat boxes = cv::Mat(2, 4, CV_32F, cv::Scalar(0));
  cv::Mat labels = cv::Mat(2, 1, CV_32F, cv::Scalar(0));
  cv::Mat scores = cv::Mat(2, 1, CV_32F, cv::Scalar(0));
  cv::Mat masks = cv::Mat(std::vector<int>{2, 1, 4, 4}, CV_32F, cv::Scalar(-6));
  std::vector<NamedOutput> outputs() const {
    return {{"scores", scores}, {"masks", masks}, {"labels", labels}, {"boxes", boxes}};
  }
};

TEST(DnnDecodeMaskRcnn, MaskCoversItsBox) {
  MaskRcnnCase mc;
  // Detection 0: input box (8, 16)-(40, 48) -> frame (8, 8)-(40, 40) (pad 8); mask cells are
  // 8x8 frame pixels; cells (1..2, 0..3) set: the middle two columns.
  const float b0[4] = {8, 16, 40, 48};
  std::copy(b0, b0 + 4, mc.boxes.ptr<float>(0));
  mc.labels.at<float>(0) = 1;
  mc.scores.at<float>(0) = 0.8f;
  float* m0 = mc.masks.ptr<float>(0);
  for (int y = 0; y < 4; ++y) m0[y * 4 + 1] = m0[y * 4 + 2] = 6.f;
  // Detection 1: below the score threshold.
  mc.scores.at<float>(1) = 0.1f;
  const auto t = identifyMaskRcnn(mc.outputs());
  const Letterbox lb = computeLetterbox({64, 48}, {64, 64});
  const auto out = decodeMaskRcnn(t, kNumClasses, {}, lb, {32, 24});  // half-size depth
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].class_id, 1);
  EXPECT_EQ(out[0].box, cv::Rect(4, 4, 16, 16));
  cv::Mat expected = cv::Mat::zeros(24, 32, CV_8U);
  expected(cv::Rect(8, 4, 8, 16)).setTo(1);  // frame x 16..32 -> depth 8..16
  EXPECT_EQ(cv::countNonZero(out[0].mask != expected), 0);
  EXPECT_NEAR(out[0].probability.at<float>(10, 10), sigmoid(6.f), kProbTolerance);

  // The same masks as probabilities.
  DecodeParams prob;
  prob.mask_logits = false;
  cv::Mat p = mc.masks.clone();
  for (float* v = p.ptr<float>(); v != p.ptr<float>() + p.total(); ++v) *v = sigmoid(*v);
  const auto out_p =
      decodeMaskRcnn({mc.boxes, mc.labels, mc.scores, p}, kNumClasses, prob, lb, {32, 24});
  ASSERT_EQ(out_p.size(), 1u);
  EXPECT_EQ(cv::countNonZero(out_p[0].mask != expected), 0);
  EXPECT_NEAR(out_p[0].probability.at<float>(10, 10), sigmoid(6.f), kProbTolerance);

  // A label that is no index into the names is an error.
  mc.labels.at<float>(0) = 3;
  const std::string e = errorOf([&] { decodeMaskRcnn(t, kNumClasses, {}, lb, {32, 24}); });
  EXPECT_NE(e.find("detection 0 has label 3.000000, not an index into the 3 class names"),
            std::string::npos)
      << e;
}

TEST(DnnIdentify, MaskRcnnByNameAndShape) {
  MaskRcnnCase mc;
  auto outs = mc.outputs();
  const auto t = identifyMaskRcnn(outs);
  EXPECT_EQ(t.boxes.data, mc.boxes.data);
  EXPECT_EQ(t.labels.data, mc.labels.data);
  EXPECT_EQ(t.scores.data, mc.scores.data);
  EXPECT_EQ(t.masks.data, mc.masks.data);
  // Boxes and masks are found by shape when unnamed; labels and scores cannot be.
  outs[1].name = "out_a";
  outs[3].name = "out_b";
  EXPECT_EQ(identifyMaskRcnn(outs).masks.data, mc.masks.data);
  outs[0].name = "out_c";
  const std::string unnamed = errorOf([&] { identifyMaskRcnn(outs); });
  EXPECT_NE(unnamed.find("name them boxes, labels, scores and masks"), std::string::npos)
      << unnamed;
  // Inconsistent N.
  MaskRcnnCase bad;
  bad.scores = cv::Mat(3, 1, CV_32F, cv::Scalar(0));
  const std::string n = errorOf([&] { identifyMaskRcnn(bad.outputs()); });
  EXPECT_NE(n.find("(boxes [2, 4], labels [2, 1], scores [3, 1], masks [2, 1, 4, 4])"),
            std::string::npos)
      << n;
  const std::string two = errorOf([&] { identifyMaskRcnn({outs[0], outs[1]}); });
  EXPECT_NE(two.find("set layout=yolov8"), std::string::npos) << two;
}

TEST(DnnOptionsTest, ParsesKeysAndRejectsBadValues) {
  const DnnOptions o = DnnOptions::parse(
      "model=/m.onnx,layout=maskrcnn,input=800x608,classes=/c.names,score=0.4,nms=0.6,"
      "mask_threshold=0.3,target=opencl,max_detections=7,mask_values=probabilities,threads=1");
  EXPECT_EQ(o.model_path, "/m.onnx");
  EXPECT_EQ(o.layout, Layout::kMaskRcnn);
  EXPECT_EQ(o.input_width_px, 800);
  EXPECT_EQ(o.input_height_px, 608);
  EXPECT_EQ(o.classes_path, "/c.names");
  EXPECT_FLOAT_EQ(o.score_threshold, 0.4f);
  EXPECT_FLOAT_EQ(o.nms_iou, 0.6f);
  EXPECT_FLOAT_EQ(o.mask_threshold, 0.3f);
  EXPECT_EQ(o.target, Target::kOpenCl);
  EXPECT_EQ(o.max_detections, 7);
  EXPECT_FALSE(o.mask_logits);
  EXPECT_EQ(o.threads, 1);
  const DnnOptions d = DnnOptions::parse("model=/m.onnx");
  EXPECT_EQ(d.threads, 0);
  EXPECT_EQ(d.layout, Layout::kYoloV8);
  EXPECT_EQ(d.input_width_px, 640);
  EXPECT_EQ(d.target, Target::kCpu);
  EXPECT_EQ(d.classes_path, defaultClassesPath());
  for (const char* bad :
       {"model=/m,score=-0.1", "model=/m,nms=x", "model=/m,mask_threshold=1", "model=/m,input=0x5",
        "model=/m,input=64x", "model=/m,max_detections=0", "model=/m,mask_values=raw",
        "model=/m,threads=-1", "model=/m,threads=257", "model", "", "model=/m,foo=1"}) {
    EXPECT_THROW(DnnOptions::parse(bad), DnnError) << bad;
  }
  EXPECT_NE(errorOf([] {
              DnnOptions::parse("model=/m,mask_threshold=1");
            }).find("mask_threshold=1: expected a number in (0, 1)"),
            std::string::npos);
}

TEST(DnnClassNames, ShippedCocoNamesAndFileErrors) {
  const auto coco = readClassNames(defaultClassesPath());
  ASSERT_EQ(coco.size(), 80u);
  EXPECT_EQ(coco[0], "person");
  EXPECT_EQ(coco[41], "cup");
  EXPECT_EQ(coco[79], "toothbrush");
  const std::string dir = emf::test::tempDir("dnn_names");
  std::ofstream(dir + "/crlf.names") << "a b\r\nc\r\n\r\n";
  EXPECT_EQ(readClassNames(dir + "/crlf.names"), (std::vector<std::string>{"a b", "c"}));
  std::ofstream(dir + "/hole.names") << "a\n\nc\n";
  EXPECT_NE(errorOf([&] { readClassNames(dir + "/hole.names"); }).find("hole.names:2: empty"),
            std::string::npos);
  std::ofstream(dir + "/empty.names") << "\n";
  EXPECT_NE(errorOf([&] { readClassNames(dir + "/empty.names"); }).find("has no names"),
            std::string::npos);
  EXPECT_THROW(readClassNames(dir + "/missing.names"), DnnError);
}

TEST(DnnTarget, OpenClFallsBackToCpuWithAReason) {
  std::string w;
  EXPECT_EQ(chooseTarget(Target::kCpu, true, true, false, "gpu", &w), Target::kCpu);
  EXPECT_TRUE(w.empty());
  EXPECT_EQ(chooseTarget(Target::kOpenCl, true, true, false, "gpu", &w), Target::kOpenCl);
  EXPECT_TRUE(w.empty());
  EXPECT_EQ(chooseTarget(Target::kOpenCl, false, false, false, "", &w), Target::kCpu);
  EXPECT_NE(w.find("no usable OpenCL device"), std::string::npos) << w;
  EXPECT_EQ(chooseTarget(Target::kOpenCl, true, false, false, "pthread-cpu", &w), Target::kCpu);
  EXPECT_NE(w.find("'pthread-cpu' is not a GPU (set OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES=1"),
            std::string::npos)
      << w;
  EXPECT_EQ(chooseTarget(Target::kOpenCl, true, false, true, "pthread-cpu", &w), Target::kOpenCl);
  EXPECT_TRUE(w.empty());
}

}  // namespace
}  // namespace emf_dnn
