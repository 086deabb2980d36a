// The per-frame SLAM loop (METHOD.md steps 1-4 and 7) on one OpenCL device: preprocess the
// depth, track the camera against the background SDF by direct alignment, integrate the frame
// into the background volume. Everything the loop needs on the device (pool, volume grids,
// images) is allocated at construction; process() allocates nothing on the device.
//
// Frames: world W = the first camera's frame (T_world_camera of frame 0 is the identity); the
// background volume V is placed so that this camera sits at the centre of one face looking in
// (map.initial_camera_face_offset). Poses are T_a_b (maps points in b to a).
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "cl/context.h"
#include "common/config.h"
#include "io/frame.h"
#include "map/raycaster.h"
#include "map/volume.h"
#include "map/volume_view.h"
#include "map/voxel_pool.h"
#include "pipeline/stage_timer.h"
#include "track/preprocess.h"
#include "track/tracker.h"

namespace emf::pipeline {

/// Life state of an object volume in one frame.
enum class ObjectState {
  kTracked,    // tracked and integrated this frame
  kLost,       // tracking failed this frame: pose kept, not integrated
  kInvisible,  // alive but not seen this frame (rendered too few pixels)
  kDeleted,    // deleted in this frame (reported once, then gone)
};
const char* objectStateName(ObjectState state);

/// One object volume as the outputs and the C API see it.
struct ObjectOutcome {
  int id = 0;  // stable, > 0 (the background is volume 0)
  std::string class_name;
  ObjectState state = ObjectState::kTracked;
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();   // volume frame in world
  Eigen::Isometry3d T_object_camera = Eigen::Isometry3d::Identity();  // camera in volume frame
  double existence = 1.0;                                             // Ex / (Ex + NonEx)
  int64_t first_frame = 0, last_frame = 0;  // frames (SlamSystem indices) tracked
  bool rendered = true;                     // false for people (tracked, never rendered)
  std::string deleted_reason;               // set with kDeleted
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
  /// Objects alive after this frame, plus those deleted in it (state kDeleted), by id.
  std::vector<ObjectOutcome> objects;
  bool detector_ran = false;  // detections were applied this frame
  int detections = 0;         // detections used this frame
};

/// The device view of a volume that tracking and the E-step read.
map::VolumeDeviceView deviceView(const map::Volume& volume);

class SlamSystem {
 public:
  /// Stages timed per frame, in order.
  static const std::vector<std::string>& stageNames();

  /// Sets up the device state for frames of `intrinsics` (their size). Throws ConfigError /
  /// InvalidArgument for bad options or intrinsics, ClError for device failures.
  /// `source_uri` is passed to the detector plugin (config detector.plugin) if one is set.
  SlamSystem(cl::Context& ctx, const Config& config, const io::Intrinsics& intrinsics,
             const std::string& source_uri = "");

  /// Processes one frame (depth CV_32F metres, NaN = invalid, of the intrinsics' size). Throws
  /// InvalidArgument naming the frame when its size or type is wrong.
  FrameOutcome process(const io::Frame& frame);

  const Eigen::Isometry3d& T_world_camera() const { return T_world_camera_; }
  map::Volume& background() { return *background_; }
  const map::Volume& background() const { return *background_; }
  map::VoxelPool& pool() { return *pool_; }
  const map::VoxelPool& pool() const { return *pool_; }
  const StageTimer& timer() const { return timer_; }
  /// Objects alive now (as in the last FrameOutcome, without the deleted ones).
  std::vector<ObjectOutcome> objects() const;
  /// The volume of `id` (0 = background), or nullptr when no such object is alive.
  const map::Volume* volume(int id) const;
  /// What a ray cast of the current map renders (background id 0 first, then every rendered
  /// object with its id), for outputs and the C API's render call.
  std::vector<map::RenderItem> renderItems() const;
  const io::Intrinsics& intrinsics() const { return intrinsics_; }
  int64_t framesProcessed() const { return frames_; }
  int64_t framesLost() const { return lost_; }

 private:
  cl::Context& ctx_;
  Config config_;
  io::Intrinsics intrinsics_;
  std::unique_ptr<map::VoxelPool> pool_;
  std::unique_ptr<map::Volume> background_;
  track::Preprocessor preprocessor_;
  track::Tracker tracker_;
  StageTimer timer_;
  Eigen::Isometry3d T_world_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  // T_prev_curr of the last frame
  int64_t frames_ = 0;
  int64_t lost_ = 0;
};

}  // namespace emf::pipeline
