// Speed of the synthetic world: per preset, the time to render frames (ray casting), apply the
// depth noise model, simulate detections, and the whole SynthSource::next() per frame; and with
// --write DIR, the time to also write the TUM folder. Prints figures; never a test.
//
// usage: synth_bench [--frames N] [--width W] [--height H] [--threads N] [--write DIR]
//                    [preset ...]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_args.h"
#include "io/tum_writer.h"
#include "synth/depth_noise.h"
#include "synth/detector_sim.h"
#include "synth/parallel.h"
#include "synth/presets.h"
#include "synth/renderer.h"
#include "synth/synth_source.h"

namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}
/// CPU time of the whole process (all threads), seconds: on a shared machine this is the
/// honest figure next to wall time.
double cpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: synth_bench [--frames N] [--width W] [--height H] [--threads N] "
               "[--write DIR] [preset ...]\n");
}

int benchMain(int argc, char** argv) {
  using namespace emf::synth;
  int frames = 600, width = 640, height = 480, threads = 0;
  std::string write_dir;
  std::vector<std::string> presets;
  try {
    emf::bench::ArgWalker args(argc, argv);
    while (args.next()) {
      if (args.is("--help") || args.is("-h")) {
        usage(stdout);
        return 0;
      } else if (args.is("--frames")) {
        frames = static_cast<int>(args.integer(1, 1000000));
      } else if (args.is("--width")) {
        width = static_cast<int>(args.integer(16, 8192));
      } else if (args.is("--height")) {
        height = static_cast<int>(args.integer(16, 8192));
      } else if (args.is("--threads")) {
        threads = static_cast<int>(args.integer(0, 1024));
      } else if (args.is("--write")) {
        write_dir = args.value();
      } else if (args.current().rfind("-", 0) == 0) {
        args.unknown();
      } else {
        presets.push_back(args.current());
      }
    }
    for (const auto& p : presets) {
      const std::vector<std::string> known = presetNames();
      if (std::find(known.begin(), known.end(), p) == known.end()) {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        throw emf::bench::UsageError("unknown preset '" + p + "' (presets: " + list + ")");
      }
    }
  } catch (const emf::bench::UsageError& e) {
    std::fprintf(stderr, "synth_bench: %s\n", e.what());
    usage(stderr);
    return emf::bench::kExitUsage;
  }
  if (presets.empty()) presets = presetNames();
  std::printf("synth_bench: %d frames at %dx%d, threads %d (0 = all %d cores)\n", frames, width,
              height, threads, resolveThreads(0));
  std::printf("components on every 10th frame: wall ms (CPU ms, all threads)\n");
  std::printf("%-10s %16s %16s %16s %16s %14s %10s\n", "preset", "render", "noise", "detect",
              "next()", "all frames", "+ write");
  std::printf("%-10s %16s %16s %16s %16s %14s %10s\n", "", "ms/frame", "ms/frame", "ms/det",
              "ms/frame", "wall s (CPU s)", "wall s");
  for (const auto& preset : presets) {
    SynthOptions o;
    o.preset = preset;
    o.frames = frames;
    o.width = width;
    o.height = height;
    o.threads = threads;
    SynthSource source(o);
    const Scene& scene = source.scene();
    RenderOptions ro;
    ro.width = width;
    ro.height = height;
    ro.threads = threads;
    Renderer renderer(ro);
    DepthNoiseModel noise(o.depth_noise);
    std::map<int, std::string> classes;
    for (const auto& obj : scene.objects) classes[obj.id] = obj.class_name;

    // Components, on every 10th frame.
    double t_render = 0, t_noise = 0, t_detect = 0, c_render = 0, c_noise = 0, c_detect = 0;
    int n_parts = 0, n_det = 0;
    for (int i = 0; i < frames; i += 10, ++n_parts) {
      const double t = scene.timeOf(i);
      std::vector<Eigen::Isometry3d> poses;
      for (const auto& obj : scene.objects) poses.push_back(obj.trajectory.pose(t));
      RenderOutput r;
      const double ca = cpuSeconds();
      const auto a = Clock::now();
      renderer.render(scene, scene.camera.pose(t), poses, &r);
      const auto b = Clock::now();
      const double cb = cpuSeconds();
      cv::Mat noisy;
      noise.apply(r.depth, r.cos_incidence, renderer.intrinsics().fx, 1, i, &noisy,
                  resolveThreads(threads));
      const auto c = Clock::now();
      const double cc = cpuSeconds();
      if (!classes.empty()) {
        simulateDetections(r.instance_ids, classes, 1, i, o.detector);
        ++n_det;
      }
      const auto d = Clock::now();
      const double cd = cpuSeconds();
      c_render += cb - ca;
      c_noise += cc - cb;
      c_detect += cd - cc;
      t_render += seconds(a, b);
      t_noise += seconds(b, c);
      t_detect += seconds(c, d);
    }
    // The whole source.
    emf::core::Frame frame;
    const double c_all0 = cpuSeconds();
    const auto a = Clock::now();
    while (source.next(frame)) {
    }
    const double t_all = seconds(a, Clock::now());
    const double c_all = cpuSeconds() - c_all0;
    double t_write = 0;
    if (!write_dir.empty()) {
      const std::string dir = (std::filesystem::path(write_dir) / preset).string();
      std::filesystem::remove_all(dir);
      SynthSource again(o);
      emf::io::TumWriter writer(dir, again.intrinsics());
      const auto w0 = Clock::now();
      while (again.next(frame)) writer.write(frame);
      writer.finish();
      t_write = seconds(w0, Clock::now());
    }
    auto cell = [](double wall_s, double cpu_s, int n) {
      char text[64];
      std::snprintf(text, sizeof(text), "%.1f (%.1f)", n ? 1000 * wall_s / n : 0.0,
                    n ? 1000 * cpu_s / n : 0.0);
      return std::string(text);
    };
    char all[64], write[64] = "-";
    std::snprintf(all, sizeof(all), "%.1f (%.1f)", t_all, c_all);
    if (!write_dir.empty()) std::snprintf(write, sizeof(write), "%.1f", t_write);
    std::printf("%-10s %16s %16s %16s %16s %14s %10s\n", preset.c_str(),
                cell(t_render, c_render, n_parts).c_str(), cell(t_noise, c_noise, n_parts).c_str(),
                cell(t_detect, c_detect, n_det).c_str(), cell(t_all, c_all, frames).c_str(), all,
                write);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return benchMain(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "synth_bench: %s\n", e.what());
    return 1;
  }
}
