// What `emf run` (and the runtime) write into an output folder: camera.txt (TUM trajectory,
// source timestamps), background.ply, run.json (summary). All files are written atomically.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/trajectory.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/object_outputs.h"
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
  /// Frames tracked whose timestamp was not after the last one written (a sensor clock that
  /// stepped back or repeated): TUM files need increasing stamps, so their poses (the camera's
  /// and the objects') are left out of the trajectory files. run.json
  /// "frames_not_in_trajectories" and "first_frame_not_in_trajectories".
  int64_t frames_not_in_trajectories = 0;
  int64_t first_frame_not_in_trajectories = -1;
  /// Per-object summaries (run.json "objects" array) when the run tracks objects.
  std::optional<std::vector<ObjectSummary>> objects;
  /// Detector counters (run.json "detector") when a detector ran.
  std::optional<DetectorStats> detector;
  /// Why the run stopped early ("" = it reached the end of the source); run.json "error".
  std::string error;
};

/// run.json's "objects" array: one entry per object (id, class, first/last frame and timestamp,
/// frames tracked/lost/invisible, state alive|deleted, deleted_frame/_timestamp/_reason when
/// deleted, existence, T_world_object as 4 rows, trajectory_file, mesh_file).
nlohmann::json objectSummariesJson(const std::vector<ObjectSummary>& objects);
/// run.json's "detector" object: the DetectorStats counters.
nlohmann::json detectorStatsJson(const DetectorStats& stats);

/// The run summary as JSON text (frames, lost frames, per-stage ms median/p90, work per frame
/// (SlamSystem::counters: LM iterations, integrated blocks), memory, device,
/// and when given: "objects" [{id, class, first_frame, last_frame, frames_tracked, ...,
/// state alive|deleted, deleted_frame, deleted_reason}], "detector" counters, "error").
std::string runSummaryJson(const SlamSystem& slam, const cl::Context& ctx, const RunInfo& info);

/// Writes camera.txt, background.ply (binary or ASCII) and run.json into `dir` (created).
void writeRunOutputs(const std::string& dir, SlamSystem& slam, const cl::Context& ctx,
                     const io::Trajectory& camera, const RunInfo& info, bool binary_ply);

}  // namespace emf::pipeline
