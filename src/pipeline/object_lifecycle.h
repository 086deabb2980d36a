// The objects of the SLAM (docs/method.md#per-frame): their volumes and bookkeeping, and every
// rule of their life, in SlamSystem::process's order: the E-step volumes, object tracking,
// detection matching (ray-cast masks, IoU), creation, re-identification, weighted integration,
// and deletion by existence, visibility, association, loss and hiding. The rules themselves
// are the pure functions of em/object_rules.h; the options they use are derived once
// (object_settings.h). SlamSystem owns the camera, the background and the frame loop, and
// hands each frame's camera pose in.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cl/context.h"
#include "core/frame.h"
#include "em/estep.h"
#include "em/object_rules.h"
#include "map/raycaster.h"
#include "map/volume.h"
#include "map/volume_view.h"
#include "map/voxel_pool.h"
#include "pipeline/config.h"
#include "pipeline/detector_scheduler.h"
#include "pipeline/frame_counters.h"
#include "pipeline/object_settings.h"
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
  /// The object it was matched to (by IoU, or as a mask spilled over it), -1 none.
  int object_id = -1;
  int best_object = -1;  // the object whose mask overlaps it most, -1 none
  double best_iou = 0;   // that overlap (IoU with the object's mask)
};

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
  /// Its tracked world poses of the last objects.still_frames frames (oldest first), and
  /// whether it is held still (em::looksStill).
  std::vector<Eigen::Isometry3d> recent_poses;
  bool still = false;
  std::vector<em::PoseChange> held_offsets;  // while still: the tracked poses' change from the held
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

  /// claim_initial in today's volume frame (growth shifts the grid by whole blocks); empty
  /// when the object claims its whole volume.
  Eigen::AlignedBox3d claimInVolume() const;
};

class ObjectLifecycle {
 public:
  /// `camera_preprocessor` gives the raw depth and (objects.filter_depth) the vertex map;
  /// `background` occludes the objects' masks; `estep` holds the association maps of every
  /// volume; `timer` and `counters` are the SlamSystem's.
  ObjectLifecycle(cl::Context& ctx, const Config& config, const core::Intrinsics& intrinsics,
                  map::VoxelPool& pool, const map::Volume& background,
                  const track::Preprocessor& camera_preprocessor, em::EStep& estep,
                  StageTimer& timer, FrameCounters& counters);

  const ObjectSettings& settings() const { return settings_; }

  // ---- one frame, in SlamSystem::process's order --------------------------------------------
  /// Starts frame `index` (SlamSystem's count) at `timestamp` (seconds): clears the per-frame
  /// state (E-step ids, pending masks, deletions, confirmations).
  void beginFrame(int64_t index, double timestamp);
  /// The objects' own depth filter (objects.filter_depth off), when the E-step or the object
  /// rules will read the vertex map this frame.
  void preprocess(const cv::Mat& depth, float frame_max_m);
  /// The vertex map the E-step and the objects use (the camera's with objects.filter_depth).
  cl_mem vertexMap() const;
  /// Each active object's pose T_object_volume_camera at the camera pose `T_world_camera`, with
  /// its last motion applied (`predicted`) or not.
  std::vector<Eigen::Isometry3d> posesInCamera(const Eigen::Isometry3d& T_world_camera,
                                               bool predicted) const;
  /// Volumes for the E-step: the background at T_world_camera, object k at T_oc[k]. Records the
  /// volume ids of this E-step (eStepIds()).
  std::vector<em::EStepVolume> eStepVolumes(const Eigen::Isometry3d& T_world_camera,
                                            const std::vector<Eigen::Isometry3d>& T_oc);
  /// The camera's pose and motion (T_prev_curr) of this frame, once it is tracked (or kept).
  void setCamera(const Eigen::Isometry3d& T_world_camera, const Eigen::Isometry3d& last_motion);
  /// E-step again at the tracked camera pose, then each object tracked from its prediction.
  /// `residual_everywhere`: the E-step's residual is wanted (the detector's feedback of this
  /// frame reads it; em::EStep::compute).
  void track(const std::vector<Eigen::Isometry3d>& T_oc_predicted, bool residual_everywhere);
  /// The camera was lost: every object is lost this frame, and the frame has no E-step
  /// (eStepIds() empty).
  void markAllLost();
  /// Detection frame, before integration: match (ray-cast masks, IoU), existence counts,
  /// foreground masks of the matched objects, growth. Keeps the unmatched detections.
  /// `matches`: one per usable detection; returns how many were usable.
  int matchDetections(const DetectionBatch& batch, std::vector<DetectionMatch>* matches);
  /// Objects from the unmatched detections, or re-attached lost and dormant ones (each
  /// integrates this frame weighted by its mask; the background then skips those pixels).
  void createObjects();
  /// The background's integration weights this frame: q_0 of the E-step with objects (or
  /// nullptr: weight 1), without the pixels of the objects created this frame.
  const cl::MemHandle* backgroundWeights();
  /// Integrates every tracked object with its association map, after the background.
  void integrate(const map::IntegrationInput& background_input);
  /// After integration: deletion by existence (on detection frames), the visibility,
  /// association, lost and hidden rules on each object's own ray cast against `depth` (the
  /// frame's raw depth), dormant objects expired.
  void applyRules(bool detector_ran, const cv::Mat& depth);
  /// Tentative objects keep their tracked poses for the outputs until they are confirmed.
  void keepTentativePoses();
  /// Objects confirmed in this frame, with their earlier poses (moved out).
  std::vector<ConfirmedObject> takeConfirmed();

  // ---- state ----------------------------------------------------------------------------------
  bool empty() const { return objects_.empty(); }
  /// Objects alive and dormant (confirmed only), plus those deleted this frame, by id.
  std::vector<ObjectOutcome> outcomes() const;
  /// The active objects' poses (for an async detector's late result).
  std::vector<ObjectPose> poses() const;
  /// The volume of object `id`, or nullptr when no such object is alive or dormant.
  const map::Volume* volume(int id) const;
  /// Every rendered object, for the ray casts of the outputs.
  void addRenderItems(std::vector<map::RenderItem>* items) const;
  /// Volume ids of this frame's E-step (0 = background, then objects); empty: none yet.
  const std::vector<int>& eStepIds() const { return estep_ids_; }
  /// Object ids ray-cast to match the last detections (SlamSystem::lastObjectIds).
  const cv::Mat& lastObjectIds() const { return last_ids_; }
  /// Called with each object volume just before it is deleted (outputs save its mesh).
  void setDeletionHook(std::function<void(const TrackedObject&)> hook) {
    deletion_hook_ = std::move(hook);
  }
  /// Objects not created because the pool had too little room (objects.min_free_pool_fraction).
  int64_t poolRefusedObjects() const { return pool_refused_objects_; }
  /// The vertex map (of vertexMap()), downloaded.
  cv::Mat downloadVertexMap() const;

 private:
  // The steps of matchDetections (object_matching.cpp).
  // Detections with a mask of the frame's size and a class, score and box the objects take.
  std::vector<const core::Detection*> usableDetections(
      const std::vector<core::Detection>& detections) const;
  // last_ids_: the objects' ids ray-cast at the detection's frame (the background occludes,
  // except where the frame's depth sees through it); downloads `vertex` when it needs it.
  void renderObjectIds(const DetectionBatch& batch, cv::Mat* vertex);
  // Each usable detection's object by mask IoU (-1: none); one report per detection.
  std::vector<int> matchByMasks(const std::vector<const core::Detection*>& usable,
                                std::vector<DetectionMatch>* matches) const;
  // A matched object takes its detection: existence count, confirmation, foreground mask,
  // claim region and volume growth.
  void takeDetection(TrackedObject& o, const core::Detection& d, cv::Mat* vertex);
  // Objects no detection matched: non-existence counts; tentative ones missed twice dropped.
  void countMisses(const std::vector<bool>& matched);

  // Still objects (em::looksStill): true when `o` is held at its pose this frame instead of
  // taking its tracked pose; keeps its recent poses. `fit_keeps_still(T_world_held)` evaluates
  // the frame at the held pose (em::fitKeepsStill), asked only when the pose rules release.
  bool holdStill(TrackedObject& o, const Eigen::Isometry3d& T_world_tracked,
                 const std::function<bool(const Eigen::Isometry3d&)>& fit_keeps_still);
  bool createObject(const core::Detection& d, const cv::Mat& vertex);
  void deleteByExistence();
  void checkVisibility(const cv::Mat& depth);
  // Mean q of object `o` over the pixels where `ids` (visibility size) shows it; downloads only
  // the rows of q that hold them when the visibility size divides the frame's.
  double visibleMeanAssociation(const TrackedObject& o, const cv::Mat& ids) const;
  // Retires active object i for `reason`: dormant with objects.reidentify_frames, else deleted;
  // a tentative one is dropped unreported.
  void deleteObject(size_t i, const std::string& reason);
  // Confirms a tentative object once objects.confirm_detections detections matched it.
  void confirmIfDue(TrackedObject& o);
  // Deletes an object for good (the deletion hook, the outcome, the trackers' state).
  void eraseObject(TrackedObject& o, const std::string& reason);
  /// Re-identification (object_reid.cpp): fits the detection (its creation mask and points,
  /// camera frame) to the lost and the dormant objects' models, or to `only` (a lost object
  /// that the detection matched); true when one fitted and was re-attached at the fitted pose.
  bool reattach(const core::Detection& d, const std::vector<Eigen::Vector3d>& points_camera,
                TrackedObject* only = nullptr);
  /// Dormant objects past objects.reidentify_frames, or beyond max_objects of them, or (oldest
  /// first) while the pool has less than objects.min_free_pool_fraction free, are deleted.
  void expireDormant();

  cl::Context& ctx_;
  Config config_;  // config_.objects: settings_.rules (pixel thresholds at the frame's size)
  ObjectSettings settings_;
  core::Intrinsics intrinsics_;
  map::VoxelPool& pool_;
  const map::Volume& background_;
  const track::Preprocessor& camera_preprocessor_;
  em::EStep& estep_;
  StageTimer& timer_;
  FrameCounters& counters_;
  track::Preprocessor object_preprocessor_;  // objects.filter_depth off: their own light filter
  track::Tracker object_tracker_;            // settings_.track
  track::Tracker reid_tracker_;              // the re-identification fits (their own lost state)
  map::RayCaster raycaster_;
  cl::MemHandle fg_mask_;      // p_fg of the matched detection per pixel (count updates)
  cl::MemHandle new_weights_;  // mask probability of a new object (its first integration)
  cl::MemHandle reid_q_;       // a detection's mask as the fits' weights
  std::vector<TrackedObject> objects_;
  std::vector<TrackedObject> dormant_;  // oldest first (objects.reidentify_frames)
  // The frame being processed: its index, timestamp and camera pose and motion (setCamera).
  int64_t frames_ = 0;
  double frame_timestamp_ = 0;
  Eigen::Isometry3d T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();
  // The scene's up direction, world frame (scene_up.h), from the first frame with a new detection
  // whose surfaces show it; until then the first camera's image up (-y).
  std::optional<Eigen::Vector3d> up_world_;
  std::map<int, cv::Mat> pending_fg_;  // id -> detection p_fg (CV_32F, NaN = no update)
  std::vector<int> estep_ids_;         // volume ids of the last E-step (empty: none this frame)
  cv::Mat created_mask_;  // union of the masks of objects created this frame (or empty)
  std::vector<core::Detection> unmatched_;  // this frame's detections that matched nothing
  bool new_objects_only_ = false;           // they come from a detector of new things only (motion)
  std::vector<ObjectOutcome> deleted_now_;  // objects deleted in this frame
  std::vector<ConfirmedObject> confirmed_now_;  // objects confirmed in this frame
  cv::Mat last_ids_;    // object ids ray-cast for the last detection matching (frame size)
  cv::Mat last_depth_;  // ... and the depth of that ray cast (camera z, m; NaN = none)
  // The images of each object's visibility cast (kept to reuse their buffers): depth, ids,
  // hidden pixels, the frame's depth at that size, and the leaving test's ids.
  cv::Mat visibility_depth_, visibility_ids_, hidden_mask_, visibility_measured_, wide_ids_;
  int next_object_id_ = 1;
  std::function<void(const TrackedObject&)> deletion_hook_;
  int64_t pool_refused_objects_ = 0;  // creations refused for want of pool room
};

}  // namespace emf::pipeline
