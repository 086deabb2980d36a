// detector_share: what a neural detector running asynchronously on the same cores costs the
// SLAM, and what the scheduling settings win back. One generated scene (synth:random, three
// movers, the small `xyz` camera motion) is rendered once; the SLAM then runs on it, paced at
// --rate frames per second, with the scene's exact detections every --every frames, once per
// configuration in one invocation:
//   - no detector (the baseline);
//   - the `dnn` plugin in async mode (its own thread, detector.every_n_frames = --every) on a
//     generated ONNX model with the compute of a small YOLOv8-seg at 640x640
//     (bench/make_detector_model.py; its class scores stay below the threshold, so it returns
//     nothing and the SLAM's objects are the same in every configuration), in emf's process
//     or under detector.isolation: process, with detector.nice and the plugin's threads=.
// Per configuration it prints the SLAM's ms per frame (slam.process plus the hand-over to the
// detector) over all frames and over the frames during which a detection was running (median,
// p90, p99), the detections run and dropped, and the detector's own ms per run.
//
//   detector_share [--frames N] [--size WxH] [--every N] [--rate HZ] [--model FILE] [--out DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "core/frame_source.h"
#include "pipeline/config.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/slam_system.h"
#include "pipeline/stage_timer.h"
#include "sources/open_source.h"

namespace {

using Clock = std::chrono::steady_clock;
using emf::pipeline::DetectorIsolation;
using emf::pipeline::DetectorMode;
using emf::pipeline::ObjectState;
using emf::pipeline::SlamSystem;

struct Setting {
  std::string name;
  bool detector = false;
  DetectorIsolation isolation = DetectorIsolation::kNone;
  int nice = 0;
  int threads = 0;  // the dnn plugin's threads= (0 = OpenCV's default)
};

std::string generateModel(const std::string& out_dir) {
  const std::string path = out_dir + "/detector_share.onnx";
  if (std::filesystem::exists(path)) return path;
  const std::string cmd =
      "/usr/bin/python3 '" EMF_SOURCE_DIR "/bench/make_detector_model.py' '" + path + "'";
  if (std::system(cmd.c_str()) != 0 || !std::filesystem::exists(path)) {
    throw std::runtime_error("cannot generate the model (" + cmd +
                             "): install python3-onnx and python3-numpy, or pass --model FILE");
  }
  return path;
}

}  // namespace

constexpr const char* kUsage =
    "usage: detector_share [--frames N] [--size WxH] [--every N] [--rate HZ] [--model FILE] "
    "[--out DIR]\n";

int main(int argc, char** argv) {
  long frames = 150, width = 640, height = 480, every = 30;
  double rate = 30.0;
  std::string model, out_dir = "detector_share_out";
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (args.is("--frames")) {
        frames = args.integer(30, 100000);
      } else if (args.is("--size")) {
        const std::string v = args.value();
        const size_t x = v.find('x');
        if (x == std::string::npos) {
          throw emf::bench::UsageError("--size '" + v + "': expected WxH");
        }
        width = emf::bench::parseInteger("--size width", v.substr(0, x), 160, 1280);
        height = emf::bench::parseInteger("--size height", v.substr(x + 1), 120, 960);
      } else if (args.is("--every")) {
        every = args.integer(1, 10000);
      } else if (args.is("--rate")) {
        rate = args.real(0.0, 1000.0);
      } else if (args.is("--model")) {
        model = args.value();
      } else if (args.is("--out")) {
        out_dir = args.value();
      } else {
        args.unknown();
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "detector_share: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  try {
    std::filesystem::create_directories(out_dir);
    if (model.empty()) model = generateModel(out_dir);
    emf::Config base;
    emf::cl::Context ctx(base.cl);
    const std::string uri =
        "synth:random?seed=4&movers=3&still=0&camera=xyz&frames=" + std::to_string(frames) +
        "&width=" + std::to_string(width) + "&height=" + std::to_string(height) +
        "&det_every=" + std::to_string(every) +
        "&det_miss=0&det_fp=0&det_confusion=0&det_spill=0&det_partial=0"
        "&det_late=0";
    auto src = emf::sources::openSource(uri, base.source);
    const emf::core::Intrinsics k = src->intrinsics();
    std::vector<emf::core::Frame> scene;
    emf::core::Frame f;
    while (src->next(f)) scene.push_back(f);
    const char* pocl_threads = std::getenv("POCL_MAX_PTHREAD_COUNT");
    std::printf(
        "detector_share: %zu frames of %s\n  paced at %.0f Hz (0 = back to back), a detection "
        "every %ld frames; model %s\n  %u cores; OpenCV threads %d; PoCL threads %s; device %s\n",
        scene.size(), uri.c_str(), rate, every, model.c_str(), std::thread::hardware_concurrency(),
        cv::getNumThreads(), pocl_threads ? pocl_threads : "(PoCL's default)",
        ctx.describe().c_str());

    const std::vector<Setting> settings = {
        {"no detector", false},
        {"in-process", true, DetectorIsolation::kNone, 0, 0},
        {"in-process, nice 10", true, DetectorIsolation::kNone, 10, 0},
        {"in-process, nice 10, threads=1", true, DetectorIsolation::kNone, 10, 1},
        {"process", true, DetectorIsolation::kProcess, 0, 0},
        {"process, nice 10", true, DetectorIsolation::kProcess, 10, 0},
        {"process, nice 19", true, DetectorIsolation::kProcess, 19, 0},
        {"process, nice 10, threads=1", true, DetectorIsolation::kProcess, 10, 1},
    };
    const int cv_threads = cv::getNumThreads();
    std::string summary;  // the machine-readable lines, printed after the table
    std::printf("\n  %-32s | %28s | %28s | %4s %4s %10s | %5s\n", "configuration",
                "SLAM ms, all frames", "SLAM ms, detection running", "runs", "drop", "det ms med",
                "alive");
    std::printf("  %-32s | %8s %9s %9s | %8s %9s %9s |\n", "", "median", "p90", "p99", "median",
                "p90", "p99");
    for (const Setting& s : settings) {
      emf::Config c = base;
      c.validate();
      SlamSystem slam(ctx, c, k, uri);
      std::unique_ptr<emf::pipeline::DetectorScheduler> detector;
      if (s.detector) {
        emf::pipeline::DetectorOptions d;
        d.plugin = "dnn";
        d.plugin_config = "model=" + model + ",layout=yolov8,input=640x640";
        if (s.threads > 0) d.plugin_config += ",threads=" + std::to_string(s.threads);
        d.mode = DetectorMode::kAsync;
        d.every_n_frames = static_cast<int>(every);
        d.isolation = s.isolation;
        d.nice = s.nice;
        detector = std::make_unique<emf::pipeline::DetectorScheduler>(d, uri, k);
      }
      std::vector<double> all, during;
      std::vector<size_t> alive;
      const auto period =
          rate > 0 ? std::chrono::duration<double>(1.0 / rate) : std::chrono::duration<double>(0);
      auto next_frame = Clock::now();
      for (const emf::core::Frame& frame : scene) {
        if (rate > 0) std::this_thread::sleep_until(next_frame);
        next_frame += std::chrono::duration_cast<Clock::duration>(period);
        const bool busy_before = detector && detector->busy();
        const auto t0 = Clock::now();
        const auto out = slam.process(frame, frame.detections ? &*frame.detections : nullptr);
        if (detector) detector->submit(frame, out.T_world_camera);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        const bool busy_after = detector && detector->busy();
        all.push_back(ms);
        // A frame the detector worked through (running when it started and when it ended).
        if (busy_before && busy_after) during.push_back(ms);
        size_t n = 0;
        for (const auto& o : out.objects) {
          n += o.state != ObjectState::kDeleted && o.state != ObjectState::kDormant;
        }
        alive.push_back(n);
      }
      emf::pipeline::DetectorStats stats;
      if (detector) {
        detector->finish();
        stats = detector->stats();
      }
      detector.reset();
      cv::setNumThreads(cv_threads);  // threads= of an in-process plugin is process-wide
      const emf::pipeline::TimingSummary a = emf::pipeline::summarize(all),
                                         d = emf::pipeline::summarize(during);
      std::sort(alive.begin(), alive.end());
      std::printf("  %-32s | %8.2f %9.2f %9.2f |", s.name.c_str(), a.median_ms, a.p90_ms, a.p99_ms);
      if (d.count > 0) {
        std::printf(" %8.2f %9.2f %9.2f |", d.median_ms, d.p90_ms, d.p99_ms);
      } else {
        std::printf(" %28s |", "-");
      }
      std::printf(" %4lld %4lld %10.1f | %5zu\n", static_cast<long long>(stats.runs),
                  static_cast<long long>(stats.dropped_frames), stats.detector_ms_median,
                  alive[alive.size() / 2]);
      char line[512];
      std::snprintf(
          line, sizeof(line),
          "detector_share config=\"%s\" size=%ldx%ld frames=%d slam_ms=%.2f slam_p90_ms=%.2f "
          "slam_p99_ms=%.2f during_frames=%d during_ms=%.2f during_p99_ms=%.2f runs=%lld "
          "detector_ms=%.1f\n",
          s.name.c_str(), width, height, a.count, a.median_ms, a.p90_ms, a.p99_ms, d.count,
          d.median_ms, d.p99_ms, static_cast<long long>(stats.runs), stats.detector_ms_median);
      summary += line;
    }
    std::printf("\n%s", summary.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "detector_share: %s\n", e.what());
    return 1;
  }
  return 0;
}
