#include "pipeline/stage_timer.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/error.h"

namespace emf::pipeline {

TimingSummary summarize(std::vector<double> samples_ms) {
  TimingSummary s;
  s.count = static_cast<int>(samples_ms.size());
  if (samples_ms.empty()) return s;
  std::sort(samples_ms.begin(), samples_ms.end());
  auto rank = [&](double p) {
    const size_t r = static_cast<size_t>(std::ceil(p * samples_ms.size()));
    return samples_ms[std::min(samples_ms.size() - 1, r == 0 ? 0 : r - 1)];
  };
  s.median_ms =
      samples_ms.size() % 2
          ? samples_ms[samples_ms.size() / 2]
          : 0.5 * (samples_ms[samples_ms.size() / 2 - 1] + samples_ms[samples_ms.size() / 2]);
  s.p90_ms = rank(0.9);
  s.p99_ms = rank(0.99);
  s.mean_ms = std::accumulate(samples_ms.begin(), samples_ms.end(), 0.0) / samples_ms.size();
  s.max_ms = samples_ms.back();
  return s;
}

StageTimer::StageTimer(std::vector<std::string> stages, size_t reserve_frames)
    : stages_(std::move(stages)) {
  for (const auto& s : stages_) {
    current_[s] = 0;
    samples_[s].reserve(reserve_frames);
  }
  samples_["total"].reserve(reserve_frames);
}

void StageTimer::add(const std::string& name, double ms) {
  auto it = current_.find(name);
  if (it == current_.end()) throw InvalidArgument("StageTimer: unknown stage '" + name + "'");
  it->second += ms;
}

void StageTimer::endFrame() {
  double total = 0;
  for (const auto& s : stages_) {
    samples_[s].push_back(current_[s]);
    total += current_[s];
    current_[s] = 0;
  }
  samples_["total"].push_back(total);
}

std::map<std::string, TimingSummary> StageTimer::summary() const {
  std::map<std::string, TimingSummary> out;
  for (const auto& kv : samples_) out[kv.first] = summarize(kv.second);
  return out;
}

const std::vector<double>& StageTimer::samples(const std::string& name) const {
  auto it = samples_.find(name);
  if (it == samples_.end()) throw InvalidArgument("StageTimer: unknown stage '" + name + "'");
  return it->second;
}

}  // namespace emf::pipeline
