// What `emf run` (and the runtime) write into an output folder: camera.txt (TUM trajectory,
// source timestamps), background.ply, run.json (summary). All files are written atomically.
#pragma once

#include <string>
#include <vector>

#include "io/trajectory.h"
#include "pipeline/slam_system.h"

namespace emf::pipeline {

/// One lost frame, for the summary.
struct LostFrame {
  int64_t index = 0;
  double timestamp = 0;
  std::string reason;
};

/// Everything the summary reports besides what SlamSystem knows.
struct RunInfo {
  std::string source_uri;
  std::string source_description;
  std::string config_file;
  double wall_s = 0;
  std::vector<LostFrame> lost;
};

/// The run summary as JSON text (frames, lost frames, per-stage ms median/p90, memory, device).
std::string runSummaryJson(const SlamSystem& slam, const cl::Context& ctx, const RunInfo& info);

/// Writes camera.txt, background.ply (binary or ASCII) and run.json into `dir` (created).
void writeRunOutputs(const std::string& dir, SlamSystem& slam, const cl::Context& ctx,
                     const io::Trajectory& camera, const RunInfo& info, bool binary_ply);

}  // namespace emf::pipeline
