#include "pipeline/run_outputs.h"

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/error.h"
#include "io/atomic_output.h"
#include "map/mesh.h"

namespace emf::pipeline {

std::string runSummaryJson(const SlamSystem& slam, const cl::Context& ctx, const RunInfo& info) {
  nlohmann::json j;
  j["source"] = {{"uri", info.source_uri}, {"description", info.source_description}};
  j["config_file"] = info.config_file;
  j["frames"] = slam.framesProcessed();
  j["lost_frames"] = slam.framesLost();
  nlohmann::json lost = nlohmann::json::array();
  for (const auto& l : info.lost) {
    lost.push_back({{"index", l.index}, {"timestamp", l.timestamp}, {"reason", l.reason}});
  }
  j["lost"] = lost;
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
  const map::PoolStats pool = slam.pool().stats();
  j["memory"] = {{"pool_bytes", pool.pool_bytes},
                 {"pool_blocks", pool.capacity_slots},
                 {"used_blocks", pool.used_slots},
                 {"occupancy", pool.occupancy()},
                 {"dropped_blocks", pool.dropped_blocks},
                 {"background_index_bytes", slam.background().indexBytes()}};
  j["device"] = {{"name", ctx.device().device_name},
                 {"platform", ctx.device().platform_name},
                 {"driver", ctx.device().driver_version},
                 {"fallback", ctx.selection().fallback}};
  const io::Intrinsics& k = slam.intrinsics();
  j["intrinsics"] = {{"fx", k.fx}, {"fy", k.fy},       {"cx", k.cx},
                     {"cy", k.cy}, {"width", k.width}, {"height", k.height}};
  return j.dump(2) + "\n";
}

void writeRunOutputs(const std::string& dir, SlamSystem& slam, const cl::Context& ctx,
                     const io::Trajectory& camera, const RunInfo& info, bool binary_ply) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir + ": cannot create the output folder: " + ec.message());
  io::writeTrajectory(dir + "/camera.txt", camera,
                      "camera trajectory T_world_camera (emf run, source " + info.source_uri + ")");
  const map::Mesh mesh = map::extractMesh(slam.background().download());
  map::writePly(dir + "/background.ply", mesh, binary_ply);
  io::writeFileAtomically(dir + "/run.json", runSummaryJson(slam, ctx, info));
}

}  // namespace emf::pipeline
