// dnn_bench: the `dnn` detector plugin's per-frame cost outside the network, on synthetic
// output tensors shaped like a real YOLOv8-seg export at 640x640 (8400 anchors, 80 classes,
// 32 prototypes of 160x160) and like a Mask R-CNN head (28x28 masks):
//   preprocess: letterbox a 640x480 BGR frame into 640x640 + the NCHW float blob;
//   decode:     recognise the outputs, score threshold, per-class NMS, mask assembly
//               (coefficients x prototypes, bilinear resampling to the depth image, sigmoid,
//               crop) for the instances that survive.
// Prints wall-clock median and p90 and the median CPU time (all threads) in milliseconds.
// Usage: dnn_bench [--instances N] [--runs R] [--depth WxH]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "bench_args.h"
#include "dnn_decode.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Stats {
  double median_ms = 0, p90_ms = 0;  // wall clock
  double cpu_median_ms = 0;          // CPU time of all threads (robust to a loaded machine)
};

double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <typename F>
Stats timeRuns(int runs, F&& f) {
  for (int i = 0; i < 3; ++i) f();  // warm-up (buffers, caches)
  std::vector<double> ms, cpu;
  ms.reserve(static_cast<size_t>(runs));
  cpu.reserve(static_cast<size_t>(runs));
  for (int i = 0; i < runs; ++i) {
    const double c0 = cpuMs();
    const auto t0 = Clock::now();
    f();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
    cpu.push_back(cpuMs() - c0);
  }
  Stats s;
  s.median_ms = median(ms);
  std::sort(ms.begin(), ms.end());
  s.p90_ms = ms[std::min(ms.size() - 1, ms.size() * 9 / 10)];
  s.cpu_median_ms = median(cpu);
  return s;
}

void print(const char* what, const Stats& s) {
  std::printf("%-42s median %7.3f ms  p90 %7.3f ms  (CPU median %7.3f ms)\n", what, s.median_ms,
              s.p90_ms, s.cpu_median_ms);
}

/// YOLOv8-seg-like outputs with `instances` objects (3 overlapping anchors each, as a real
/// model fires several anchors per object) over a 640x480 frame letterboxed to 640x640.
emf_dnn::YoloTensors yoloOutputs(int instances, cv::RNG& rng) {
  constexpr int kClasses = 80, kNm = 32, kAnchors = 8400, kProto = 160;
  cv::Mat pred(std::vector<int>{1, 4 + kClasses + kNm, kAnchors}, CV_32F);
  cv::Mat protos(std::vector<int>{1, kNm, kProto, kProto}, CV_32F);
  rng.fill(protos, cv::RNG::UNIFORM, -2.0, 2.0);
  auto row = [&](int c) { return pred.ptr<float>(0, c); };
  for (int c = 0; c < 4 + kClasses + kNm; ++c) {
    for (int i = 0; i < kAnchors; ++i) {
      row(c)[i] = c < 4              ? rng.uniform(8.f, 600.f)
                  : c < 4 + kClasses ? rng.uniform(0.f, 0.05f)
                                     : rng.uniform(-1.f, 1.f);
    }
  }
  for (int k = 0; k < instances; ++k) {
    // Objects on a grid so that different objects do not suppress each other.
    const float w = rng.uniform(60.f, 140.f), h = rng.uniform(60.f, 120.f);
    const float cx = 70.f + static_cast<float>(k % 5) * 125.f;
    const float cy = 80.f + 70.f + static_cast<float>(k / 5 % 4) * 120.f;
    const int cls = k % kClasses;
    for (int dup = 0; dup < 3; ++dup) {
      const int a = 97 * k + 13 * dup + 1;
      row(0)[a] = cx + 3.f * static_cast<float>(dup);
      row(1)[a] = cy + 2.f * static_cast<float>(dup);
      row(2)[a] = w;
      row(3)[a] = h;
      row(4 + cls)[a] = 0.9f - 0.1f * static_cast<float>(dup);
    }
  }
  return {pred, protos};
}

/// Mask R-CNN-like outputs: `instances` boxes with 28x28 mask logits.
emf_dnn::MaskRcnnTensors maskRcnnOutputs(int instances, cv::RNG& rng) {
  emf_dnn::MaskRcnnTensors t;
  t.boxes = cv::Mat(instances, 4, CV_32F);
  t.labels = cv::Mat(instances, 1, CV_32F);
  t.scores = cv::Mat(instances, 1, CV_32F);
  t.masks = cv::Mat(std::vector<int>{instances, 1, 28, 28}, CV_32F);
  rng.fill(t.masks, cv::RNG::UNIFORM, -4.0, 4.0);
  for (int k = 0; k < instances; ++k) {
    const float x = 10.f + static_cast<float>(k % 5) * 125.f;
    const float y = 90.f + static_cast<float>(k / 5 % 4) * 115.f;
    float* b = t.boxes.ptr<float>(k);
    b[0] = x;
    b[1] = y;
    b[2] = x + rng.uniform(60.f, 110.f);
    b[3] = y + rng.uniform(60.f, 110.f);
    t.labels.at<float>(k) = static_cast<float>(k % 80);
    t.scores.at<float>(k) = 0.5f + 0.02f * static_cast<float>(k % 20);
  }
  return t;
}

}  // namespace

constexpr const char* kUsage =
    "usage: dnn_bench [--instances N (1..20)] [--runs R] [--depth WxH]\n";

int main(int argc, char** argv) {
  int instances = 20, runs = 200;
  cv::Size depth(640, 480);
  const cv::Size frame(640, 480), input(640, 640);
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::printf("%s", kUsage);
        return 0;
      } else if (args.is("--instances")) {
        instances = static_cast<int>(args.integer(1, 20));
      } else if (args.is("--runs")) {
        runs = static_cast<int>(args.integer(1, 1000000));
      } else if (args.is("--depth")) {
        const std::string v = args.value();
        char rest = 0;
        if (std::sscanf(v.c_str(), "%dx%d%c", &depth.width, &depth.height, &rest) != 2 ||
            depth.width < 1 || depth.height < 1 || depth.width > 8192 || depth.height > 8192) {
          throw emf::bench::UsageError("--depth '" + v + "': expected WxH, each in [1, 8192]");
        }
      } else {
        args.unknown();
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "dnn_bench: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  cv::RNG rng(8);
  cv::Mat bgr(frame, CV_8UC3);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  const emf_dnn::Letterbox lb = emf_dnn::computeLetterbox(frame, input);
  const emf_dnn::DecodeParams params;
  const auto yolo = yoloOutputs(instances, rng);
  const auto maskrcnn = maskRcnnOutputs(instances, rng);
  const std::vector<emf_dnn::NamedOutput> yolo_named = {{"output0", yolo.predictions},
                                                        {"output1", yolo.prototypes}};
  const std::vector<emf_dnn::NamedOutput> maskrcnn_named = {{"boxes", maskrcnn.boxes},
                                                            {"labels", maskrcnn.labels},
                                                            {"scores", maskrcnn.scores},
                                                            {"masks", maskrcnn.masks}};

  size_t found_yolo = 0, found_maskrcnn = 0;
  // Like the plugin: the host releases each result after copying it, and its mask buffers go
  // back to the pool for the next frame.
  emf_dnn::MaskPool pool;
  auto recycle = [&](std::vector<emf_dnn::Instance>&& decoded) {
    const size_t n = decoded.size();
    for (auto& inst : decoded) pool.recycle(&inst);
    return n;
  };
  cv::Mat letterboxed, blob;
  const Stats pre = timeRuns(runs, [&] { emf_dnn::makeInputBlob(bgr, lb, &letterboxed, &blob); });
  const Stats dec_yolo = timeRuns(runs, [&] {
    const auto t = emf_dnn::identifyYolo(yolo_named, 80, "bench");
    found_yolo = recycle(emf_dnn::decodeYolo(t, 80, params, lb, depth, &pool));
  });
  const Stats dec_maskrcnn = timeRuns(runs, [&] {
    const auto t = emf_dnn::identifyMaskRcnn(maskrcnn_named);
    found_maskrcnn = recycle(emf_dnn::decodeMaskRcnn(t, 80, params, lb, depth, &pool));
  });
  const Stats total = timeRuns(runs, [&] {
    emf_dnn::makeInputBlob(bgr, lb, &letterboxed, &blob);
    const auto t = emf_dnn::identifyYolo(yolo_named, 80, "bench");
    found_yolo = recycle(emf_dnn::decodeYolo(t, 80, params, lb, depth, &pool));
  });

  std::printf(
      "dnn_bench: frame %dx%d -> input %dx%d, depth %dx%d, %d instances (%d candidates above "
      "the score threshold), YOLO 8400 anchors x 116, prototypes 32x160x160; Mask R-CNN 28x28 "
      "masks; %d runs, OpenCV threads %d\n",
      frame.width, frame.height, input.width, input.height, depth.width, depth.height, instances,
      3 * instances, runs, cv::getNumThreads());
  print("preprocess (letterbox + blob)", pre);
  print("decode yolov8 (threshold, NMS, masks)", dec_yolo);
  print("decode maskrcnn (threshold, NMS, masks)", dec_maskrcnn);
  print("preprocess + decode yolov8 (per frame)", total);
  std::printf("instances decoded: yolov8 %zu, maskrcnn %zu\n", found_yolo, found_maskrcnn);
  if (found_yolo != static_cast<size_t>(instances)) {
    std::fprintf(stderr, "dnn_bench: expected %d yolov8 instances, decoded %zu\n", instances,
                 found_yolo);
    return 1;
  }
  return 0;
}
