// What `emf run` writes into its output folder besides the trajectories (streamed, see
// io::TrajectoryStream): run.json, the run's summary and status, rewritten atomically at start,
// at every checkpoint and at the end; background.ply, written atomically at the end (and at
// mesh checkpoints when asked).
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

/// Where a run stands (run.json "status").
enum class RunStatus {
  kRunning,      // frames are being processed (a run killed hard keeps this status)
  kFinished,     // the source ended or the frame limit was reached
  kInterrupted,  // a signal stopped it after a frame (run.json "signal")
  kFailed,       // an error stopped it (run.json "error")
};
const char* runStatusName(RunStatus status);

/// Everything the summary reports besides what SlamSystem knows.
struct RunInfo {
  /// RunFolder::runId(), its start time and the process.
  std::string run_id;
  std::string started_utc;
  int64_t pid = 0;
  RunStatus status = RunStatus::kRunning;
  /// "SIGINT", "SIGTERM", "SIGHUP" for an interrupted run.
  std::string signal;
  /// Frames the source dropped before emf saw them (a live sensor running ahead of the SLAM).
  int64_t source_dropped_frames = 0;
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

/// run.json before the SLAM exists (device and kernels still starting): run id, status,
/// source, pid, start time, 0 frames.
std::string startingSummaryJson(const RunInfo& info);

/// Writes `dir`/background.ply from the background volume (streamed, atomically). Throws.
void writeBackgroundMesh(const std::string& dir, SlamSystem& slam, bool binary_ply);

/// End of a run: writes background.ply (binary or ASCII), then run.json, into `dir`. run.json is
/// written even when the mesh cannot be, with the mesh's error in "error"; then throws IoError
/// for it unless the run had already failed.
void writeFinalOutputs(const std::string& dir, SlamSystem& slam, const cl::Context& ctx,
                       const RunInfo& info, bool binary_ply);

}  // namespace emf::pipeline
