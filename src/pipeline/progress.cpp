#include "pipeline/progress.h"

#include <unistd.h>

#include <cstdio>

namespace emf::pipeline {

Progress::Progress(int64_t total, bool force)
    : total_(total),
      enabled_(force || isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()),
      last_(start_) {}

std::string Progress::format(int64_t done, int64_t total, double elapsed_s,
                             const std::string& note) {
  char buf[256];
  const double fps = elapsed_s > 0 ? done / elapsed_s : 0.0;
  if (total > 0) {
    const double eta = fps > 0 ? (total - done) / fps : 0.0;
    std::snprintf(buf, sizeof(buf), "frame %lld/%lld  %.1f frames/s  ETA %02d:%02d",
                  static_cast<long long>(done), static_cast<long long>(total), fps,
                  static_cast<int>(eta) / 60, static_cast<int>(eta) % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "frame %lld  %.1f frames/s", static_cast<long long>(done), fps);
  }
  return note.empty() ? std::string(buf) : std::string(buf) + "  " + note;
}

void Progress::update(int64_t done, const std::string& note) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_ < std::chrono::milliseconds(250) && done != total_) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::fprintf(stderr, "\r%s\033[K", format(done, total_, elapsed, note).c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void Progress::finish() {
  if (enabled_ && drawn_) std::fprintf(stderr, "\n");
  drawn_ = false;
}

}  // namespace emf::pipeline
