// `emf run`: the SLAM on a source (dataset, synthetic world or sensor), writing camera.txt,
// the background mesh, per-object trajectories and meshes, optional per-frame images and a run
// summary into the output folder. Nothing done is lost: the folder is claimed before the first
// frame, the trajectories are appended and flushed every frame, run.json is rewritten at
// checkpoints with the run's status; an error, Ctrl-C, SIGTERM or SIGHUP still write the meshes
// and the final run.json, and a SIGKILL leaves the trajectories of every frame processed.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "cl/context.h"
#include "cli/arg_parser.h"
#include "cli/commands.h"
#include "cli/interrupt.h"
#include "cli/load_config.h"
#include "cli/run_viewer.h"
#include "common/error.h"
#include "common/log.h"
#include "core/frame_source.h"
#include "io/atomic_output.h"
#include "io/trajectory_stream.h"
#include "map/raycaster.h"
#include "pipeline/detector_plugin.h"
#include "pipeline/object_outputs.h"
#include "pipeline/plugin_search_path.h"
#include "pipeline/progress.h"
#include "pipeline/run_folder.h"
#include "pipeline/run_outputs.h"
#include "pipeline/slam_system.h"
#include "sources/open_source.h"

namespace emf::cli {

int cmdRun(const std::vector<std::string>& args) {
  // First: main() records signals from its first instruction; this guard takes over, so a
  // Ctrl-C during the parsing or the start-up still ends in a consistent output folder.
  const InterruptGuard interrupt;
  std::string source, config_file, out_dir = "out/run", frames_text, detector, detector_config;
  std::vector<std::string> sets;
  bool quiet = false, force = false;
  ArgParser p("run",
              "Runs the SLAM on a source and writes camera.txt (TUM format, the source's "
              "timestamps), background.ply, object-<id>.txt (T_object_camera) and object-<id>.ply "
              "(object frame) per object, images/ when output.write_images is set, and run.json "
              "(run id, status, frames, lost frames, ms per frame per stage, memory, device, "
              "objects, detector) into the output folder. The trajectories are written as the "
              "frames are processed; a folder holds one run. Without --source, source.uri of the "
              "configuration is used (default: the synthetic static room).");
  p.option("source", &source, "URI",
           "tum:<dir>, cofusion:<dir>, klg:<file>, synth:<preset>, openni2:[uri], v4l2:<dev>");
  p.option("config", &config_file, "FILE", "YAML configuration (conf/*.yaml)");
  p.repeated("set", &sets, "SECTION.KEY=VALUE", "override one configuration key");
  p.option("out", &out_dir, "DIR", "output folder (default out/run)");
  p.flag("force", &force, "replace the outputs of an earlier run in the output folder");
  p.option("frames", &frames_text, "N", "stop after N frames (source.max_frames)");
  p.option("detector", &detector, "NAME|PATH",
           "detector plugin (detector.plugin): a name looked up on detector.search_path, "
           "$EMF_PLUGIN_PATH and the plugin folders, or a path to a .so");
  p.option("detector-config", &detector_config, "STR",
           "configuration string for the plugin (detector.plugin_config)");
  p.flag("quiet", &quiet, "no progress line");
  RunViewerOptions view;
  p.flag("view", &view.window,
         "a live window: objects over the colour image, association maps, depth, top view ('q' "
         "closes it; frames it cannot draw in time are skipped, never the SLAM's)");
  p.option("video", &view.video_path, "FILE", "the same pictures, one per frame, as .avi or .mp4");
  p.option("frames-png", &view.png_dir, "DIR", "the same pictures as DIR/<frame>.png");
  if (auto code = p.parse(args)) return *code;
  if (!frames_text.empty()) sets.push_back("source.max_frames=" + frames_text);
  Config config = loadConfig(config_file, sets);
  // Set directly, not through --set: plugin configuration strings may hold '=', ':' or quotes.
  if (!detector.empty()) config.detector.plugin = detector;
  if (!detector_config.empty()) config.detector.plugin_config = detector_config;
  config.validate();
  if (source.empty()) source = config.source.uri;
  if (!config.detector.plugin.empty()) {
    // Fail before opening the device and the source: a wrong name lists the folders searched.
    pipeline::resolvePluginPath(config.detector.plugin,
                                pipeline::pluginSearchPath(config.detector));
  }

  const bool viewing = view.window || !view.video_path.empty() || !view.png_dir.empty();
  if (viewing) RunViewer::checkOptions(view);  // no display, a video name OpenCV cannot write

  // The folder before the device and the source: an unwritable --out fails in milliseconds.
  const pipeline::RunFolder folder(out_dir, force);
  pipeline::RunInfo info;
  info.run_id = folder.runId();
  info.started_utc = folder.startedUtc();
  info.pid = static_cast<int64_t>(getpid());
  info.source_uri = source;
  info.config_file = config_file;
  const std::string run_json = folder.path("run.json");
  io::writeFileAtomically(run_json, pipeline::startingSummaryJson(info));
  io::TrajectoryStream camera(
      folder.path("camera.txt"),
      "camera trajectory T_world_camera (emf run " + info.run_id + ", source " + source + ")");

  std::unique_ptr<cl::Context> ctx_ptr;
  std::unique_ptr<core::FrameSource> src;
  std::unique_ptr<pipeline::SlamSystem> slam_ptr;
  core::Intrinsics k, id_camera;
  // Images and the viewer: the object ids are ray cast here at each frame's estimated pose
  // (the viewer's at half the resolution, a quarter of the rays, shown scaled up; images/ at
  // full resolution); the association maps are those of the frame's last E-step.
  std::unique_ptr<map::RayCaster> id_renderer;
  std::unique_ptr<RunViewer> viewer;
  try {
    ctx_ptr = std::make_unique<cl::Context>(config.cl);
    src = sources::openSource(source, config.source);
    info.source_description = src->describe();
    logInfo("source: ", src->describe(), "; device: ", ctx_ptr->device().device_name);
    slam_ptr = std::make_unique<pipeline::SlamSystem>(*ctx_ptr, config, src->intrinsics(), source);
    k = src->intrinsics();
    id_camera = config.output.write_images
                    ? k
                    : k.scaled(std::max(2, k.width / 2), std::max(2, k.height / 2));
    if (config.output.write_images || viewing) {
      id_renderer =
          std::make_unique<map::RayCaster>(*ctx_ptr, config.map, id_camera.width, id_camera.height);
    }
    if (viewing) viewer = std::make_unique<RunViewer>(view, cv::Size(k.width, k.height));
  } catch (const std::exception& e) {
    // No SLAM to summarise: run.json keeps the start-up fields and says why it failed.
    info.status = pipeline::RunStatus::kFailed;
    info.error = std::string("start-up failed: ") + e.what();
    io::writeFileAtomically(run_json, pipeline::startingSummaryJson(info));
    throw;
  }
  cl::Context& ctx = *ctx_ptr;
  pipeline::SlamSystem& slam = *slam_ptr;
  slam.setEvictedSurfaceFolder(out_dir);  // background.ply takes it in at every mesh written
  pipeline::ObjectOutputs objects(out_dir, config.output.binary_ply, info.run_id);
  slam.setDeletionHook(
      [&objects](const pipeline::TrackedObject& o) { objects.onObjectDeleted(o.id, *o.volume); });
  const auto volume_of = [&slam](int id) { return slam.volume(id); };
  std::vector<double> viewer_ms;  // SLAM-thread time per frame spent on the viewer

  int64_t total = src->size();
  if (config.source.max_frames > 0 && (total < 0 || total > config.source.max_frames)) {
    total = config.source.max_frames;
  }
  pipeline::Progress progress(total, false);
  const auto t0 = std::chrono::steady_clock::now();
  // run.json with the counts so far (and the meshes when asked): survives any later kill.
  const auto refreshSummary = [&]() {
    info.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    info.objects = objects.summaries();
    if (!config.detector.plugin.empty()) info.detector = slam.detectorStats();
    info.source_dropped_frames = src->droppedFrames();
  };
  const auto checkpoint = [&](int64_t frames_done) {
    camera.sync();
    objects.sync();
    const int mesh_every = config.output.mesh_checkpoint_frames;
    if (mesh_every > 0 && frames_done > 0 && frames_done % mesh_every == 0) {
      pipeline::writeBackgroundMesh(out_dir, slam, config.output.binary_ply);
      objects.writeLiveMeshes(volume_of);
    }
    refreshSummary();
    io::writeFileAtomically(run_json, pipeline::runSummaryJson(slam, ctx, info));
  };
  core::Frame frame;
  int64_t n = 0;
  std::string last_written_stamp;
  try {
    checkpoint(0);
    while (!interrupt.requested() &&
           (config.source.max_frames == 0 || n < config.source.max_frames) && src->next(frame)) {
      const auto frame_t0 = std::chrono::steady_clock::now();
      const pipeline::FrameOutcome o = slam.process(frame);
      const double frame_ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_t0)
              .count();
      objects.add(o);
      if (o.lost) {
        info.lost.push_back({o.index, frame.timestamp, o.loss_reason});
        logWarning("frame ", o.index, " (t=", frame.timestamp_text,
                   "): tracking lost: ", o.loss_reason,
                   "; not integrated, keeping the last good pose");
      } else if (camera.append(frame.timestamp, o.T_world_camera)) {
        last_written_stamp = frame.timestamp_text;
      } else {
        // Tracked and fused, but a TUM file cannot hold a stamp that is not after the last.
        if (info.frames_not_in_trajectories++ % 100 == 0) {
          if (info.first_frame_not_in_trajectories < 0) {
            info.first_frame_not_in_trajectories = o.index;
          }
          logWarning("frame ", o.index, ": timestamp ", frame.timestamp_text,
                     " is not after the last pose written (", last_written_stamp,
                     "); the source's clock repeated or stepped back. The frame is tracked and "
                     "fused but its pose is left out of camera.txt and object-<id>.txt (",
                     info.frames_not_in_trajectories,
                     " such frame(s) so far; run.json "
                     "frames_not_in_trajectories)");
        }
      }
      if (id_renderer) {
        cv::Mat ids;
        id_renderer->render(slam.renderItems(), id_camera, o.T_world_camera);
        id_renderer->download(nullptr, nullptr, &ids);
        if (ids.cols != k.width) {
          cv::resize(ids, ids, cv::Size(k.width, k.height), 0, 0, cv::INTER_NEAREST);
        }
        std::vector<pipeline::AssociationImage> maps;
        const pipeline::SlamSystem::Associations a = slam.associations();
        for (size_t i = 0; i < a.ids.size(); ++i) maps.push_back({a.ids[i], a.q[i]});
        if (config.output.write_images) objects.writeFrameImages(o, frame.color, ids, maps);
        if (viewer) {
          pipeline::ViewFrame v;
          v.index = o.index;
          v.timestamp = frame.timestamp;
          v.color = frame.color.clone();  // the source reuses its buffers
          v.depth = frame.depth.clone();
          v.object_ids = ids;
          v.association = std::move(maps);
          v.T_world_camera = o.T_world_camera;
          v.intrinsics = k;
          v.objects = o.objects;
          v.lost = o.lost;
          v.ms = frame_ms;
          v.pool_occupancy = slam.pool().stats().occupancy();
          v.dropped_frames = src->droppedFrames();
          viewer->submit(std::move(v));
          viewer_ms.push_back(
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - frame_t0)
                  .count() -
              frame_ms);
        }
      }
      ++n;
      const int mesh_every = config.output.mesh_checkpoint_frames;
      if (n % config.output.checkpoint_frames == 0 || (mesh_every > 0 && n % mesh_every == 0)) {
        checkpoint(n);
      }
      if (!quiet) {
        std::string status;
        if (!info.lost.empty()) status = "lost " + std::to_string(info.lost.size());
        if (const int64_t dropped = src->droppedFrames(); dropped > 0) {
          status +=
              (status.empty() ? "" : ", ") + std::string("dropped ") + std::to_string(dropped);
        }
        progress.update(n, status);
      }
    }
  } catch (const std::exception& e) {
    // Keep what the frames so far produced: write the outputs, then fail.
    info.error = "stopped after " + std::to_string(n) + " frames: " + e.what();
  }
  if (interrupt.requested() && info.error.empty()) {
    info.error = std::string("interrupted by ") + interrupt.signalName() + " after " +
                 std::to_string(n) + " frames";
    info.status = pipeline::RunStatus::kInterrupted;
    info.signal = interrupt.signalName();
  } else {
    info.status =
        info.error.empty() ? pipeline::RunStatus::kFinished : pipeline::RunStatus::kFailed;
  }
  progress.finish();
  if (viewer) {
    try {
      viewer->finish();
    } catch (const std::exception& e) {
      const std::string viewer_error = e.what();
      info.error = info.error.empty() ? viewer_error : info.error + "; " + viewer_error;
      if (info.status == pipeline::RunStatus::kFinished) info.status = pipeline::RunStatus::kFailed;
    }
  }
  try {
    camera.sync();
    objects.finish(volume_of);
  } catch (const std::exception& e) {
    const std::string output_error = std::string("object outputs: ") + e.what();
    info.error = info.error.empty() ? output_error : info.error + "; " + output_error;
    if (info.status == pipeline::RunStatus::kFinished) info.status = pipeline::RunStatus::kFailed;
  }
  refreshSummary();
  std::string final_error;
  try {
    pipeline::writeFinalOutputs(out_dir, slam, ctx, info, config.output.binary_ply);
  } catch (const std::exception& e) {
    final_error = e.what();
  }
  const int64_t dropped = src->droppedFrames();
  if (dropped > 0) {
    logWarning("the source dropped ", dropped,
               " frame(s) before emf read them (a live sensor running ahead of the SLAM; "
               "run.json source.dropped_frames)");
  }
  if (!info.error.empty() || !final_error.empty()) {
    std::string message = info.error;
    if (!final_error.empty() && message.find(final_error) == std::string::npos) {
      message += (message.empty() ? "" : "; ") + final_error;
    }
    std::fprintf(stderr, "emf run: error: %s\n(outputs of the frames done so far are in %s)\n",
                 message.c_str(), std::filesystem::absolute(out_dir).string().c_str());
    return interrupt.requested() ? interrupt.exitCode() : kExitFailure;
  }
  const auto s = slam.timer().summary();
  std::printf(
      "emf run: %lld frames (%lld lost%s) in %.1f s, %.1f ms/frame median (p90 %.1f)\n",
      static_cast<long long>(slam.framesProcessed()), static_cast<long long>(slam.framesLost()),
      dropped > 0 ? (", " + std::to_string(dropped) + " dropped by the source").c_str() : "",
      info.wall_s, s.at("total").median_ms, s.at("total").p90_ms);
  if (info.frames_not_in_trajectories > 0) {
    std::printf(
        "  %lld tracked frame(s) left out of camera.txt: their timestamp was not after the last "
        "one written (run.json frames_not_in_trajectories)\n",
        static_cast<long long>(info.frames_not_in_trajectories));
  }
  for (const auto& stage : pipeline::SlamSystem::stageNames()) {
    std::printf("  %-10s %7.2f ms median  %7.2f ms p90\n", stage.c_str(), s.at(stage).median_ms,
                s.at(stage).p90_ms);
  }
  if (slam.backgroundPoolFullFrames() > 0 || slam.poolRefusedObjects() > 0) {
    std::printf(
        "voxel pool full: background blocks dropped on %lld frame(s), %lld object(s) not "
        "created: the map is incomplete; raise map.memory_mb (%d MiB)\n",
        static_cast<long long>(slam.backgroundPoolFullFrames()),
        static_cast<long long>(slam.poolRefusedObjects()), config.map.memory_mb);
  }
  if (viewer) {
    std::vector<double> sorted = viewer_ms;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
    std::printf(
        "viewer: %lld frame(s) shown, %lld skipped by the window, %lld written; %.2f ms median "
        "per frame on the SLAM thread (object ids ray cast + hand-over)\n",
        static_cast<long long>(viewer->framesShown()),
        static_cast<long long>(viewer->framesDropped()),
        static_cast<long long>(viewer->framesWritten()), median);
  }
  std::printf("outputs in %s: camera.txt background.ply run.json, %zu object(s)%s\n",
              std::filesystem::absolute(out_dir).string().c_str(), info.objects->size(),
              config.output.write_images ? ", images/" : "");
  return kExitOk;
}

}  // namespace emf::cli
