// Multithreaded rendering and noise (std::thread over rows): identical output for any thread
// count, and worker exceptions reach the caller. Runs under ThreadSanitizer (label threads).
#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <stdexcept>

#include "synth/parallel.h"
#include "synth/synth_source.h"

namespace emf::synth {
namespace {

bool sameBytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

TEST(SynthThreads, OutputDoesNotDependOnThreadCount) {
  core::Frame frames[3];
  const int thread_counts[3] = {1, 2, 5};
  for (int k = 0; k < 3; ++k) {
    SynthOptions o;
    o.preset = "occlusion";
    o.width = 120;
    o.height = 90;
    o.threads = thread_counts[k];
    SynthSource(o).renderFrame(180, &frames[k]);
  }
  for (int k = 1; k < 3; ++k) {
    EXPECT_TRUE(sameBytes(frames[0].depth, frames[k].depth)) << thread_counts[k];
    EXPECT_TRUE(sameBytes(frames[0].color, frames[k].color)) << thread_counts[k];
    EXPECT_TRUE(sameBytes(frames[0].instance_ids, frames[k].instance_ids)) << thread_counts[k];
  }
  EXPECT_GT(cv::countNonZero(frames[0].instance_ids), 100);
}

TEST(SynthThreads, ParallelForCoversEveryIndexOnceAndRethrows) {
  std::vector<std::atomic<int>> hits(1000);
  parallelFor(1000, 4, [&](int b, int e) {
    for (int i = b; i < e; ++i) hits[static_cast<size_t>(i)]++;
  });
  for (const auto& h : hits) EXPECT_EQ(h.load(), 1);
  EXPECT_THROW(parallelFor(100, 3,
                           [](int b, int) {
                             if (b == 0) throw std::runtime_error("chunk failed");
                           }),
               std::runtime_error);
  int calls = 0;
  parallelFor(0, 4, [&](int, int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

}  // namespace
}  // namespace emf::synth
