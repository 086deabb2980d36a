#include "dnn_detector.h"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/core/ocl.hpp>

namespace emf_dnn {
namespace {

/// OpenCV's message without its file/line decoration, on one line, not too long for the ABI's
/// error buffer.
std::string cvMessage(const cv::Exception& e) {
  std::string s = e.err.empty() ? std::string(e.what()) : e.err;
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  constexpr size_t kMaxChars = 300;
  if (s.size() > kMaxChars) s = s.substr(0, kMaxChars) + "...";
  return s;
}

bool envTrue(const char* name) {
  const char* v = std::getenv(name);
  if (!v) return false;
  std::string s(v);
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s == "1" || s == "true" || s == "on" || s == "yes";
}

std::string trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

}  // namespace

std::vector<std::string> readClassNames(const std::string& path) {
  std::ifstream in(path);
  if (!isReadableFile(path) || !in) {
    throw DnnError(EMF_ERROR_IO, "dnn: cannot read the class names file '" + path +
                                     "' (classes=): give a text file with one name per line");
  }
  std::vector<std::string> names;
  std::string line;
  while (std::getline(in, line)) names.push_back(trim(line));
  while (!names.empty() && names.back().empty()) names.pop_back();
  if (names.empty()) {
    throw DnnError(EMF_ERROR_CONFIG, "dnn: the class names file '" + path + "' has no names");
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty()) {
      throw DnnError(EMF_ERROR_CONFIG, "dnn: " + path + ":" + std::to_string(i + 1) +
                                           ": empty class name (one name per line, in the "
                                           "model's class order)");
    }
  }
  return names;
}

Target chooseTarget(Target requested, bool have_opencl, bool device_is_gpu, bool allow_all,
                    const std::string& device_name, std::string* warning) {
  warning->clear();
  if (requested == Target::kCpu) return Target::kCpu;
  if (!have_opencl) {
    *warning =
        "dnn: target=opencl: OpenCV finds no usable OpenCL device (it picks one by "
        "OPENCV_OPENCL_DEVICE, e.g. ':GPU:', or ':CPU:' for PoCL); running the network on the CPU";
    return Target::kCpu;
  }
  if (!device_is_gpu && !allow_all) {
    *warning = "dnn: target=opencl: OpenCV's DNN runs OpenCL on GPUs only and '" + device_name +
               "' is not a GPU (set OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES=1 to use it anyway); "
               "running the network on the CPU";
    return Target::kCpu;
  }
  return Target::kOpenCl;
}

DnnDetector::DnnDetector(const DnnOptions& options) : options_(options) {
  names_ = readClassNames(options_.classes_path);
  const std::string& model = options_.model_path;
  if (!isReadableFile(model)) {
    throw DnnError(EMF_ERROR_IO, "dnn: model file '" + model +
                                     "' does not exist or is unreadable (set model= to an "
                                     "exported .onnx file)");
  }
  try {
    net_ = cv::dnn::readNetFromONNX(model);
  } catch (const cv::Exception& e) {
    throw DnnError(EMF_ERROR_IO, "dnn: '" + model + "' is not an ONNX model OpenCV can read (" +
                                     cvMessage(e) +
                                     "): export the model to ONNX (e.g. opset 12) and pass the "
                                     ".onnx file as model=");
  }
  if (net_.empty()) {
    throw DnnError(EMF_ERROR_IO, "dnn: '" + model + "' holds no network (export it to ONNX)");
  }
  output_names_ = net_.getUnconnectedOutLayersNames();

  std::string warning;
  if (options_.target == Target::kOpenCl) {
    const bool have = cv::ocl::haveOpenCL() && cv::ocl::useOpenCL();
    const cv::ocl::Device& device = cv::ocl::Device::getDefault();
    const bool gpu = have && (device.type() & cv::ocl::Device::TYPE_GPU) != 0;
    target_ =
        chooseTarget(options_.target, have, gpu, envTrue("OPENCV_DNN_OPENCL_ALLOW_ALL_DEVICES"),
                     have ? device.name() : std::string(), &warning);
  } else {
    target_ = Target::kCpu;
  }
  if (!warning.empty()) warn(warning);
  if (options_.threads > 0) cv::setNumThreads(options_.threads);
  net_.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  net_.setPreferableTarget(target_ == Target::kOpenCl ? cv::dnn::DNN_TARGET_OPENCL
                                                      : cv::dnn::DNN_TARGET_CPU);

  // One pass on a blank (padding-grey) input: a model that rejects the input size, or whose
  // outputs match no layout, fails here, at load time, rather than on the first frame.
  const int w = options_.input_width_px, h = options_.input_height_px;
  const cv::Mat blank(std::vector<int>{1, 3, h, w}, CV_32F, cv::Scalar(kLetterboxPad / 255.0));
  const std::string failed = "dnn: model '" + model + "' failed its first forward pass on a 1x3x" +
                             std::to_string(h) + "x" + std::to_string(w) +
                             " input (input=" + std::to_string(w) + "x" + std::to_string(h) + "): ";
  const std::string hint =
      ". Either the model was exported for another input size (set input=WxH to it), or it "
      "has operations this OpenCV cannot run (YOLOv8/YOLO11 exports on OpenCV 4.6: convert the "
      "model with scripts/onnx_for_opencv.py)";
  std::vector<NamedOutput> outputs;
  try {
    outputs = forward(blank);
  } catch (const cv::Exception& e) {
    if (target_ != Target::kOpenCl) throw DnnError(EMF_ERROR_CONFIG, failed + cvMessage(e) + hint);
    warn("dnn: target=opencl: OpenCV's OpenCL forward pass failed (" + cvMessage(e) +
         "); running the network on the CPU");
    target_ = Target::kCpu;
    net_.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    try {
      outputs = forward(blank);
    } catch (const cv::Exception& e2) {
      throw DnnError(EMF_ERROR_CONFIG, failed + cvMessage(e2) + hint);
    }
  }
  checkOutputs(outputs);
}

void DnnDetector::warn(const std::string& message) {
  warnings_.push_back(message);
  std::fprintf(stderr, "warning: %s\n", message.c_str());
}

std::vector<NamedOutput> DnnDetector::forward(const cv::Mat& blob) {
  net_.setInput(blob);
  net_.forward(output_blobs_, output_names_);
  std::vector<NamedOutput> outputs(output_blobs_.size());
  for (size_t i = 0; i < outputs.size(); ++i) {
    outputs[i].name = i < output_names_.size() ? output_names_[i] : std::to_string(i);
    outputs[i].value = output_blobs_[i];
  }
  return outputs;
}

void DnnDetector::checkOutputs(const std::vector<NamedOutput>& outputs) const {
  try {
    if (options_.layout == Layout::kYoloV8) {
      identifyYolo(outputs, static_cast<int>(names_.size()), "'" + options_.classes_path + "'");
    } else {
      identifyMaskRcnn(outputs);
    }
  } catch (const DnnError& e) {
    throw DnnError(e.status(), "dnn: model '" + options_.model_path + "': " + e.what());
  }
}

std::vector<Instance> DnnDetector::detect(const cv::Mat& bgr, cv::Size depth_size) {
  const Letterbox lb =
      computeLetterbox(bgr.size(), cv::Size(options_.input_width_px, options_.input_height_px));
  makeInputBlob(bgr, lb, &letterboxed_, &blob_);
  const std::vector<NamedOutput> outputs = forward(blob_);
  DecodeParams p;
  p.score_threshold = options_.score_threshold;
  p.nms_iou = options_.nms_iou;
  p.mask_threshold = options_.mask_threshold;
  p.max_detections = options_.max_detections;
  p.mask_logits = options_.mask_logits;
  const int nc = static_cast<int>(names_.size());
  try {
    if (options_.layout == Layout::kYoloV8) {
      return decodeYolo(identifyYolo(outputs, nc, "'" + options_.classes_path + "'"), nc, p, lb,
                        depth_size, &mask_pool_);
    }
    return decodeMaskRcnn(identifyMaskRcnn(outputs), nc, p, lb, depth_size, &mask_pool_);
  } catch (const DnnError& e) {
    throw DnnError(e.status(), "dnn: model '" + options_.model_path + "': " + e.what());
  }
}

void DnnDetector::recycle(std::vector<Instance>* instances) {
  for (Instance& inst : *instances) mask_pool_.recycle(&inst);
  instances->clear();
}

}  // namespace emf_dnn
