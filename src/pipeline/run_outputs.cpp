#include "pipeline/run_outputs.h"

#include <filesystem>

#include "common/error.h"
#include "io/atomic_output.h"
#include "io/ply.h"
#include "map/mesh.h"
#include "map/volume_host_access.h"
#include "pipeline/run_folder.h"

namespace emf::pipeline {

namespace {

nlohmann::json poseJson(const Eigen::Isometry3d& T) {
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) {
    rows.push_back({T.matrix()(r, 0), T.matrix()(r, 1), T.matrix()(r, 2), T.matrix()(r, 3)});
  }
  return rows;
}

}  // namespace

nlohmann::json objectSummariesJson(const std::vector<ObjectSummary>& objects) {
  nlohmann::json out = nlohmann::json::array();
  for (const ObjectSummary& o : objects) {
    nlohmann::json j;
    j["id"] = o.id;
    j["class"] = o.class_name;
    j["first_frame"] = o.first_frame;
    j["last_frame"] = o.last_frame;
    j["first_timestamp"] = o.first_timestamp;
    j["last_timestamp"] = o.last_timestamp;
    j["frames_tracked"] = o.frames_tracked;
    j["frames_lost"] = o.frames_lost;
    j["frames_invisible"] = o.frames_invisible;
    j["frames_dormant"] = o.frames_dormant;
    j["state"] = o.deleted ? "deleted" : "alive";
    if (o.deleted) {
      j["deleted_frame"] = o.deleted_frame;
      j["deleted_timestamp"] = o.deleted_timestamp;
      j["deleted_reason"] = o.deleted_reason;
    }
    j["existence"] = o.existence;
    j["T_world_object"] = poseJson(o.T_world_object);
    j["trajectory_file"] = o.trajectory_file;
    j["mesh_file"] = o.mesh_file;
    out.push_back(j);
  }
  return out;
}

nlohmann::json detectorStatsJson(const DetectorStats& s) {
  nlohmann::json problems = nlohmann::json::object();
  for (const auto& [kind, count] : s.problems) problems[kind] = count;
  return {{"plugin", s.plugin},
          {"mode", s.mode},
          {"runs", s.runs},
          {"failures", s.failures},
          {"detections", s.detections},
          {"rejected_detections", s.rejected},
          {"dropped_frames", s.dropped_frames},
          {"labelled_frames_skipped", s.labelled_frames_skipped},
          {"results_delivered", s.results_delivered},
          {"detector_ms_median", s.detector_ms_median},
          {"detector_ms_max", s.detector_ms_max},
          {"isolation", s.isolation},
          {"crashes", s.crashes},
          {"timeouts", s.timeouts},
          {"restarts", s.restarts},
          {"problems", problems}};
}

const char* runStatusName(RunStatus status) {
  switch (status) {
    case RunStatus::kRunning:
      return "running";
    case RunStatus::kFinished:
      return "finished";
    case RunStatus::kInterrupted:
      return "interrupted";
    case RunStatus::kFailed:
      return "failed";
  }
  return "unknown";
}

namespace {

// The fields every run.json has, from its first version on.
nlohmann::json statusJson(const RunInfo& info) {
  nlohmann::json j;
  j["run_id"] = info.run_id;
  j["status"] = runStatusName(info.status);
  if (!info.signal.empty()) j["signal"] = info.signal;
  j["pid"] = info.pid;
  j["started_utc"] = info.started_utc;
  j["updated_utc"] = utcNow();
  j["source"] = {{"uri", info.source_uri},
                 {"description", info.source_description},
                 {"dropped_frames", info.source_dropped_frames}};
  j["config_file"] = info.config_file;
  return j;
}

}  // namespace

std::string startingSummaryJson(const RunInfo& info) {
  nlohmann::json j = statusJson(info);
  j["frames"] = 0;
  if (!info.error.empty()) j["error"] = info.error;
  return j.dump(2) + "\n";
}

std::string runSummaryJson(const SlamSystem& slam, const cl::Context& ctx, const RunInfo& info) {
  nlohmann::json j = statusJson(info);
  j["frames"] = slam.framesProcessed();
  j["lost_frames"] = slam.framesLost();
  nlohmann::json lost = nlohmann::json::array();
  for (const auto& l : info.lost) {
    lost.push_back({{"index", l.index}, {"timestamp", l.timestamp}, {"reason", l.reason}});
  }
  j["lost"] = lost;
  j["frames_not_in_trajectories"] = info.frames_not_in_trajectories;
  if (info.frames_not_in_trajectories > 0) {
    j["first_frame_not_in_trajectories"] = info.first_frame_not_in_trajectories;
  }
  j["wall_s"] = info.wall_s;
  j["frames_per_s"] = info.wall_s > 0 ? slam.framesProcessed() / info.wall_s : 0.0;
  nlohmann::json stages;
  for (const auto& [name, s] : slam.timer().summary()) {
    stages[name] = {{"median_ms", s.median_ms},
                    {"p90_ms", s.p90_ms},
                    {"mean_ms", s.mean_ms},
                    {"max_ms", s.max_ms},
                    {"count", s.count}};
  }
  j["ms_per_frame"] = stages;
  nlohmann::json work;
  for (const auto& [name, c] : slam.counters().summary()) {
    work[name] = {
        {"median", c.median}, {"p90", c.p90}, {"mean", c.mean}, {"max", c.max}, {"count", c.count}};
  }
  j["work_per_frame"] = work;
  const map::PoolStats pool = slam.pool().stats();
  j["memory"] = {{"pool_bytes", pool.pool_bytes},
                 {"pool_slots", pool.capacity_slots},
                 {"used_slots", pool.used_slots},
                 {"occupancy", pool.occupancy()},
                 {"dropped_blocks", pool.dropped_blocks},
                 {"background_pool_full_frames", slam.backgroundPoolFullFrames()},
                 {"objects_refused_for_pool", slam.poolRefusedObjects()},
                 {"background_index_bytes", slam.background().indexBytes()},
                 {"background_shifts", slam.backgroundShifts()},
                 {"evicted_blocks", slam.evictedBlocks()}};
  j["device"] = {{"name", ctx.device().device_name},
                 {"platform", ctx.device().platform_name},
                 {"driver", ctx.device().driver_version},
                 {"fallback", ctx.selection().fallback},
                 {"description", ctx.describe()},
                 {"pocl_target", ctx.device().poclTarget()},
                 {"native_vector_width_float", ctx.device().native_vector_width_float}};
  const core::Intrinsics& k = slam.intrinsics();
  j["intrinsics"] = {{"fx", k.fx}, {"fy", k.fy},       {"cx", k.cx},
                     {"cy", k.cy}, {"width", k.width}, {"height", k.height}};
  if (info.objects) j["objects"] = objectSummariesJson(*info.objects);
  if (info.detector) j["detector"] = detectorStatsJson(*info.detector);
  if (!info.error.empty()) j["error"] = info.error;
  return j.dump(2) + "\n";
}

void writeBackgroundMesh(const std::string& dir, SlamSystem& slam, bool binary_ply) {
  // Streamed from the mapped volume (and the surface the moving map left, on disk) into the
  // file: no host copy of the map, no mesh in memory.
  io::PlyWriter ply(dir + "/background.ply", binary_ply);
  slam.extractBackgroundMesh(ply);
  ply.commit();
}

void writeFinalOutputs(const std::string& dir, SlamSystem& slam, const cl::Context& ctx,
                       const RunInfo& info, bool binary_ply) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create the output folder: " + ec.message());
  // run.json is written even when the mesh cannot be (e.g. after a device error ended the run).
  std::string mesh_error;
  try {
    writeBackgroundMesh(dir, slam, binary_ply);
  } catch (const std::exception& e) {
    mesh_error = std::string("background.ply not written: ") + e.what();
  }
  RunInfo written = info;
  if (!mesh_error.empty()) {
    written.error = written.error.empty() ? mesh_error : written.error + "; " + mesh_error;
    if (written.status == RunStatus::kFinished) written.status = RunStatus::kFailed;
  }
  io::writeFileAtomically(dir + "/run.json", runSummaryJson(slam, ctx, written));
  if (!mesh_error.empty() && info.error.empty()) throw IoError(dir + ": " + mesh_error);
}

}  // namespace emf::pipeline
