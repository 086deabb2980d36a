// isolation_bench: the latency a detector plugin's process isolation (detector.isolation:
// process) adds per detection frame, against the same plugin in emf's process, in one run.
// The maskfile plugin replays the masks of a synthetic `cars` sequence rendered at the chosen
// size (RGB-D in, two or three full-image float masks out); each frame is detected both ways,
// alternating which goes first, and the per-frame difference is reported.
//
//   isolation_bench [--frames N] [--width W --height H] [--out DIR]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "bench_args.h"
#include "core/frame_source.h"
#include "pipeline/detector_plugin.h"
#include "pipeline/isolated_detector.h"
#include "pipeline/plugin_search_path.h"
#include "pipeline/stage_timer.h"
#include "sources/open_source.h"

namespace {

using Clock = std::chrono::steady_clock;

}  // namespace

constexpr const char* kUsage =
    "usage: isolation_bench [--frames N] [--width W] [--height H] [--out DIR]\n";

int main(int argc, char** argv) {
  int frames = 60, width = 640, height = 480;
  std::string out = "out/isolation_bench";
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        std::fputs(kUsage, stdout);
        return 0;
      } else if (args.is("--frames")) {
        frames = static_cast<int>(args.integer(2, 100000));
      } else if (args.is("--width")) {
        width = static_cast<int>(args.integer(64, 4096));
      } else if (args.is("--height")) {
        height = static_cast<int>(args.integer(48, 4096));
      } else if (args.is("--out")) {
        out = args.value();
      } else {
        args.unknown();
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "isolation_bench: %s\n%s", e.what(), kUsage);
    return emf::bench::kExitUsage;
  }
  try {
    const std::string data = out + "/cars";
    std::filesystem::remove_all(data);
    const std::string synth = std::string(EMF_CLI_PATH) + " synth cars --frames " +
                              std::to_string(frames) + " --width " + std::to_string(width) +
                              " --height " + std::to_string(height) + " --det-every 1 --out " +
                              data + " >/dev/null 2>&1";
    if (std::system(synth.c_str()) != 0) {
      std::fprintf(stderr, "isolation_bench: '%s' failed\n", synth.c_str());
      return 1;
    }
    emf::core::SourceOptions so;
    auto src = emf::sources::openSource("tum:" + data, so);
    const emf::core::Intrinsics k = src->intrinsics();
    const std::string plugin =
        emf::pipeline::resolvePluginPath("maskfile", emf::pipeline::modulePluginFolders());
    auto in_process = emf::pipeline::DetectorPlugin::load(plugin, {}, "dir=" + data, "", k);
    emf::pipeline::IsolatedDetector isolated(emf::pipeline::detectorHostPath(), plugin,
                                             "dir=" + data, "", k, 30.0, 60.0);
    std::vector<double> a_ms, b_ms, diff_ms;
    size_t detections = 0;
    emf::core::Frame f;
    for (int i = 0; src->next(f); ++i) {
      double t[2];
      for (int j = 0; j < 2; ++j) {
        const bool isolated_turn = (i + j) % 2 == 1;  // alternate the order
        const auto t0 = Clock::now();
        const emf::pipeline::DetectorOutput o =
            isolated_turn ? isolated.detect(f) : in_process->detect(f);
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!o.error.empty()) throw std::runtime_error(o.error);
        t[isolated_turn ? 1 : 0] = ms;
        if (isolated_turn) detections += o.detections.size();
      }
      if (i == 0) continue;  // the first call of each warms caches and maps the segment
      a_ms.push_back(t[0]);
      b_ms.push_back(t[1]);
      diff_ms.push_back(t[1] - t[0]);
    }
    std::printf("isolation_bench: %dx%d RGB-D, maskfile plugin, %zu frames, %.1f masks/frame\n",
                width, height, a_ms.size(),
                static_cast<double>(detections) / static_cast<double>(a_ms.size() + 1));
    std::printf("  %-12s %8s %8s\n", "", "median", "p90");
    const auto a = emf::pipeline::summarize(a_ms), b = emf::pipeline::summarize(b_ms),
               d = emf::pipeline::summarize(diff_ms);
    std::printf("  %-12s %6.2f ms %6.2f ms\n", "in-process", a.median_ms, a.p90_ms);
    std::printf("  %-12s %6.2f ms %6.2f ms\n", "process", b.median_ms, b.p90_ms);
    std::printf("  %-12s %6.2f ms %6.2f ms  (per frame, process - in-process)\n", "added",
                d.median_ms, d.p90_ms);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isolation_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
