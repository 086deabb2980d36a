// The `dnn` detector plugin through the host (dlopen, ABI checks, result validation) on the
// generated ONNX models: the instances they encode must come back exactly (boxes within 1 px,
// classes, scores, masks with IoU >= 0.99) after letterboxing a 640x480 frame.
#include <cstdio>
#include <fstream>

#include "dnn_test_truth.h"
#include "pipeline/detector_plugin.h"
#include "test_support.h"

namespace {

using emf::pipeline::DetectorPlugin;
using emf::pipeline::PluginError;
using namespace emf_dnn_test;

constexpr double kBoxTolerancePx = 1.0;   // reported box corners vs the encoded box
constexpr double kMinMaskIou = 0.99;      // binary mask (probability >= 0.5) vs the encoded shape
constexpr float kScoreTolerance = 1e-6f;  // scores pass through unchanged
constexpr float kMaskThreshold = 0.5f;    // the plugin's default mask_threshold

emf::core::Intrinsics intrinsics(cv::Size depth) {
  emf::core::Intrinsics k;
  k.fx = k.fy = 525.0 * depth.width / 640.0;
  k.cx = depth.width / 2.0 - 0.5;
  k.cy = depth.height / 2.0 - 0.5;
  k.width = depth.width;
  k.height = depth.height;
  return k;
}

std::unique_ptr<DetectorPlugin> loadDnn(const std::string& config, cv::Size depth) {
  return DetectorPlugin::load("dnn", {EMF_PLUGIN_BUILD_DIR}, config, "", intrinsics(depth));
}

emf::core::Frame makeFrame(int64_t index, cv::Size color, cv::Size depth) {
  emf::core::Frame f;
  f.index = index;
  f.timestamp = 0.033 * static_cast<double>(index);
  f.timestamp_text = std::to_string(f.timestamp);
  f.depth = cv::Mat(depth, CV_32F, cv::Scalar(1.5f));
  if (!color.empty()) f.color = syntheticColor(color, static_cast<int>(index));
  return f;
}

/// The message of the PluginError thrown by loading with `config` ("" if none was thrown).
std::string loadError(const std::string& config) {
  try {
    loadDnn(config, cv::Size(640, 480));
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

/// Checks that `out` holds exactly the truth's objects, in a depth image of `depth` size.
void expectTruth(const emf::pipeline::DetectorOutput& out, const Truth& truth, cv::Size depth) {
  ASSERT_TRUE(out.error.empty()) << out.error;
  EXPECT_TRUE(out.rejected.empty()) << out.rejected.front();
  ASSERT_EQ(out.detections.size(), truth.objects.size());
  for (size_t i = 0; i < truth.objects.size(); ++i) {
    // Best score first, as the truth lists them.
    const auto& o = truth.objects[i];
    const auto& d = out.detections[i];
    SCOPED_TRACE("object " + o.class_name);
    EXPECT_EQ(d.class_name, o.class_name);
    EXPECT_NEAR(d.score, o.score, kScoreTolerance);
    const cv::Rect2d b = expectedBox(truth, o, depth);
    EXPECT_NEAR(d.box.x, b.x, kBoxTolerancePx);
    EXPECT_NEAR(d.box.y, b.y, kBoxTolerancePx);
    EXPECT_NEAR(d.box.br().x, b.br().x, kBoxTolerancePx);
    EXPECT_NEAR(d.box.br().y, b.br().y, kBoxTolerancePx);
    ASSERT_EQ(d.mask.size(), depth);
    ASSERT_EQ(d.mask.type(), CV_32F);
    const cv::Mat expected = expectedMask(truth, o, depth);
    EXPECT_GE(maskIou(d.mask >= kMaskThreshold, expected), kMinMaskIou);
    // Probabilities, not a binary mask: values strictly between 0 and 1 inside the shape,
    // exactly 0 outside the box.
    const cv::Mat strictly_between = (d.mask > 0.f) & (d.mask < 1.f);
    EXPECT_GT(cv::countNonZero(strictly_between & (expected != 0)), 0);
    cv::Mat outside = cv::Mat::ones(depth, CV_8U);
    outside(d.box).setTo(0);
    double max_outside = 0;
    cv::minMaxLoc(d.mask, nullptr, &max_outside, nullptr, nullptr, outside);
    EXPECT_EQ(max_outside, 0.0);
  }
}

TEST(DnnPlugin, YoloSegReturnsTheEncodedInstancesAfterLetterboxing) {
  const Truth truth = loadTruth("yolov8_seg.json");
  const cv::Size depth(640, 480);
  auto p = loadDnn("model=" + modelPath("yolov8_seg.onnx") + ",layout=yolov8,input=640x640", depth);
  EXPECT_EQ(p->name(), "dnn");
  expectTruth(p->detect(makeFrame(0, truth.frame, depth)), truth, depth);
}

TEST(DnnPlugin, YoloSegMasksAreResizedToASmallerDepthImage) {
  const Truth truth = loadTruth("yolov8_seg.json");
  const cv::Size depth(320, 240);  // colour 640x480 registered to a half-size depth image
  auto p = loadDnn("model=" + modelPath("yolov8_seg.onnx"), depth);
  expectTruth(p->detect(makeFrame(3, truth.frame, depth)), truth, depth);
}

TEST(DnnPlugin, MaskRcnnLogitsReturnTheEncodedInstances) {
  const Truth truth = loadTruth("maskrcnn.json");  // 800x800 input: scale 1.25, pad 100
  const cv::Size depth(640, 480);
  auto p = loadDnn("model=" + modelPath("maskrcnn.onnx") + ",layout=maskrcnn,input=800x800", depth);
  expectTruth(p->detect(makeFrame(0, truth.frame, depth)), truth, depth);
}

TEST(DnnPlugin, MaskRcnnProbabilitiesReturnTheEncodedInstances) {
  const Truth truth = loadTruth("maskrcnn.json");
  const cv::Size depth(320, 240);
  auto p = loadDnn("model=" + modelPath("maskrcnn_prob.onnx") +
                       ",layout=maskrcnn,input=800x800,mask_values=probabilities",
                   depth);
  expectTruth(p->detect(makeFrame(0, truth.frame, depth)), truth, depth);
}

TEST(DnnPlugin, ThresholdKeysAreApplied) {
  const std::string model = "model=" + modelPath("yolov8_seg.onnx");
  const cv::Size depth(640, 480);
  const auto frame = makeFrame(0, cv::Size(640, 480), depth);
  // score=0.8 keeps the person (0.91), not the cup (0.78).
  auto high = loadDnn(model + ",score=0.8", depth)->detect(frame);
  ASSERT_EQ(high.detections.size(), 1u);
  EXPECT_EQ(high.detections[0].class_name, "person");
  // nms=0.95 keeps the duplicate person (IoU 0.89 with the first, score 0.6).
  auto loose = loadDnn(model + ",nms=0.95", depth)->detect(frame);
  ASSERT_EQ(loose.detections.size(), 3u);
  EXPECT_EQ(loose.detections[2].class_name, "person");
  EXPECT_NEAR(loose.detections[2].score, 0.6f, kScoreTolerance);
  // score=0.15 also admits the chair candidate (0.2).
  auto low = loadDnn(model + ",score=0.15", depth)->detect(frame);
  ASSERT_EQ(low.detections.size(), 3u);
  EXPECT_EQ(low.detections[2].class_name, "chair");
  auto one = loadDnn(model + ",max_detections=1", depth)->detect(frame);
  ASSERT_EQ(one.detections.size(), 1u);
  EXPECT_EQ(one.detections[0].class_name, "person");
}

TEST(DnnPlugin, WrongOutputShapesGiveTheDocumentedError) {
  const std::string e = loadError("model=" + modelPath("yolov8_detect.onnx") + ",layout=yolov8");
  EXPECT_NE(e.find("yolov8_detect.onnx': the model's outputs do not match layout=yolov8"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("detection-only model"), std::string::npos) << e;
  EXPECT_NE(e.find("layout=yolov8 expects 2 outputs, [1, 4+nc+nm, N]"), std::string::npos) << e;
  EXPECT_NE(e.find("layout=maskrcnn expects 4 outputs"), std::string::npos) << e;
  EXPECT_NE(e.find("found 1 output: 'output0' [1, 84, 64]"), std::string::npos) << e;
  EXPECT_NE(e.find("[EMF_ERROR_CONFIG]"), std::string::npos) << e;
}

TEST(DnnPlugin, LayoutMismatchNamesTheOtherLayout) {
  const std::string as_yolo =
      loadError("model=" + modelPath("maskrcnn.onnx") + ",layout=yolov8,input=800x800");
  EXPECT_NE(as_yolo.find("set layout=maskrcnn"), std::string::npos) << as_yolo;
  EXPECT_NE(as_yolo.find("'boxes' [4, 4]"), std::string::npos) << as_yolo;
  const std::string as_maskrcnn =
      loadError("model=" + modelPath("yolov8_seg.onnx") + ",layout=maskrcnn");
  EXPECT_NE(as_maskrcnn.find("set layout=yolov8"), std::string::npos) << as_maskrcnn;
  EXPECT_NE(as_maskrcnn.find("'output1' [1, 32, 160, 160]"), std::string::npos) << as_maskrcnn;
}

TEST(DnnPlugin, MissingOrNonOnnxModelFileIsAnError) {
  const std::string missing = loadError("model=/nonexistent/m.onnx");
  EXPECT_NE(missing.find("model file '/nonexistent/m.onnx' does not exist"), std::string::npos)
      << missing;
  const std::string dir = emf::test::tempDir("dnn_not_onnx");
  const std::string bogus = dir + "/not_a_model.onnx";
  std::ofstream(bogus) << "this is not a protobuf\n";
  const std::string not_onnx = loadError("model=" + bogus);
  EXPECT_NE(not_onnx.find("'" + bogus + "' is not an ONNX model OpenCV can read"),
            std::string::npos)
      << not_onnx;
  const std::string no_model = loadError("layout=yolov8");
  EXPECT_NE(no_model.find("no model given: set model="), std::string::npos) << no_model;
  // A folder is not a model file (it opened as a stream and failed as "not ONNX").
  const std::string folder = loadError("model=" + dir);
  EXPECT_NE(folder.find("model file '" + dir + "' does not exist or is unreadable"),
            std::string::npos)
      << folder;
}

TEST(DnnPlugin, ClassNameCountMismatchIsAnError) {
  const std::string dir = emf::test::tempDir("dnn_classes");
  const std::string names = dir + "/ten.names";
  {
    std::ofstream f(names);
    for (int i = 0; i < 10; ++i) f << "class" << i << "\n";
  }
  const std::string e = loadError("model=" + modelPath("yolov8_seg.onnx") + ",classes=" + names);
  EXPECT_NE(e.find("the model has 80 classes (output [1, 116, 64] = 4 box values + 80 class "
                   "scores + 32 mask coefficients), but the class names '" +
                   names + "' list 10"),
            std::string::npos)
      << e;
  const std::string missing =
      loadError("model=" + modelPath("yolov8_seg.onnx") + ",classes=/nonexistent/coco.names");
  EXPECT_NE(missing.find("cannot read the class names file '/nonexistent/coco.names'"),
            std::string::npos)
      << missing;
  const std::string folder = loadError("model=" + modelPath("yolov8_seg.onnx") + ",classes=" + dir);
  EXPECT_NE(folder.find("cannot read the class names file '" + dir + "'"), std::string::npos)
      << folder;
}

TEST(DnnPlugin, InputSizeTheModelRejectsIsAnError) {
  const std::string e = loadError("model=" + modelPath("yolov8_seg.onnx") + ",input=320x320");
  EXPECT_NE(e.find("failed its first forward pass on a 1x3x320x320 input (input=320x320)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("exported for another input size (set input=WxH to it)"), std::string::npos)
      << e;
}

// A head with the ops of a real YOLOv8-seg export (DFL softmax, anchor decoding, Concat...):
// OpenCV 4.6 cannot broadcast its strides constant; the error says how to convert the model,
// and the converted model returns the encoded instances.
TEST(DnnPlugin, ExportLikeYoloHeadRunsAfterConversion) {
  const std::string raw =
      loadError("model=" + modelPath("yolov8_head.onnx") + ",layout=yolov8,input=320x320");
  EXPECT_NE(raw.find("convert the model with scripts/onnx_for_opencv.py"), std::string::npos)
      << raw;
  const Truth truth = loadTruth("yolov8_head.json");
  for (const cv::Size depth : {cv::Size(640, 480), cv::Size(320, 240)}) {
    SCOPED_TRACE("depth " + std::to_string(depth.width));
    auto p = loadDnn("model=" + modelPath("yolov8_head_opencv.onnx") + ",input=320x320", depth);
    expectTruth(p->detect(makeFrame(0, truth.frame, depth)), truth, depth);
  }
}

TEST(DnnPlugin, BadConfigIsAnError) {
  const std::string model = "model=" + modelPath("yolov8_seg.onnx");
  EXPECT_NE(loadError(model + ",scroe=0.3").find("unknown key 'scroe'"), std::string::npos);
  EXPECT_NE(loadError(model + ",score=1.5").find("score=1.5: expected a number in [0, 1]"),
            std::string::npos);
  EXPECT_NE(loadError(model + ",input=640").find("input=640: expected WxH"), std::string::npos);
  EXPECT_NE(loadError(model + ",target=gpu").find("target=gpu: expected cpu or opencl"),
            std::string::npos);
  EXPECT_NE(loadError(model + ",layout=yolov5").find("layout=yolov5"), std::string::npos);
}

TEST(DnnPlugin, FrameWithoutColourIsAnErrorNotACrash) {
  const cv::Size depth(640, 480);
  auto p = loadDnn("model=" + modelPath("yolov8_seg.onnx"), depth);
  const auto out = p->detect(makeFrame(7, cv::Size(), depth));
  EXPECT_TRUE(out.detections.empty());
  EXPECT_NE(out.error.find("dnn: frame 7 has no colour image"), std::string::npos) << out.error;
  EXPECT_NE(out.error.find("INVALID_ARGUMENT"), std::string::npos) << out.error;
  // The detector keeps working on the next frame with colour.
  const Truth truth = loadTruth("yolov8_seg.json");
  expectTruth(p->detect(makeFrame(8, truth.frame, depth)), truth, depth);
}

// Stand-in for `emf run --detector dnn` on a synthetic sequence (until `emf run` exists): the
// plugin found by name on the build tree's plugin folder, loaded through dlopen, run every
// other frame of a short sequence whose colour changes per frame, as the SLAM's detector
// schedule would; every call must validate and return the encoded instances.
TEST(DnnPlugin, SyntheticSequenceThroughTheHost) {
  const Truth truth = loadTruth("yolov8_seg.json");
  const cv::Size depth(640, 480);
  auto p = loadDnn("model=" + modelPath("yolov8_seg.onnx") + ",layout=yolov8", depth);
  constexpr int kFrames = 6, kEveryN = 2;
  int calls = 0;
  for (int i = 0; i < kFrames; ++i) {
    if (i % kEveryN != 0) continue;
    SCOPED_TRACE("frame " + std::to_string(i));
    auto frame = makeFrame(i, truth.frame, depth);
    frame.depth(cv::Rect(100, 60, 160, 300)).setTo(0.8f + 0.05f * static_cast<float>(i));
    expectTruth(p->detect(frame), truth, depth);
    ++calls;
  }
  EXPECT_EQ(calls, kFrames / kEveryN);
}

}  // namespace
