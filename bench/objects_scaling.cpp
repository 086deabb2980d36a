// objects_scaling: what each object alive costs per frame. One generated scene with up to eight
// detected objects (synth:random, 4 movers and 4 still, the small `xyz` camera motion, a perfect
// detector every 30 frames as detector.every_n_frames, or every --det-every; seed 16 keeps all
// eight alive on every measured frame) is rendered once per image size; the SLAM then runs on the
// same frames with objects.max_objects = 0, 1, 2, 4, 8 in one invocation (the 0-object run is the
// baseline). For the frames from --warmup on where exactly that many objects are alive it prints
// the ms per frame (median, p90) and per stage, and the counts that do not depend on the
// machine's load: kernel launches, blocking host waits, bytes read back and the objects' tracking
// steps (Levenberg-Marquardt evaluations of all objects) per frame. Last, the marginal cost of
// one more object (least-squares slope over the counts that were reached). --kernels adds, per
// count, the device time and launches per measured frame of each kernel (OpenCL profiling
// events, cl/kernel_profile.h): where the time goes on the device the bench runs on, a GPU
// included. --set S.K=V (repeatable) changes a default for every run (e.g. cl.lanes=8).
//
//   objects_scaling [--frames N] [--seed S] [--sizes 320,640] [--counts 0,1,2,4,8]
//                   [--warmup F] [--det-every N] [--kernels] [--set S.K=V]..
// A detection frame also ray-casts every object and the background at full size to match the
// masks: --det-every 10 weighs that more on the p90 and on the kernel table's means.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <sstream>
#include <vector>

#include "bench_args.h"
#include "cl/context.h"
#include "cl/kernel_profile.h"
#include "core/frame_source.h"
#include "pipeline/config.h"
#include "pipeline/slam_system.h"
#include "pipeline/stage_timer.h"
#include "sources/open_source.h"

namespace {

using emf::pipeline::ObjectState;
using emf::pipeline::SlamSystem;

std::vector<long> parseList(const std::string& option, const std::string& text, long lo, long hi) {
  std::vector<long> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(emf::bench::parseInteger(option, item, lo, hi));
  if (out.empty()) throw emf::bench::UsageError(option + ": empty list");
  return out;
}

double median(const std::vector<double>& v) { return emf::pipeline::summarize(v).median_ms; }

struct Row {
  long objects = 0;
  size_t frames = 0;  // measured frames (exactly `objects` alive)
  double ms_median = 0, ms_p90 = 0;
  std::map<std::string, double> stage_median;
  double launches = 0, waits = 0, mb_read = 0;         // medians per frame
  double track_iterations = 0;                         // object tracking LM steps, median per frame
  std::map<std::string, emf::cl::KernelTime> kernels;  // --kernels: sums over the measured frames
};

// --kernels: per kernel, device ms and launches per measured frame at each count, the kernels
// with the most time at the largest count first.
void printKernels(const std::vector<Row>& rows) {
  const Row* last = nullptr;
  for (const Row& r : rows) {
    if (r.frames > 0) last = &r;
  }
  if (!last) return;
  std::vector<std::pair<double, std::string>> order;
  std::map<std::string, bool> seen;
  for (const Row& r : rows) {
    for (const auto& [name, t] : r.kernels) {
      if (seen[name]) continue;
      seen[name] = true;
      const auto it = last->kernels.find(name);
      order.push_back({it == last->kernels.end() ? 0.0 : -it->second.device_ms, name});
    }
  }
  std::sort(order.begin(), order.end());
  std::printf("   device ms per frame (launches per frame) of each kernel, by objects alive:\n");
  std::printf("   %-28s", "kernel");
  for (const Row& r : rows) {
    if (r.frames > 0) std::printf(" %15ld", r.objects);
  }
  std::printf("\n");
  std::vector<double> total(rows.size(), 0.0);
  for (const auto& [unused, name] : order) {
    std::printf("   %-28.28s", name.c_str());
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      if (r.frames == 0) continue;
      const auto it = r.kernels.find(name);
      const double n = static_cast<double>(r.frames);
      const double ms = it == r.kernels.end() ? 0.0 : it->second.device_ms / n;
      const double launches =
          it == r.kernels.end() ? 0.0 : static_cast<double>(it->second.launches) / n;
      total[i] += ms;
      std::printf(" %7.3f (%5.1f)", ms, launches);
    }
    std::printf("\n");
  }
  std::printf("   %-28s", "all kernels");
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].frames > 0) std::printf(" %7.3f        ", total[i]);
  }
  std::printf("\n");
}

}  // namespace

constexpr const char* kUsage =
    "usage: objects_scaling [--frames N] [--seed S] [--sizes 320,640] [--counts 0,1,2,4,8] "
    "[--warmup F] [--det-every N] [--kernels] [--set S.K=V]..\n";

int main(int argc, char** argv) {
  long frames = 150, seed = 16, warmup = 70, det_every = 30;
  bool kernels = false;
  std::vector<std::string> sets;  // section.key=value overrides of the defaults
  std::vector<long> sizes = {320, 640}, counts = {0, 1, 2, 4, 8};
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (args.is("--frames")) {
        frames = args.integer(20, 100000);
      } else if (args.is("--seed")) {
        seed = args.integer(1, 1000000);
      } else if (args.is("--warmup")) {
        warmup = args.integer(0, 100000);
      } else if (args.is("--sizes")) {
        sizes = parseList("--sizes", args.value(), 160, 1280);
      } else if (args.is("--counts")) {
        counts = parseList("--counts", args.value(), 0, 8);
      } else if (args.is("--det-every")) {
        det_every = args.integer(1, 100000);
      } else if (args.is("--kernels")) {
        kernels = true;
      } else if (args.is("--set")) {
        sets.push_back(args.value());
      } else {
        args.unknown();
      }
    }
    if (warmup >= frames) throw emf::bench::UsageError("--warmup must be below --frames");
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "objects_scaling: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  try {
    emf::Config base;
    for (const std::string& assignment : sets) base.set(assignment);
    base.validate();
    emf::cl::setKernelProfiling(kernels);  // before the Context: its queue takes the property
    emf::cl::Context ctx(base.cl);
    for (const long width : sizes) {
      const long height = width * 3 / 4;
      const std::string uri =
          "synth:random?seed=" + std::to_string(seed) +
          "&movers=4&still=4&camera=xyz&frames=" + std::to_string(frames) +
          "&width=" + std::to_string(width) + "&height=" + std::to_string(height) +
          "&det_every=" + std::to_string(det_every) +
          "&det_miss=0&det_fp=0&det_confusion=0&det_spill=0&det_partial=0&det_late=0";
      auto src = emf::sources::openSource(uri, base.source);
      const emf::core::Intrinsics k = src->intrinsics();
      std::vector<emf::core::Frame> scene;
      emf::core::Frame f;
      while (src->next(f)) scene.push_back(f);
      std::printf(
          "\n== %ldx%ld, %zu frames of %s\n   measured from frame %ld, on frames with "
          "exactly N objects alive; device %s\n",
          width, height, scene.size(), uri.c_str(), warmup, ctx.describe().c_str());
      std::vector<Row> rows;
      for (const long n : counts) {
        emf::Config c = base;
        c.objects.max_objects = static_cast<int>(n);
        c.validate();
        SlamSystem slam(ctx, c, k, uri);
        std::vector<double> ms;
        std::vector<size_t> alive_at;
        std::vector<std::map<std::string, emf::cl::KernelTime>> kernel_at;
        emf::cl::takeKernelProfile();  // the set-up's launches are no frame's
        for (const emf::core::Frame& frame : scene) {
          const auto t0 = std::chrono::steady_clock::now();
          const auto out = slam.process(frame, frame.detections ? &*frame.detections : nullptr);
          ms.push_back(
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                  .count());
          size_t alive = 0;
          for (const auto& o : out.objects) {
            alive += o.state != ObjectState::kDeleted && o.state != ObjectState::kDormant;
          }
          alive_at.push_back(alive);
          if (kernels) kernel_at.push_back(emf::cl::takeKernelProfile());
        }
        Row r;
        r.objects = n;
        std::vector<size_t> use;
        for (size_t i = static_cast<size_t>(warmup); i < ms.size(); ++i) {
          if (alive_at[i] == static_cast<size_t>(n)) use.push_back(i);
        }
        r.frames = use.size();
        const auto pick = [&](const std::vector<double>& all) {
          std::vector<double> v;
          for (size_t i : use) v.push_back(all[i]);
          return v;
        };
        const emf::pipeline::TimingSummary t = emf::pipeline::summarize(pick(ms));
        r.ms_median = t.median_ms;
        r.ms_p90 = t.p90_ms;
        for (const auto& stage : SlamSystem::stageNames()) {
          r.stage_median[stage] = median(pick(slam.timer().samples(stage)));
        }
        r.launches = median(pick(slam.counters().samples("kernel_launches")));
        r.waits = median(pick(slam.counters().samples("host_waits")));
        r.mb_read = median(pick(slam.counters().samples("bytes_read"))) / (1 << 20);
        r.track_iterations = median(pick(slam.counters().samples("object_track_iterations")));
        for (size_t i : kernels ? use : std::vector<size_t>{}) {
          for (const auto& [name, kt] : kernel_at[i]) {
            r.kernels[name].launches += kt.launches;
            r.kernels[name].device_ms += kt.device_ms;
          }
        }
        rows.push_back(r);
      }
      std::printf("   %-7s %6s %9s %7s |", "objects", "frames", "ms median", "p90");
      for (const auto& stage : SlamSystem::stageNames()) std::printf(" %9.9s", stage.c_str());
      std::printf(" | %8s %6s %7s %8s\n", "launches", "waits", "MB read", "LM steps");
      for (const Row& r : rows) {
        if (r.frames == 0) {
          std::printf("   %-7ld %6s  (never exactly %ld alive after the warm-up)\n", r.objects, "0",
                      r.objects);
          continue;
        }
        std::printf("   %-7ld %6zu %9.2f %7.2f |", r.objects, r.frames, r.ms_median, r.ms_p90);
        for (const auto& stage : SlamSystem::stageNames()) {
          std::printf(" %9.2f", r.stage_median.at(stage));
        }
        std::printf(" | %8.0f %6.0f %7.2f %8.0f\n", r.launches, r.waits, r.mb_read,
                    r.track_iterations);
      }
      if (kernels) printKernels(rows);
      // Least-squares slope over the rows that were measured.
      double sx = 0, sy = 0, sxx = 0, sxy = 0, sl = 0, slx = 0, sw = 0, swx = 0;
      int m = 0;
      for (const Row& r : rows) {
        if (r.frames == 0) continue;
        const double x = static_cast<double>(r.objects);
        sx += x;
        sxx += x * x;
        sy += r.ms_median;
        sxy += x * r.ms_median;
        sl += r.launches;
        slx += x * r.launches;
        sw += r.waits;
        swx += x * r.waits;
        ++m;
      }
      const double den = m * sxx - sx * sx;
      if (m >= 2 && den > 0) {
        std::printf(
            "   per object alive: %+.2f ms per frame, %+.1f kernel launches, %+.1f host "
            "waits (least squares over %d counts)\n",
            (m * sxy - sx * sy) / den, (m * slx - sx * sl) / den, (m * swx - sx * sw) / den, m);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "objects_scaling: %s\n", e.what());
    return 1;
  }
  return 0;
}
