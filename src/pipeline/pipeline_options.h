// Options of the detector scheduling (section `detector`), the runtime threads (section
// `runtime`) and the outputs (section `output`).
#pragma once

#include <string>
#include <vector>

#include "common/option_binder.h"
#include "core/ring_policy.h"

namespace emf::pipeline {

enum class DetectorMode { kSequential, kAsync };
inline const ChoiceNames<DetectorMode>& detectorModeNames() {
  static const ChoiceNames<DetectorMode> names = {{DetectorMode::kSequential, "sequential"},
                                                  {DetectorMode::kAsync, "async"}};
  return names;
}
enum class DetectorIsolation { kAuto, kProcess, kNone };
inline const ChoiceNames<DetectorIsolation>& detectorIsolationNames() {
  static const ChoiceNames<DetectorIsolation> names = {{DetectorIsolation::kAuto, "auto"},
                                                       {DetectorIsolation::kProcess, "process"},
                                                       {DetectorIsolation::kNone, "none"}};
  return names;
}

struct DetectorOptions {
  /// Plugin name (looked up on the search path) or path to a shared object; "" = none.
  std::string plugin;
  /// Configuration string passed to the plugin's create().
  std::string plugin_config;
  /// Extra folders searched for plugins (before EMF_PLUGIN_PATH and the install folder).
  std::vector<std::string> search_path;
  /// Sequential mode: run the detector on every N-th frame.
  int every_n_frames = 30;
  /// sequential (deterministic, datasets) or async (own thread, live sensors).
  DetectorMode mode = DetectorMode::kSequential;
  /// Where the plugin runs: process (a child process, emf_detector_host: a crash or hang of the
  /// plugin cannot take the SLAM down), none (inside emf), auto (process for a plugin loaded by
  /// path, none for the plugins installed with emf).
  DetectorIsolation isolation = DetectorIsolation::kAuto;
  /// Under process isolation: a detect() call that takes longer is a hang; the child is killed
  /// and restarted (the SLAM waits this long at most in sequential mode).
  double deadline_s = 5.0;
  /// Niceness of the async detector (Linux nice, 0-19; 0 = the SLAM's own priority): the
  /// detector thread, and under process isolation the plugin's whole process (its worker
  /// threads included), so that the SLAM thread wins the cores while a detection runs.
  /// In-process, worker threads another thread started earlier (OpenCV's pool) keep their
  /// priority: with isolation none, the dnn plugin's threads=1 keeps the network on the niced
  /// thread. Sequential mode (the detector on the SLAM thread, or the SLAM thread waiting for
  /// the plugin's process) is not niced. 10: while a detection runs the SLAM keeps most of its
  /// rate and the detection takes 2-3 times as long
  /// (docs/benchmarks.md#the-detectors-share-of-the-cores-benchdetector_share).
  int nice = 10;

  void bind(OptionBinder& b) {
    b.text("plugin", plugin, "detector plugin name or path ('' = none)");
    b.text("plugin_config", plugin_config, "configuration string for the plugin");
    b.textList("search_path", search_path, "extra plugin folders");
    b.integer("every_n_frames", every_n_frames, 1, 100000, "frames", "detection interval");
    b.choice("mode", mode, detectorModeNames(), "how the detector runs");
    b.choice("isolation", isolation, detectorIsolationNames(),
             "plugin in a child process (process), in emf (none), or process for plugins "
             "loaded by path (auto)");
    b.real("deadline_s", deadline_s, 0.01, 3600.0, "s",
           "isolated plugin: a call taking longer is a hang (child killed, restarted)");
    b.integer("nice", nice, 0, 19, "",
              "niceness of the async detector thread and of an isolated plugin's process");
  }
};

struct RuntimeOptions {
  /// Frame ring slots between capture and SLAM.
  int ring_slots = 4;
  /// drop_oldest (live) or block (replay, lossless).
  core::RingPolicy ring_policy = core::RingPolicy::kBlock;
  /// Results kept for polling; when the poller is slower the oldest results are discarded
  /// (counted as results_dropped), so a poll always returns the newest ones.
  int result_queue = 32;

  void bind(OptionBinder& b) {
    b.integer("ring_slots", ring_slots, 2, 1024, "frames", "frame ring capacity");
    b.choice("ring_policy", ring_policy, core::ringPolicyNames(), "frame ring policy");
    b.integer("result_queue", result_queue, 1, 100000, "results",
              "results kept for polling (oldest discarded when full)");
  }
};

struct OutputOptions {
  /// Write binary (true) or ASCII (false) PLY meshes.
  bool binary_ply = true;
  /// Write per-frame PNG overlays of object masks and association maps.
  bool write_images = false;
  /// `emf run` rewrites run.json (status, counts) and syncs the trajectories to disk every this
  /// many frames. The trajectories are flushed every frame regardless: a killed process loses
  /// nothing; a power cut loses at most the frames since the last checkpoint.
  int checkpoint_frames = 30;
  /// `emf run` also rewrites background.ply and the live objects' meshes every this many frames
  /// (0 = only at the end). A mesh costs about as much as a few frames' work.
  int mesh_checkpoint_frames = 0;

  void bind(OptionBinder& b) {
    b.boolean("binary_ply", binary_ply, "binary PLY meshes (false = ASCII)");
    b.boolean("write_images", write_images, "per-frame PNG overlays and association maps");
    b.integer("checkpoint_frames", checkpoint_frames, 1, 1000000, "frames",
              "run.json rewritten and trajectories synced to disk every N frames");
    b.integer("mesh_checkpoint_frames", mesh_checkpoint_frames, 0, 1000000, "frames",
              "meshes rewritten every N frames (0 = at the end only)");
  }
};

}  // namespace emf::pipeline
