// Throughput of the dataset readers, the KLG writer/reader and the evaluator. Prints figures;
// never asserts on time. Usage: bench_io [data_dir] (default ../shared/data beside the repo).
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/frame_source.h"
#include "eval/eval.h"
#include "io/klg.h"
#include "sources/open_source.h"

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const std::string data = argc > 1 ? argv[1] : std::string(EMF_SOURCE_DIR) + "/../shared/data";
  try {
    // 1. TUM folder reading (PNG depth + JPEG colour decode, conversion to metres).
    std::vector<emf::core::Frame> frames;
    {
      auto t0 = std::chrono::steady_clock::now();
      auto src = emf::sources::openSource("tum:" + data + "/redkitchen-0-299?depth_scale=1000",
                                          emf::core::SourceOptions{});
      const double open_s = secondsSince(t0);
      t0 = std::chrono::steady_clock::now();
      emf::core::Frame f;
      while (src->next(f)) frames.push_back(f);
      const double read_s = secondsSince(t0);
      std::printf(
          "tum read   redkitchen-0-299: %zu frames 640x480, open %.1f ms, %.2f ms/frame "
          "(%.1f frames/s)\n",
          frames.size(), open_s * 1e3, read_s * 1e3 / frames.size(), frames.size() / read_s);
    }
    // 2. KLG write (zlib level 1 + JPEG q90) and read back.
    const fs::path tmp = fs::temp_directory_path() / "emf-bench-io.klg";
    {
      auto t0 = std::chrono::steady_clock::now();
      emf::io::KlgWriter w(tmp.string());
      for (const auto& f : frames) w.write(f);
      w.close();
      const double write_s = secondsSince(t0);
      const double mb = static_cast<double>(fs::file_size(tmp)) / 1e6;
      const double raw_mb = frames.size() * 640.0 * 480 * 5 / 1e6;  // uint16 depth + RGB
      std::printf("klg write  %zu frames: %.2f ms/frame, %.1f MB (%.1f%% of raw depth+rgb)\n",
                  frames.size(), write_s * 1e3 / frames.size(), mb, 100 * mb / raw_mb);
      t0 = std::chrono::steady_clock::now();
      auto src = emf::sources::openSource("klg:" + tmp.string() + "?fx=585&fy=585&cx=320&cy=240",
                                          emf::core::SourceOptions{});
      emf::core::Frame f;
      size_t n = 0;
      while (src->next(f)) ++n;
      const double read_s = secondsSince(t0);
      std::printf("klg read   %zu frames: %.2f ms/frame (%.1f frames/s)\n", n, read_s * 1e3 / n,
                  n / read_s);
      fs::remove(tmp);
    }
    // 3. Evaluation of the reference pair (3000 GT poses, 788 estimated).
    {
      const std::string gt = data + "/trajectories/freiburg1_xyz-groundtruth.txt";
      const std::string est = data + "/trajectories/freiburg1_xyz-rgbdslam.txt";
      const int reps = 20;
      auto t0 = std::chrono::steady_clock::now();
      emf::eval::EvalReport r;
      for (int i = 0; i < reps; ++i)
        r = emf::eval::evaluatePaths(gt, est, emf::eval::EvalOptions{});
      const double s = secondsSince(t0) / reps;
      std::printf(
          "eval       fr1_xyz reference (read both files, ATE %zu pairs, RPE %zu pairs): "
          "%.1f ms\n",
          r.camera.ate->pairs, r.camera.rpe->pairs, s * 1e3);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_io: %s\n", e.what());
    return 1;
  }
  return 0;
}
