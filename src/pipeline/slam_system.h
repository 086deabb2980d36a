// The per-frame SLAM loop (docs/method.md#per-frame) on one OpenCL device: preprocess the
// depth, track the camera against the background SDF by direct alignment, integrate the frame
// into the background volume. Everything the loop needs on the device (pool, volume grids,
// images) is allocated at construction; process() allocates nothing on the device.
//
// Frames: world W = the first camera's frame (T_world_camera of frame 0 is the identity); the
// background volume V is placed so that this camera sits at the centre of one face looking in
// (map.initial_camera_face_offset) and, with map.follow_camera, moves by whole blocks to follow
// the camera (map/volume_follow.h). Poses are T_a_b (maps points in b to a).
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "cl/context.h"
#include "core/frame.h"
#include "em/estep.h"
#include "map/raycaster.h"
#include "map/volume.h"
#include "map/volume_follow.h"
#include "map/voxel_pool.h"
#include "pipeline/config.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/evicted_surface.h"
#include "pipeline/frame_counters.h"
#include "pipeline/object_lifecycle.h"
#include "pipeline/stage_timer.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace emf::pipeline {

/// What process() did with one frame.
struct FrameOutcome {
  int64_t index = 0;     // frames processed before this one
  double timestamp = 0;  // the frame's timestamp (seconds)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // estimate (last good if lost)
  bool first = false;  // the first frame: placed, not tracked
  bool lost = false;   // tracking failed: the frame was not integrated
  /// The background's move this frame (whole blocks along its grid axes; map.follow_camera)
  /// and the blocks that left it.
  Eigen::Vector3i map_shift = Eigen::Vector3i::Zero();
  int evicted_blocks = 0;
  std::string loss_reason;
  track::TrackResult track;          // of the background (unset on the first frame)
  map::AllocationReport allocation;  // of the background integration (unset when lost)
  /// Objects alive after this frame, plus those deleted in it (state kDeleted), by id. Tentative
  /// objects (objects.confirm_detections) are left out until confirmed.
  std::vector<ObjectOutcome> objects;
  /// Objects confirmed in this frame, with their tracked poses before it (earliest first).
  std::vector<ConfirmedObject> confirmed;
  bool detector_ran = false;            // detections were applied this frame
  int detections = 0;                   // detections used this frame
  std::vector<DetectionMatch> matches;  // per detection used, in the detector's order
};

class SlamSystem {
 public:
  /// Stages timed per frame, in order.
  static const std::vector<std::string>& stageNames();

  /// Sets up the device state for frames of `intrinsics` (their size). Throws ConfigError /
  /// InvalidArgument for bad options or intrinsics, ClError for device failures.
  /// `source_uri` is passed to the detector plugin (config detector.plugin) if one is set.
  SlamSystem(cl::Context& ctx, const Config& config, const core::Intrinsics& intrinsics,
             const std::string& source_uri = "");
  ~SlamSystem();

  /// Processes one frame (depth CV_32F metres, NaN = invalid, of the intrinsics' size): the EM
  /// loop of docs/method.md#per-frame. The detector plugin of config detector.* (if any) runs on
  /// its schedule (sequential: every N-th frame, now; async: on its own thread, its result applied
  /// on the frame it arrives with object masks rendered at the poses of the frame it was
  /// computed on). `detections` (optional): instances the caller detected on this very frame,
  /// applied like a detector result. Throws InvalidArgument naming the frame when its size or
  /// type is wrong.
  FrameOutcome process(const core::Frame& frame,
                       const std::vector<core::Detection>* detections = nullptr);
  const Eigen::Isometry3d& T_world_camera() const { return T_world_camera_; }
  map::Volume& background() { return *background_; }
  const map::Volume& background() const { return *background_; }
  map::VoxelPool& pool() { return *pool_; }
  const map::VoxelPool& pool() const { return *pool_; }
  const StageTimer& timer() const { return timer_; }
  /// Work per frame: "track_iterations" (the camera's LM iterations), "object_track_iterations"
  /// (summed over objects), "object_track_pixels" (the objects' tracking rectangles, summed),
  /// "integrated_blocks" (blocks integrated, all volumes).
  const FrameCounters& counters() const { return counters_; }
  /// The detector's counters (plugin empty when none is configured).
  DetectorStats detectorStats() const;
  /// Objects alive now, dormant ones included (as in the last FrameOutcome, without the deleted
  /// ones).
  std::vector<ObjectOutcome> objects() const;
  /// The volume of `id` (0 = background), or nullptr when no such object is alive or dormant.
  const map::Volume* volume(int id) const;
  /// What a ray cast of the current map renders (background id 0 first, then every rendered
  /// object with its id), for outputs and the C API's render call.
  std::vector<map::RenderItem> renderItems() const;
  /// The last E-step's association maps (blocking downloads, for outputs and images).
  struct Associations {
    std::vector<int> ids;    // volume ids: 0 = background, then objects
    std::vector<cv::Mat> q;  // CV_32F q per id
  };
  /// Empty when no E-step ran in the last frame (no objects and no detection) or the camera was
  /// lost on it (its E-step gave q_0 alone, at the camera tracker's pixels).
  Associations associations() const;
  /// Object ids ray-cast (frame size, the background occluding) to match the last detections
  /// (CV_32S, -1 none, 0 background); all -1 when no object was alive then, empty before the
  /// first detection. The visibility rule's own cast is smaller (objects.visibility_width).
  const cv::Mat& lastObjectIds() const { return objects_->lastObjectIds(); }
  /// Called with each object volume just before it is deleted (outputs save its mesh).
  void setDeletionHook(std::function<void(const TrackedObject&)> hook) {
    objects_->setDeletionHook(std::move(hook));
  }
  const core::Intrinsics& intrinsics() const { return intrinsics_; }
  int64_t framesProcessed() const { return frames_; }
  int64_t framesLost() const { return lost_; }
  /// Frames on which the background could not get a slot for every block it needed (its map is
  /// incomplete there: map.memory_mb is too small for the scene).
  int64_t backgroundPoolFullFrames() const { return background_pool_full_frames_; }
  /// The background's moves (map.follow_camera) and the blocks they took out of it, summed.
  int64_t backgroundShifts() const { return shifts_; }
  int64_t evictedBlocks() const { return evicted_blocks_; }
  /// Where the surface of evicted blocks waits until a background mesh is written (two unlinked
  /// temporary files, written by a worker thread: pipeline/evicted_surface.h; default the
  /// system's temporary folder). Set before the first frame.
  void setEvictedSurfaceFolder(const std::string& folder) { evicted_folder_ = folder; }
  /// The background mesh, world frame: the surface of every block the background left behind
  /// (after the worker has meshed all of it), then the current grid's (map::extractMesh),
  /// streamed to `sink` with indices from 0. Between frames only.
  void extractBackgroundMesh(map::MeshSink& sink) const;
  /// Objects not created because the pool had too little room (objects.min_free_pool_fraction).
  int64_t poolRefusedObjects() const { return objects_->poolRefusedObjects(); }
  /// The objects and their rules.
  const ObjectLifecycle& objectLifecycle() const { return *objects_; }

 private:
  // Whether the detector reads the SLAM's feedback images on this frame.
  bool feedbackDue(const core::Frame& frame) const;
  // Runs the detector schedule for this frame; the batch to apply now, if any.
  std::optional<DetectionBatch> runDetector(const core::Frame& frame);
  /// The detector's feedback images for this frame (detector_feedback.cpp): *q0 = how well the
  /// background explains each pixel, *residual = |psi| of the best-associated volume.
  void detectorFeedback(cv::Mat* q0, cv::Mat* residual);
  /// Signed background SDF (metres) at each valid vertex (CV_32FC4, camera frame); NaN where
  /// unobserved (weight < em.min_weight), outside the grid or invalid.
  cv::Mat backgroundSdf(const cv::Mat& vertex);
  /// The background's integration of this frame.
  map::AllocationReport integrateBackground(const map::IntegrationInput& in);
  /// map.follow_camera: moves the background to follow the camera, keeping what leaves it.
  void followCamera(FrameOutcome* out);

  cl::Context& ctx_;
  Config config_;
  core::Intrinsics intrinsics_;
  std::unique_ptr<map::VoxelPool> pool_;
  std::unique_ptr<map::Volume> background_;
  track::Preprocessor preprocessor_;
  track::Tracker tracker_;
  em::EStep estep_;
  StageTimer timer_;
  FrameCounters counters_;
  std::unique_ptr<ObjectLifecycle> objects_;
  std::unique_ptr<DetectorScheduler> scheduler_;  // null without a detector plugin
  // Background SDF probe for the detector feedback (allocated only with a detector).
  std::unique_ptr<map::SdfSampler> sdf_sampler_;
  cl::MemHandle probe_points_, probe_psi_, probe_weight_, probe_gradient_, probe_pfg_;
  Eigen::Isometry3d T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  // T_prev_curr of the last frame
  int64_t frames_ = 0;
  int64_t lost_ = 0;
  int64_t background_pool_full_frames_ = 0;  // frames on which background blocks found no slot
  map::FollowRule follow_;
  std::string evicted_folder_;
  std::unique_ptr<EvictedSurface> evicted_;  // created on the first move
  int64_t shifts_ = 0, evicted_blocks_ = 0;
};

}  // namespace emf::pipeline
