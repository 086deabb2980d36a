// When the detector runs (docs/method.md#detection-frames, docs/architecture.md#threads): either
// sequentially on every N-th frame (deterministic, for datasets) or asynchronously on its own
// thread (live sensors), where a result arrives some frames late and is matched using the poses
// of the frame it was computed on — so every result carries those poses.
//
// Frames: poses are T_a_b (maps points in b to a); W = the SLAM's world frame.
#pragma once

#include <Eigen/Geometry>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/frame.h"
#include "pipeline/detector_plugin.h"
#include "pipeline/isolated_detector.h"
#include "pipeline/pipeline_options.h"

namespace emf::pipeline {

/// The pose of one object volume at the frame a detection batch was computed on.
struct ObjectPose {
  int id = 0;                                                        // object id (> 0)
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // volume frame in W
};

/// The detections of one detector run and the state of the frame they were computed on. In
/// async mode that frame lies `frames_late` frames before the one whose submit() returned the
/// batch: render the object masks for matching at `T_world_camera` / `objects`, not at the
/// current poses.
struct DetectionBatch {
  int64_t frame_index = 0;     // core::Frame::index of the frame the detector ran on
  double timestamp = 0;        // its timestamp (seconds)
  std::string timestamp_text;  // its timestamp as the source wrote it
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // camera pose of that frame
  std::vector<ObjectPose> objects;          // object poses of that frame (as given to submit())
  std::vector<core::Detection> detections;  // valid detections (CV_32F masks in [0, 1])
  int64_t frames_late = 0;        // index of the submitting frame minus frame_index (0: sequential)
  double detector_ms = 0;         // wall time of the plugin's detect() call
  bool new_objects_only = false;  // DetectorOutput::new_objects_only of the call
};

/// Counters of a scheduler (for run.json and the C API's metrics).
struct DetectorStats {
  std::string plugin;          // plugin name ("" = none)
  std::string mode;            // sequential | async
  int64_t runs = 0;            // detect() calls finished
  int64_t failures = 0;        // calls that failed as a whole (no detections used)
  int64_t detections = 0;      // valid detections returned
  int64_t rejected = 0;        // malformed detections dropped by the host
  int64_t dropped_frames = 0;  // async: frames not handed over because the detector was busy
  /// Sequential: frames that carry the source's own detections (a dataset's masks/) but are not
  /// on the detector's schedule (detector.every_n_frames), so the maskfile plugin skips them.
  int64_t labelled_frames_skipped = 0;
  int64_t results_delivered = 0;  // batches returned by submit()/finish()
  double detector_ms_median = 0;  // of the detect() calls (0 when none ran)
  double detector_ms_max = 0;
  /// "in-process" or "process" (detector.isolation); the counters of an isolated plugin.
  std::string isolation = "in-process";
  int64_t crashes = 0;   // the plugin's process died during a call
  int64_t timeouts = 0;  // a call passed detector.deadline_s: the process was killed
  int64_t restarts = 0;  // the plugin's process was started again
  /// Every distinct kind of problem (message with its numbers replaced by '#') and its count.
  std::map<std::string, int64_t> problems;
};

/// Runs a detector on the frames handed to it, per DetectorOptions::mode.
///
/// Threading: submit(), finish() and stats() are called from one thread (the SLAM thread); in
/// async mode the detector runs on a thread owned by the scheduler. submit() never waits for
/// the detector: it copies the frame into a slot allocated at construction (the copy reuses the
/// slot's buffers once they have the frame's size) or drops the frame when the detector is busy.
class DetectorScheduler {
 public:
  /// The function that detects (for tests and embedders; the plugin host in normal use). Called
  /// from the detector thread in async mode. Must not throw; failures go into DetectorOutput.
  using DetectFunction = std::function<DetectorOutput(
      const core::Frame& frame, const cv::Mat* background_association, const cv::Mat* residual)>;

  /// Loads options.plugin (a name looked up on pluginSearchPath(options) — detector.search_path,
  /// $EMF_PLUGIN_PATH, the build and install plugin folders — or a path), passing it
  /// options.plugin_config, `source_uri` and `intrinsics`, in emf or in a child process per
  /// options.isolation (usesProcess). No plugin when options.plugin is empty (enabled() is
  /// false). Throws PluginError (not found: lists the folders searched;
  /// cannot load/create: says why) and ConfigError for a bad mode / interval.
  DetectorScheduler(const DetectorOptions& options, const std::string& source_uri,
                    const core::Intrinsics& intrinsics);
  /// A scheduler around `detect` (named `name` in messages and stats).
  DetectorScheduler(const DetectorOptions& options, const std::string& name, DetectFunction detect,
                    const core::Intrinsics& intrinsics);
  /// Stops the detector thread after its current call (waits for that call to return).
  ~DetectorScheduler();
  DetectorScheduler(const DetectorScheduler&) = delete;
  DetectorScheduler& operator=(const DetectorScheduler&) = delete;

  bool enabled() const { return static_cast<bool>(detect_); }
  /// Whether the detector reads the feedback images of submit() (a plugin's
  /// EMF_DETECTOR_FLAG_READS_FEEDBACK; always true for a DetectFunction).
  bool readsFeedback() const {
    return plugin_ ? plugin_->readsFeedback() : isolated_ ? isolated_->readsFeedback() : true;
  }
  bool async() const { return async_; }

  /// Call once per frame after tracking, with the frame's camera pose and the object poses
  /// (may be null = none). Feedback images (CV_32F, depth size; may be null) are passed to the
  /// plugin. Sequential: on frames with frame.index % every_n_frames == 0 runs the detector now
  /// and returns its batch (also when it found nothing or failed: then `detections` is empty).
  /// Async: returns the finished result not yet returned, if any, then hands a due frame (same
  /// rule) to the detector thread if it is idle, else counts it as dropped. The slot holds one
  /// frame, so every result is returned before the next hand-over. Disabled: nullopt.
  /// Detections a source attaches to frames (core::Frame::detections) are never used here: the
  /// maskfile plugin replays them.
  std::optional<DetectionBatch> submit(const core::Frame& frame,
                                       const Eigen::Isometry3d& T_world_camera,
                                       const cv::Mat* background_association = nullptr,
                                       const cv::Mat* residual = nullptr,
                                       const std::vector<ObjectPose>* objects = nullptr);

  /// Async: waits until the detector thread has finished the frame it is working on and
  /// returns the newest result not yet returned (end of a replay, tests). Sequential: nullopt.
  std::optional<DetectionBatch> finish();
  /// Async: waits until the detector thread has finished the frame it is working on (its result
  /// stays for the next submit()). Returns at once when idle or sequential.
  void waitIdle();

  /// Async: whether the detector thread is working on a frame now (benches, tests).
  bool busy() const;

  /// The counters so far.
  DetectorStats stats() const;

  const std::string& name() const { return name_; }

 private:
  // One frame handed to the detector thread, with buffers reused from frame to frame.
  struct Slot {
    core::Frame frame;
    cv::Mat background_association, residual;
    bool has_background_association = false, has_residual = false;
    Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
    std::vector<ObjectPose> objects;
  };

  void init(const DetectorOptions& options, const core::Intrinsics& intrinsics);
  // Runs the detector on `slot` and fills `batch` (any thread); records stats under mutex_.
  void runDetector(const Slot& slot, DetectionBatch* batch);
  void recordProblem(const std::string& message);  // mutex_ held
  void threadMain();
  std::optional<DetectionBatch> takeReady(int64_t current_index);  // mutex_ held

  std::unique_ptr<DetectorPlugin> plugin_;      // detector.isolation none
  std::unique_ptr<IsolatedDetector> isolated_;  // detector.isolation process
  DetectFunction detect_;
  std::string name_;
  bool async_ = false;
  int every_n_frames_ = 30;
  int nice_ = 0;  // DetectorOptions::nice
  bool warned_source_detections_ = false;
  bool warned_skipped_labels_ = false;

  // Async state. The SLAM thread owns slot_ while busy_ is false; the detector thread owns it
  // (and working_) while busy_ is true. ready_ is guarded by mutex_.
  Slot slot_;
  DetectionBatch working_;
  DetectionBatch ready_;
  bool has_ready_ = false;
  bool busy_ = false;
  bool stop_ = false;
  std::thread thread_;
  std::condition_variable wake_, idle_;

  mutable std::mutex mutex_;  // guards everything below and the async flags above
  DetectorStats stats_;
  std::vector<double> detector_ms_;
};

/// Whether detector.isolation puts the plugin at `resolved_path` in a child process: process
/// always, none never, auto when the plugin is not one installed with emf (not in
/// modulePluginFolders()).
bool usesProcess(const DetectorOptions& options, const std::string& resolved_path);

/// `message` with every run of digits replaced by '#' (the kind of a problem for counting and
/// logging once: "frame 12 detection 3: ..." and "frame 40 detection 1: ..." are one kind).
std::string problemKind(const std::string& message);

}  // namespace emf::pipeline
