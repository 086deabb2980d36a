// The `dnn` detector with target=opencl on PoCL's CPU device. OpenCV's DNN runs OpenCL only on
// GPUs unless OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES is set, and picks its device by
// OPENCV_OPENCL_DEVICE; this test sets both (its own process, before OpenCV reads them) and
// checks that the OpenCL path really runs and gives the CPU path's instances.
#include <gtest/gtest.h>

#include <cstdlib>

#include "dnn_detector.h"
#include "dnn_test_truth.h"

namespace emf_dnn {
namespace {

constexpr float kOpenClVsCpuProbTolerance = 1e-4f;  // float32 on both paths, other op order
constexpr double kMinMaskIou = 0.99;

TEST(DnnOpenCl, PoclRunsTheModelLikeTheCpu) {
  ASSERT_EQ(setenv("OPENCV_OPENCL_DEVICE", ":CPU:", 1), 0);
  ASSERT_EQ(setenv("OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES", "1", 1), 0);
  const emf_dnn_test::Truth truth = emf_dnn_test::loadTruth("yolov8_seg.json");
  const std::string model = "model=" + emf_dnn_test::modelPath("yolov8_seg.onnx");
  DnnDetector cpu(DnnOptions::parse(model + ",target=cpu"));
  DnnDetector ocl(DnnOptions::parse(model + ",target=opencl"));
  EXPECT_EQ(cpu.target(), Target::kCpu);
  ASSERT_EQ(ocl.target(), Target::kOpenCl) << (ocl.warnings().empty() ? "" : ocl.warnings()[0]);
  EXPECT_TRUE(ocl.warnings().empty());

  const cv::Mat color = emf_dnn_test::syntheticColor(truth.frame, 1);
  const cv::Size depth(640, 480);
  const auto a = cpu.detect(color, depth);
  const auto b = ocl.detect(color, depth);
  ASSERT_EQ(a.size(), truth.objects.size());
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].class_id, a[i].class_id);
    EXPECT_EQ(b[i].class_id, truth.objects[i].class_id);
    EXPECT_FLOAT_EQ(b[i].score, a[i].score);
    EXPECT_EQ(b[i].box, a[i].box);
    double max_diff = 0;
    cv::minMaxLoc(cv::abs(b[i].probability - a[i].probability), nullptr, &max_diff);
    EXPECT_LE(max_diff, kOpenClVsCpuProbTolerance);
    EXPECT_GE(emf_dnn_test::maskIou(b[i].mask,
                                    emf_dnn_test::expectedMask(truth, truth.objects[i], depth)),
              kMinMaskIou);
  }
}

}  // namespace
}  // namespace emf_dnn
