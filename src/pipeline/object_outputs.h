// Per-object outputs of a run, from the per-frame FrameOutcomes, in the run folder:
//   object-<id>.txt   TUM trajectory of T_object_camera (the camera's pose in the object's own
//                     frame = its volume frame at creation, unchanged when the volume grows) at
//                     the frames where the object was tracked; appended and flushed as the
//                     frames come (io::TrajectoryStream), so a killed run keeps them
//   object-<id>.ply   the object's mesh in that same frame, metres: place it in the world
//                     with T_world_object of the frame of interest (run.json has the last one);
//                     written when the object is deleted (onObjectDeleted) or at the end
//   images/<frame>-objects.png   colour image with the rendered object ids overlaid (optional)
//   images/<frame>-q<id>.png     association map q_id in false colour (optional)
// and a per-object summary (class, first/last frame, frames tracked, deleted why/when) that
// runSummaryJson puts into run.json.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "io/trajectory_stream.h"
#include "map/volume.h"
#include "pipeline/slam_system.h"

namespace emf::pipeline {

/// What run.json reports for one object.
struct ObjectSummary {
  int id = 0;
  std::string class_name;
  int64_t first_frame = -1, last_frame = -1;  // frames (SlamSystem indices) tracked; -1 = never
  double first_timestamp = 0, last_timestamp = 0;  // seconds, of those frames
  int64_t frames_tracked = 0, frames_lost = 0, frames_invisible = 0, frames_dormant = 0;
  bool deleted = false;        // false: alive at the end of the run
  int64_t deleted_frame = -1;  // frame in which it was deleted
  double deleted_timestamp = 0;
  std::string deleted_reason;
  double existence = 0;  // Ex / (Ex + NonEx) as last reported
  Eigen::Isometry3d T_world_object = Eigen::Isometry3d::Identity();  // as last reported
  std::string trajectory_file;  // name in the run folder ("" = not tracked in any frame)
  std::string mesh_file;        // name in the run folder ("" = not written)
};

/// One association map for the images: q of volume `id` (0 = background) per pixel.
struct AssociationImage {
  int id = 0;
  cv::Mat q;  // CV_32F in [0, 1], NaN = no data (drawn black)
};

/// Opacity of the object colours over the colour image in the overlay images.
constexpr double kOverlayAlpha = 0.5;

/// The overlay colour (BGR) of object `id` (> 0): hues spaced by the golden angle, so ids close
/// together get clearly different colours.
cv::Vec3b objectColor(int id);

/// `color` (CV_8UC3 BGR, resized to the ids' size if it differs; empty = black) with every pixel
/// whose id (CV_32S, <= 0 = background / nothing) is an object blended with objectColor(id):
/// out = (1 - kOverlayAlpha) * color + kOverlayAlpha * objectColor, rounded.
cv::Mat objectOverlay(const cv::Mat& color, const cv::Mat& object_ids);

/// `q` (CV_32F in [0, 1]) in false colour (OpenCV's JET colour map of round(255 q); NaN black).
cv::Mat associationFalseColor(const cv::Mat& q);

/// Accumulates per-object trajectories and summaries over a run and writes their files.
class ObjectOutputs {
 public:
  /// Outputs go into `dir` (created when the first file is written); PLY binary or ASCII;
  /// `run_id` (RunFolder::runId) goes into each trajectory's header.
  ObjectOutputs(std::string dir, bool binary_ply, std::string run_id = "");

  /// Records one frame's objects (call for every FrameOutcome, in order) and appends their
  /// poses to object-<id>.txt (created at an object's first pose, synced and closed when the
  /// object is deleted). Throws IoError when a trajectory cannot be written.
  void add(const FrameOutcome& outcome);
  /// Asks the disk to keep every trajectory written so far (fdatasync). Throws IoError.
  void sync();

  /// Writes object-<id>.ply from `volume` now: call before an object's volume is freed.
  /// Throws IoError when the file cannot be written.
  void onObjectDeleted(int id, const map::Volume& volume);
  /// Writes object-<id>.ply from a host view of the volume, streamed (vertices in the object's
  /// frame: the volume frame at creation, `T_volume_initial` as Volume::T_volume_initial()).
  void writeMesh(int id, const map::VolumeHostView& volume,
                 const Eigen::Isometry3d& T_volume_initial);

  /// Writes images/<index>-objects.png (overlay of `object_ids`, CV_32S, on `color`) and one
  /// images/<index>-q<id>.png per association map. Throws InvalidArgument naming the frame for
  /// images of the wrong type or size, IoError when a file cannot be written.
  void writeFrameImages(const FrameOutcome& outcome, const cv::Mat& color,
                        const cv::Mat& object_ids,
                        const std::vector<AssociationImage>& association);

  /// Writes object-<id>.ply for every object still alive whose volume `volume_of(id)` returns
  /// (nullptr = skip).
  void writeLiveMeshes(const std::function<const map::Volume*(int id)>& volume_of);
  /// End of the run (or an interrupted run): writeLiveMeshes, then syncs the trajectories.
  void finish(const std::function<const map::Volume*(int id)>& volume_of);

  /// Summaries of every object seen so far, by increasing id.
  std::vector<ObjectSummary> summaries() const;
  const std::string& dir() const { return dir_; }

  static std::string trajectoryName(int id);
  static std::string meshName(int id);
  /// images/<index, 6 digits>-<what>.png relative to the run folder.
  static std::string imageName(int64_t frame_index, const std::string& what);

 private:
  struct Track {
    ObjectSummary summary;
    std::unique_ptr<io::TrajectoryStream> T_object_camera;  // null until the first pose
  };
  void ensureDir(const std::string& dir) const;
  void appendPose(Track& track, double timestamp, const Eigen::Isometry3d& T_object_camera);

  std::string dir_;
  bool binary_ply_;
  std::string run_id_;
  std::map<int, Track> tracks_;
};

}  // namespace emf::pipeline
