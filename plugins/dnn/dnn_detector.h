// The `dnn` detector: an ONNX instance-segmentation model run by OpenCV's DNN module, with the
// decoding of dnn_decode.h. One instance per plugin instance; not thread-safe (the ABI calls
// one detector from one thread at a time).
#pragma once

#include <opencv2/dnn.hpp>
#include <string>
#include <vector>

#include "dnn_decode.h"
#include "dnn_options.h"

namespace emf_dnn {

/// Reads class names, one per line (trailing blank lines and '\r' ignored). Throws DnnError
/// (EMF_ERROR_IO / EMF_ERROR_CONFIG) naming the file and line.
std::vector<std::string> readClassNames(const std::string& path);

/// Which compute target to use for a requested one, given what OpenCV offers. OpenCV's DNN
/// runs OpenCL only on GPU devices unless OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES is set; anything
/// else falls back to the CPU with *warning set (empty when the request is honoured).
Target chooseTarget(Target requested, bool have_opencl, bool device_is_gpu, bool allow_all,
                    const std::string& device_name, std::string* warning);

class DnnDetector {
 public:
  /// Loads the model and the class names, picks the target, runs one forward pass on a blank
  /// input and checks the outputs against the layout. Throws DnnError with a message naming the
  /// model file and what to change.
  explicit DnnDetector(const DnnOptions& options);

  /// Instances in a BGR colour image (CV_8UC3, registered to depth), masks and boxes in
  /// `depth_size` pixels. Throws DnnError or cv::Exception.
  std::vector<Instance> detect(const cv::Mat& bgr, cv::Size depth_size);

  /// Hands the mask buffers of instances the caller is done with back for the next frames.
  void recycle(std::vector<Instance>* instances);

  const std::vector<std::string>& classNames() const { return names_; }
  /// The target actually used (may be kCpu after an OpenCL fallback).
  Target target() const { return target_; }
  /// Warnings from loading (e.g. an OpenCL fallback), also printed to stderr.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  std::vector<NamedOutput> forward(const cv::Mat& blob);
  void checkOutputs(const std::vector<NamedOutput>& outputs) const;
  void warn(const std::string& message);

  DnnOptions options_;
  std::vector<std::string> names_;
  cv::dnn::Net net_;
  std::vector<std::string> output_names_;
  Target target_ = Target::kCpu;
  std::vector<std::string> warnings_;
  cv::Mat letterboxed_, blob_;         // reused per frame
  std::vector<cv::Mat> output_blobs_;  // reused per frame
  MaskPool mask_pool_;
};

}  // namespace emf_dnn
