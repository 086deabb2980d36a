// Scoring of one run of the objects suite (bench/objects_suite): which ground-truth object
// each estimated object is, how often an object was split into several estimates, the
// spurious estimates, and per object the ATE and coverage as `emf eval` computes them.
//
// Each frame an estimate was tracked is labelled with the ground-truth object its mask (the
// SLAM's ray cast of its model at its pose, the background in front where it is nearer) covers
// most: the true instance under at least kLabelMinShare of its pixels, else 0 (nothing); frames
// it renders no pixel on do not vote (labelFromMasks). An estimate is the object most of its
// voting frames are labelled with; spurious when that is 0.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/trajectory.h"

namespace emf::bench {

constexpr double kLabelMinShare = 0.3;
/// A ground-truth object counts as moving when its box centre moves more than this, or it
/// turns more than kMovingDeg, over the run.
constexpr double kMovingM = 0.02;
constexpr double kMovingDeg = 2.0;
/// emf eval's eligibility: an estimate must cover this fraction of the object's visible frames.
constexpr double kMinCoverage = 0.3;
/// A new estimate of an object counts as a re-creation in view when the object was visible on
/// at least this fraction of the frames between its previous estimate's last tracked frame and
/// the new one's first.
constexpr double kInViewFraction = 0.9;

/// One ground-truth object over a run: poses and visibility per frame (indices into the run's
/// frames).
struct GtObject {
  int id = 0;
  std::string class_name;
  std::string motion;          // the scene's motion families ("still", "rock+push", ...)
  Eigen::AlignedBox3d bounds;  // its parts' box in its own frame, metres
  std::vector<Eigen::Isometry3d> T_world_object;  // per frame
  std::vector<bool> visible;                      // per frame
};

/// One estimated object as the SLAM reported it: the frames it was tracked on.
struct EstObject {
  int id = 0;
  std::string class_name;
  std::vector<int64_t> frames;                     // tracked frames, increasing
  std::vector<Eigen::Isometry3d> T_object_camera;  // per tracked frame
  std::vector<int> labels;  // per tracked frame: labelFromMasks (-1: rendered no pixel)
  int64_t lost_frames = 0;  // frames its tracking failed
};

/// Everything one run produced, per frame.
struct RunRecord {
  std::vector<double> stamps;                                    // seconds
  std::vector<Eigen::Isometry3d> T_world_camera_gt;              // ground truth
  std::vector<std::optional<Eigen::Isometry3d>> T_world_camera;  // estimate (none: lost)
  std::vector<GtObject> gt;
  std::vector<EstObject> est;
  std::vector<double> ms_per_frame;
};

struct ObjectScore {
  int gt_id = 0;
  std::string class_name, motion;
  bool moving = false;
  int visible_frames = 0;
  int estimates = 0;            // estimates that are this object
  int recreated_in_view = 0;    // ... created while it had stayed in view since the last ended
  std::optional<int> est_id;    // the matched estimate (emf eval's rule among its own)
  std::optional<double> ate_m;  // its ATE (RMSE after rigid alignment)
  double coverage = 0;          // its share of the visible frames (0 when none matched)
  double union_coverage = 0;    // share of the visible frames any of its estimates tracked
};

struct RunScore {
  std::optional<double> camera_ate_m;
  std::vector<ObjectScore> objects;
  std::vector<int> spurious_ids;  // estimates that are no ground-truth object
  int id_switches = 0;            // estimates labelled with two objects, each >= 20 % of frames
  int64_t lost_object_frames = 0;
  double ms_median = 0, ms_p90 = 0;
};

/// Whether a ground-truth object moves over the run (kMovingM, kMovingDeg).
bool isMoving(const GtObject& object);

/// The label of estimate `id` in one frame: `rendered_ids` (CV_32S, the SLAM's ray cast: object
/// ids > 0) against `instance_ids` (CV_16U ground truth, same size): the instance under most of
/// its pixels when that is at least kLabelMinShare of them (0 = the static scene counts as
/// nothing), -1 when it renders no pixel.
int labelFromMasks(const cv::Mat& rendered_ids, const cv::Mat& instance_ids, int id);

/// Scores a run (see the file comment).
RunScore scoreRun(const RunRecord& run);

/// Quantile q in [0, 1] of `values` (linear interpolation between order statistics, as numpy);
/// 0 for an empty list. Infinite values sort last.
double quantile(std::vector<double> values, double q);

}  // namespace emf::bench
