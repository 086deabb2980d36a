// The per-frame SLAM loop (docs/method.md#per-frame) on one OpenCL device: preprocess the
// depth, track the camera against the background SDF by direct alignment, integrate the frame
// into the background volume. Everything the loop needs on the device (pool, volume grids,
// images) is allocated at construction; process() allocates nothing on the device.
//
// Frames: world W = the first camera's frame (T_world_camera of frame 0 is the identity); the
// background volume V is placed so that this camera sits at the centre of one face looking in
// (map.initial_camera_face_offset). Poses are T_a_b (maps points in b to a).
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "cl/context.h"
#include "common/config.h"
#include "em/estep.h"
#include "em/object_rules.h"
#include "io/frame.h"
#include "map/raycaster.h"
#include "map/volume.h"
#include "map/volume_view.h"
#include "map/voxel_pool.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/frame_counters.h"
#include "pipeline/stage_timer.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace emf::pipeline {

/// Life state of an object volume in one frame.
enum class ObjectState {
  kTracked,    // tracked and integrated this frame
  kLost,       // tracking failed this frame: pose kept, not integrated
  kInvisible,  // alive but hidden behind nearer surfaces (objects.hidden_fraction) or leaving
               // the view (objects.leaving_fraction): not tracked, pose held still in the world,
               // not integrated
  kDeleted,    // deleted in this frame (reported once, then gone)
  kDormant,    // deleted by a rule but its model kept (objects.reidentify_frames): not tracked,
               // integrated or rendered; a detection that fits it re-attaches it
};
const char* objectStateName(ObjectState state);

/// One object volume as the outputs and the C API see it.
struct ObjectOutcome {
  int id = 0;  // stable, > 0 (the background is volume 0)
  std::string class_name;
  ObjectState state = ObjectState::kTracked;
  /// The object's frame in the world: its volume frame at creation, which stays on the object
  /// when the volume grows (map::Volume::T_world_initial), so trajectories do not jump.
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_object_camera = Eigen::Isometry3d::Identity();  // camera in object frame
  double existence = 1.0;                                             // Ex / (Ex + NonEx)
  int64_t first_frame = 0, last_frame = 0;  // frames (SlamSystem indices) tracked
  bool rendered = true;                     // false for people (tracked, never rendered)
  std::string deleted_reason;               // set with kDeleted, and with kDormant: why
};

/// The poses of a tentative object (objects.confirm_detections) before it was confirmed: the
/// frames it was tracked on, for outputs to fill its trajectory in.
struct ConfirmedObject {
  int id = 0;
  std::string class_name;
  struct Pose {
    int64_t index = 0;     // SlamSystem frame index
    double timestamp = 0;  // seconds
    Eigen::Isometry3d T_object_camera = Eigen::Isometry3d::Identity();
  };
  std::vector<Pose> earlier;  // oldest first, before the frame of the FrameOutcome
};

/// How one detection of a frame was matched to the objects' ray-cast masks.
struct DetectionMatch {
  std::string class_name;
  int object_id = -1;    // the object it was matched to, -1 none (a candidate for a new object)
  int best_object = -1;  // the object whose mask overlaps it most, -1 none
  double best_iou = 0;   // that overlap (IoU with the object's mask)
};

/// What process() did with one frame.
struct FrameOutcome {
  int64_t index = 0;     // frames processed before this one
  double timestamp = 0;  // the frame's timestamp (seconds)
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // estimate (last good if lost)
  bool first = false;  // the first frame: placed, not tracked
  bool lost = false;   // tracking failed: the frame was not integrated
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

/// The preprocessing of the depth the E-step and the objects use (objects.filter_depth).
track::PreprocessOptions objectPreprocessOptions(const Config& config);

/// The tracking options for object volumes: the camera's (track section) with the object rules
/// below, objects.huber_truncation_factor and the rotation prior objects.motion_prior_rotation
/// (scaled from 640x480 to an image `image_width` pixels wide).
track::TrackOptions objectTrackOptions(const Config& config, int image_width);

/// The tracking options of the re-identification fits: objectTrackOptions without the motion
/// rules and the rotation prior (a fit starts from a guess).
track::TrackOptions reidTrackOptions(const Config& config, int image_width);

/// The device view of a volume that tracking and the E-step read.
map::VolumeDeviceView deviceView(const map::Volume& volume);

/// An object volume and its bookkeeping (docs/method.md#state).
struct TrackedObject {
  int id = 0;
  std::string class_name;
  bool rendered = true;  // false for people (tracked so they leave the background, not shown)
  std::unique_ptr<map::Volume> volume;  // object pose: volume->T_world_initial()
  /// Camera motion relative to the object over the last tracked frame, T_prev_curr (frame
  /// independent: unchanged when the volume grows). Predicts the next pose.
  Eigen::Isometry3d last_motion = Eigen::Isometry3d::Identity();
  em::Existence existence;
  int64_t first_frame = 0, last_frame = 0;
  ObjectState state = ObjectState::kTracked;
  int lost_frames = 0;  // consecutive frames its tracking failed (with the camera tracked)
  /// Hidden behind nearer surfaces in the last visibility check (objects.hidden_fraction): the
  /// next frame holds it instead of tracking it. hidden_frames: consecutive frames held.
  bool hidden = false;
  int hidden_frames = 0;
  /// Leaving the view in the last visibility check (objects.leaving_fraction): the next frame
  /// holds it too, but it stays subject to the invisibility and association rules.
  bool leaving = false;
  int pool_full_frames = 0;  // frames on which some of its blocks found no slot in the pool
  int e_step_slot = 0;       // index of this object in the current E-step (1..)
  /// Where the object claims pixels in the E-step (objects.claim_region), in its frame at
  /// creation (volume->T_world_initial(): growth does not move it). Empty: the whole volume.
  Eigen::AlignedBox3d claim_initial;
  /// Dormant (objects.reidentify_frames): since which frame, and the rule that retired it.
  int64_t dormant_since = -1;
  std::string dormant_reason;
  /// The frame a detection re-attached it (its E-step association of that frame is not its
  /// own: it is not integrated or judged by its association then).
  int64_t reattached_frame = -1;
  /// Tentative until objects.confirm_detections detections matched it: tracked and fused but not
  /// reported; `earlier` keeps its tracked poses for the outputs once it is confirmed.
  bool confirmed = true;
  std::vector<ConfirmedObject::Pose> earlier;
};

class SlamSystem {
 public:
  /// Stages timed per frame, in order.
  static const std::vector<std::string>& stageNames();

  /// Sets up the device state for frames of `intrinsics` (their size). Throws ConfigError /
  /// InvalidArgument for bad options or intrinsics, ClError for device failures.
  /// `source_uri` is passed to the detector plugin (config detector.plugin) if one is set.
  SlamSystem(cl::Context& ctx, const Config& config, const io::Intrinsics& intrinsics,
             const std::string& source_uri = "");
  ~SlamSystem();

  /// Processes one frame (depth CV_32F metres, NaN = invalid, of the intrinsics' size): the EM
  /// loop of docs/method.md#per-frame. The detector plugin of config detector.* (if any) runs on
  /// its schedule (sequential: every N-th frame, now; async: on its own thread, its result applied
  /// on the frame it arrives with object masks rendered at the poses of the frame it was
  /// computed on). `detections` (optional): instances the caller detected on this very frame,
  /// applied like a detector result. Throws InvalidArgument naming the frame when its size or
  /// type is wrong.
  FrameOutcome process(const io::Frame& frame,
                       const std::vector<io::Detection>* detections = nullptr);
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
    cv::Mat residual;        // CV_32F |psi| of the best volume (NaN none)
  };
  /// Empty when no E-step ran in the last frame (no objects and no detection).
  Associations associations() const;
  /// Object ids ray-cast (frame size, the background occluding) to match the last detections
  /// (CV_32S, -1 none, 0 background); all -1 when no object was alive then, empty before the
  /// first detection. The visibility rule's own cast is smaller (objects.visibility_width).
  const cv::Mat& lastObjectIds() const { return last_ids_; }
  /// Called with each object volume just before it is deleted (outputs save its mesh).
  void setDeletionHook(std::function<void(const TrackedObject&)> hook) {
    deletion_hook_ = std::move(hook);
  }
  const io::Intrinsics& intrinsics() const { return intrinsics_; }
  int64_t framesProcessed() const { return frames_; }
  int64_t framesLost() const { return lost_; }
  /// Frames on which the background could not get a slot for every block it needed (its map is
  /// incomplete there: map.memory_mb is too small for the scene).
  int64_t backgroundPoolFullFrames() const { return background_pool_full_frames_; }
  /// Objects not created because the pool had too little room (objects.min_free_pool_fraction).
  int64_t poolRefusedObjects() const { return pool_refused_objects_; }

 private:
  /// Per-frame helpers (object_lifecycle.cpp).
  // Volumes for the E-step: the background at T_world_camera, object k at T_oc[k].
  std::vector<em::EStepVolume> eStepVolumes(const Eigen::Isometry3d& T_world_camera,
                                            const std::vector<Eigen::Isometry3d>& T_oc);
  void trackObjects(const std::vector<Eigen::Isometry3d>& T_oc_predicted);
  void integrateAll();
  // Detection frame, before integration: match (ray-cast masks, IoU), existence counts,
  // foreground masks of the matched objects, growth. Keeps the unmatched detections.
  void matchDetections(const DetectionBatch& batch, FrameOutcome* out);
  // Runs the detector schedule for this frame; the batch to apply now, if any.
  std::optional<DetectionBatch> runDetector(const io::Frame& frame);
  /// The detector's feedback images for this frame (detector_feedback.cpp): *q0 = how well the
  /// background explains each pixel, *residual = |psi| of the best-associated volume.
  void detectorFeedback(cv::Mat* q0, cv::Mat* residual);
  /// Signed background SDF (metres) at each valid vertex (CV_32FC4, camera frame); NaN where
  /// unobserved (weight < em.min_weight), outside the grid or invalid.
  cv::Mat backgroundSdf(const cv::Mat& vertex);
  // Before integration: objects from the unmatched detections (each integrates this frame
  // weighted by its mask; the background then skips those pixels: created_mask_).
  void createObjects();
  bool createObject(const io::Detection& d, const cv::Mat& vertex);
  // After integration: delete objects whose existence probability fell too low.
  void deleteByExistence();
  // After integration: the visibility, association, lost and hidden rules on each object's own
  // ray cast at objects.visibility_width against `depth` (the frame's raw depth).
  void checkVisibility(const cv::Mat& depth);
  // Retires active object i for `reason`: dormant with objects.reidentify_frames, else deleted;
  // a tentative one is dropped unreported.
  void deleteObject(size_t i, const std::string& reason);
  // Confirms a tentative object once objects.confirm_detections detections matched it.
  void confirmIfDue(TrackedObject& o);
  // Deletes an object for good (the deletion hook, the outcome, the trackers' state).
  void eraseObject(TrackedObject& o, const std::string& reason);
  /// Re-identification (object_reid.cpp): fits the detection (its creation mask and points,
  /// camera frame) to the lost and the dormant objects' models; true when one fitted and was
  /// re-attached at the fitted pose.
  bool reattach(const io::Detection& d, const std::vector<Eigen::Vector3d>& points_camera);
  /// Dormant objects past objects.reidentify_frames, or beyond max_objects of them, or (oldest
  /// first) while the pool has less than objects.min_free_pool_fraction free, are deleted.
  void expireDormant();
  void fillObjectOutcomes(FrameOutcome* out) const;
  cv::Mat downloadVertexMap() const;  // of objectVertexMap()
  cl_mem objectVertexMap() const;     // what the E-step and the objects use

  cl::Context& ctx_;
  Config config_;
  io::Intrinsics intrinsics_;
  std::unique_ptr<map::VoxelPool> pool_;
  std::unique_ptr<map::Volume> background_;
  track::Preprocessor preprocessor_;
  track::Preprocessor object_preprocessor_;  // objects.filter_depth off: their own light filter
  track::Tracker tracker_;
  track::Tracker object_tracker_;  // objectTrackOptions(config, width)
  track::Tracker reid_tracker_;    // the re-identification fits (their own lost state)
  em::EStep estep_;
  map::RayCaster raycaster_;
  cl::MemHandle fg_mask_;      // p_fg of the matched detection per pixel (count updates)
  cl::MemHandle new_weights_;  // mask probability of a new object (its first integration)
  std::vector<TrackedObject> objects_;
  std::vector<TrackedObject> dormant_;  // oldest first (objects.reidentify_frames)
  cl::MemHandle reid_q_;                // a detection's mask as the fits' weights
  std::map<int, cv::Mat> pending_fg_;   // id -> detection p_fg (CV_32F, NaN = no update)
  std::vector<int> estep_ids_;          // volume ids of the last E-step (empty: none this frame)
  cv::Mat created_mask_;  // union of the masks of objects created this frame (or empty)
  std::vector<io::Detection> unmatched_;    // this frame's detections that matched nothing
  bool new_objects_only_ = false;           // they come from a detector of new things only (motion)
  std::vector<ObjectOutcome> deleted_now_;  // objects deleted in this frame
  std::vector<ConfirmedObject> confirmed_now_;  // objects confirmed in this frame
  double frame_timestamp_ = 0;                  // of the frame being processed
  cv::Mat last_ids_;  // object ids ray-cast for the last detection matching (frame size)
  // The visibility rule's ray cast: its image size (objects.visibility_width), its thresholds
  // scaled to that size, and the images of each object's cast (kept to reuse their buffers):
  // depth, ids, hidden pixels, and the frame's depth at that size.
  io::Intrinsics visibility_k_;
  em::ObjectOptions visibility_options_;
  cv::Mat visibility_depth_, visibility_ids_, hidden_mask_, visibility_measured_;
  io::Intrinsics wide_k_;  // the leaving test's cast (objects.leaving_fraction)
  cv::Rect wide_frame_;    // the frame's rectangle in it
  cv::Mat wide_ids_;
  int next_object_id_ = 1;
  std::function<void(const TrackedObject&)> deletion_hook_;
  std::unique_ptr<DetectorScheduler> scheduler_;  // null without a detector plugin
  // Background SDF probe for the detector feedback (allocated only with a detector).
  std::unique_ptr<map::SdfSampler> sdf_sampler_;
  cl::MemHandle probe_points_, probe_psi_, probe_weight_, probe_gradient_, probe_pfg_;
  StageTimer timer_;
  FrameCounters counters_;
  Eigen::Isometry3d T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  // T_prev_curr of the last frame
  int64_t frames_ = 0;
  int64_t lost_ = 0;
  int64_t background_pool_full_frames_ = 0;  // frames on which background blocks found no slot
  int64_t pool_refused_objects_ = 0;         // creations refused for want of pool room
};

}  // namespace emf::pipeline
