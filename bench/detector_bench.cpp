// detector_bench: what detector scheduling and the per-object outputs cost the SLAM thread.
//   1. async DetectorScheduler::submit() (frame copied into the slot, or dropped) with a
//      stand-in detector that takes --detector-ms, the SLAM thread spending --slam-ms per frame:
//      submit() time per call, frames handed over / dropped, results and how late they come
//   2. ObjectOutputs per frame at 3 objects: add(), writeFrameImages() (overlay + q_0..q_3 PNGs),
//      (which appends and flushes the trajectories) and syncing them to disk at the end
// Usage: detector_bench [--frames N] [--detector-ms MS] [--slam-ms MS] [--out DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "bench_args.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/object_outputs.h"

namespace {

using Clock = std::chrono::steady_clock;
using emf::pipeline::DetectionBatch;
using emf::pipeline::DetectorOptions;
using emf::pipeline::DetectorOutput;
using emf::pipeline::DetectorScheduler;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Figures {
  double median = 0, p99 = 0, max = 0;
};

Figures figures(std::vector<double> v) {
  Figures f;
  if (v.empty()) return f;
  std::sort(v.begin(), v.end());
  f.median = v[v.size() / 2];
  f.p99 = v[std::min(v.size() - 1, v.size() * 99 / 100)];
  f.max = v.back();
  return f;
}

emf::core::Intrinsics camera(int w, int h) {
  emf::core::Intrinsics k;
  k.width = w;
  k.height = h;
  k.fx = k.fy = 525.0 * w / 640.0;
  k.cx = (w - 1) / 2.0;
  k.cy = (h - 1) / 2.0;
  return k;
}

emf::core::Frame frame(int64_t index, int w, int h) {
  emf::core::Frame f;
  f.index = index;
  f.timestamp = static_cast<double>(index) / 30.0;
  f.timestamp_text = std::to_string(f.timestamp);
  f.depth = cv::Mat(h, w, CV_32F, cv::Scalar(1.5f));
  f.color = cv::Mat(h, w, CV_8UC3, cv::Scalar(50, 100, 150));
  return f;
}

void asyncSubmit(int w, int h, int frames, double detector_ms, double slam_ms) {
  DetectorOptions o;
  o.mode = emf::pipeline::DetectorMode::kAsync;
  o.every_n_frames = 1;
  const auto sleep_ms = [](double ms) {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(ms));
  };
  DetectorScheduler s(
      o, "standin",
      [&](const emf::core::Frame& f, const cv::Mat*, const cv::Mat*) {
        sleep_ms(detector_ms);
        DetectorOutput out;
        emf::core::Detection d;
        d.id = 1;
        d.class_name = "car";
        d.score = 0.9f;
        d.box = cv::Rect(0, 0, 10, 10);
        d.mask = cv::Mat(f.depth.size(), CV_32F, cv::Scalar(0.f));
        out.detections.push_back(d);
        return out;
      },
      camera(w, h));
  const cv::Mat q0(h, w, CV_32F, cv::Scalar(0.5f));
  std::vector<emf::pipeline::ObjectPose> objects(3);
  std::vector<double> handover_us, dropped_us, late;
  for (int i = 0; i < frames; ++i) {
    const emf::core::Frame f = frame(i, w, h);
    const int64_t dropped_before = s.stats().dropped_frames;
    const auto t0 = Clock::now();
    const auto b = s.submit(f, Eigen::Isometry3d::Identity(), &q0, nullptr, &objects);
    const double us = 1000.0 * msSince(t0);
    (s.stats().dropped_frames > dropped_before ? dropped_us : handover_us).push_back(us);
    if (b) late.push_back(static_cast<double>(b->frames_late));
    sleep_ms(slam_ms);
  }
  s.finish();
  const emf::pipeline::DetectorStats st = s.stats();
  const Figures hu = figures(handover_us), du = figures(dropped_us), lf = figures(late);
  std::printf(
      "async %dx%d  detector %.0f ms, SLAM %.0f ms/frame, %d frames: submit() with hand-over "
      "(copies depth, colour, q_0) %.0f us median, %.0f us p99; dropped %.1f us median; runs "
      "%lld, dropped %lld, results %lld, %.0f frames late (median), detector %.1f ms median\n",
      w, h, detector_ms, slam_ms, frames, hu.median, hu.p99, du.median,
      static_cast<long long>(st.runs), static_cast<long long>(st.dropped_frames),
      static_cast<long long>(st.results_delivered), lf.median, st.detector_ms_median);
}

void outputs(int w, int h, int frames, const std::string& dir) {
  emf::pipeline::ObjectOutputs out(dir, true);
  const emf::core::Frame f = frame(0, w, h);
  cv::Mat ids(h, w, CV_32S, cv::Scalar(0));
  std::vector<emf::pipeline::AssociationImage> q;
  q.push_back({0, cv::Mat(h, w, CV_32F, cv::Scalar(0.7f))});
  for (int id = 1; id <= 3; ++id) {
    const cv::Rect r(w * id / 5, h / 3, w / 6, h / 3);
    ids(r).setTo(id);
    cv::Mat qi(h, w, CV_32F, cv::Scalar(0.f));
    qi(r).setTo(0.9f);
    q.push_back({id, qi});
  }
  std::vector<double> add_us, image_ms;
  for (int i = 0; i < frames; ++i) {
    emf::pipeline::FrameOutcome o;
    o.index = i;
    o.timestamp = static_cast<double>(i) / 30.0;
    for (int id = 1; id <= 3; ++id) {
      emf::pipeline::ObjectOutcome obj;
      obj.id = id;
      obj.class_name = "car";
      obj.T_object_camera.translation() = Eigen::Vector3d(0.01 * i, 0.0, 1.0);
      o.objects.push_back(obj);
    }
    auto t0 = Clock::now();
    out.add(o);
    add_us.push_back(1000.0 * msSince(t0));
    t0 = Clock::now();
    out.writeFrameImages(o, f.color, ids, q);
    image_ms.push_back(msSince(t0));
  }
  const auto t0 = Clock::now();
  out.sync();
  const double traj_ms = msSince(t0);
  const Figures a = figures(add_us), im = figures(image_ms);
  std::printf(
      "outputs %dx%d, 3 objects, %d frames: add() %.2f us median; images (overlay + 4 q maps) "
      "%.1f ms median, %.1f ms p99; 3 trajectories synced to disk in %.1f ms\n",
      w, h, frames, a.median, im.median, im.p99, traj_ms);
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: detector_bench [--frames N] [--detector-ms MS] [--slam-ms MS] "
               "[--out DIR]\n");
}

}  // namespace

int main(int argc, char** argv) {
  int frames = 300;
  double detector_ms = 100, slam_ms = 30;
  std::string dir = "/tmp/emf-detector-bench";
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        usage(stdout);
        return 0;
      } else if (args.is("--frames")) {
        frames = static_cast<int>(args.integer(1, 1000000));
      } else if (args.is("--detector-ms")) {
        detector_ms = args.real(0.0, 60000.0);
      } else if (args.is("--slam-ms")) {
        slam_ms = args.real(0.0, 60000.0);
      } else if (args.is("--out")) {
        dir = args.value();
      } else {
        args.unknown();
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "detector_bench: %s\n", e.what());
    usage(stderr);
    return emf::bench::kExitUsage;
  }
  try {
    for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
      asyncSubmit(w, h, frames, detector_ms, slam_ms);
    }
    for (const auto& [w, h] : {std::pair{320, 240}, std::pair{640, 480}}) {
      outputs(w, h, std::min(frames, 60), dir + "/" + std::to_string(w));
    }
    std::filesystem::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "detector_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
