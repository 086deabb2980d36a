// Trajectory evaluation as the TUM RGB-D benchmark tools (evaluate_ate.py, evaluate_rpe.py) do
// it, for the camera and for objects. Camera trajectories are T_world_camera; object
// trajectories are T_object_camera (the camera's pose in the object's frame), so ATE with a
// rigid alignment does not depend on where each object's origin lies.
#pragma once

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/trajectory.h"

namespace emf::eval {

/// Summary of a list of errors (units of the errors). median as numpy (mean of the two middle
/// values for an even count); std is the population standard deviation.
struct ErrorStats {
  size_t count = 0;
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
};
ErrorStats errorStats(std::vector<double> errors);

/// Absolute trajectory error after a rigid (no scale) Horn/Umeyama alignment of the estimated
/// positions onto the associated ground-truth positions.
struct AteResult {
  size_t pairs = 0;
  ErrorStats trans_m;  // per-pair position error after alignment, metres
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  // applied to the estimate
  std::vector<double> gt_stamps;                               // per pair, seconds
  std::vector<double> errors_m;                                // per pair
  std::vector<Eigen::Vector3d> gt_positions, est_positions_aligned;
};

/// The minimum number of associated pairs for an ATE, as evaluate_ate.py (with 2 the rotation
/// about their line is free, which leaves the residuals unchanged).
constexpr size_t kMinAtePairs = 2;

/// ATE like evaluate_ate.py: association as associate.py within `max_diff_s`, alignment of the
/// estimate onto the ground truth (SVD of the cross-covariance, reflection-corrected). Throws
/// InvalidArgument when fewer than kMinAtePairs pairs associate.
AteResult computeAte(const io::Trajectory& gt, const io::Trajectory& est, double max_diff_s = 0.02);

/// Relative pose error with a fixed time delta, like evaluate_rpe.py --fixed_delta (without its
/// random subsampling above 10000 pairs): for each estimated pose i, j is the estimated pose
/// closest in time to t_i + delta (pairs whose j is the last pose are dropped); ground-truth
/// poses are the closest in time, and pairs whose ground truth is more than twice the median
/// ground-truth interval away are dropped. Error = (E_i^-1 E_j)^-1 (G_i^-1 G_j).
struct RpeResult {
  size_t pairs = 0;
  double delta_s = 0;
  ErrorStats trans_m;  // translational error, metres
  ErrorStats rot_deg;  // rotation angle of the error, degrees
};
/// Throws InvalidArgument when fewer than 2 pairs remain.
RpeResult computeRpe(const io::Trajectory& gt, const io::Trajectory& est, double delta_s = 1.0);

/// The three-cornered hat (as three clocks are compared): three trajectories of the same motion,
/// compared pairwise by their RPE over `delta_s`. When their errors per step are independent
/// with rms a, b and c, the pairwise RPE rms are sqrt(a^2 + b^2), sqrt(a^2 + c^2) and
/// sqrt(b^2 + c^2), so each trajectory's own share follows: a^2 = (ab^2 + ac^2 - bc^2) / 2, and
/// so on. A share whose square comes out negative (correlated errors, or an exact trajectory
/// with sampling noise in the others) is reported as 0. Used by bench/slam_bench to tell how
/// much of the step error against a ground truth is the ground truth's own. Only the poses
/// all three have (associated within `max_diff_s`) are compared, and the three RPEs use the
/// same pose pairs: for each common pose i, the next common pose j > i closest in time to
/// t_i + delta_s (a tracker that lost frames has gaps, which stretch a step). Throws
/// InvalidArgument when fewer than 3 poses are common.
struct ThreeCorneredHat {
  size_t common_poses = 0;  // poses that a, b and c all have
  RpeResult ab, ac, bc;     // the pairwise RPEs (the first trajectory of each pair as reference)
  double rot_deg[3] = {0, 0, 0};  // the own rms rotation error per step of a, b, c
  double trans_m[3] = {0, 0, 0};  // the own rms translation error per step of a, b, c
};
ThreeCorneredHat threeCorneredHat(const io::Trajectory& a, const io::Trajectory& b,
                                  const io::Trajectory& c, double delta_s,
                                  double max_diff_s = 0.02);

struct EvalOptions {
  double max_diff_s = 0.02;          // timestamp association, seconds
  double rpe_delta_s = 1.0;          // RPE time delta, seconds
  double min_object_coverage = 0.3;  // an estimate must cover this fraction of a GT object
};

/// The evaluation of one estimated trajectory against one ground-truth trajectory.
struct TrajectoryEval {
  std::string name;               // "camera", "object 2"
  std::string gt_file, est_file;  // est_file empty: no estimate matched
  size_t gt_poses = 0, est_poses = 0;
  double coverage = 0;  // fraction of GT timestamps with an associated estimate
  std::optional<AteResult> ate;
  std::optional<RpeResult> rpe;
  std::string note;  // why ate/rpe are missing, if they are
};

/// One candidate estimate considered for a ground-truth object.
struct ObjectCandidate {
  int est_id = 0;
  std::string est_file;
  double coverage = 0;
  std::optional<double> ate_rmse_m;  // when eligible (coverage and pair count sufficient)
};

struct ObjectEval {
  int gt_id = 0;
  std::optional<int> est_id;  // the matched estimate
  TrajectoryEval eval;
  std::vector<ObjectCandidate> candidates;
};

struct EvalReport {
  std::string gt_path, est_path;
  EvalOptions options;
  TrajectoryEval camera;
  std::vector<ObjectEval> objects;
  std::vector<int> unmatched_est_ids;  // estimated objects no ground-truth object chose
};

/// Evaluates one pair of trajectories (ATE, RPE, coverage). A missing ATE/RPE (too few pairs)
/// is recorded in `note` instead of throwing.
TrajectoryEval evaluateTrajectory(const std::string& name, const io::Trajectory& gt,
                                  const io::Trajectory& est, const EvalOptions& options);

/// Matches ground-truth objects to estimated objects one to one and evaluates each match. An
/// estimate is eligible for a ground-truth object when it covers at least
/// options.min_object_coverage of its timestamps; the eligible pairs are taken in order of
/// their ATE RMSE, each when neither its ground-truth object nor its estimate is taken yet
/// (greedy). A ground-truth object left without one has a note saying why.
std::vector<ObjectEval> evaluateObjects(
    const std::vector<std::pair<int, io::Trajectory>>& gts,
    const std::vector<std::pair<int, io::Trajectory>>& estimates, const EvalOptions& options);

/// evaluateObjects for one ground-truth object: the eligible estimate of lowest ATE RMSE.
ObjectEval evaluateObject(int gt_id, const io::Trajectory& gt,
                          const std::vector<std::pair<int, io::Trajectory>>& estimates,
                          const EvalOptions& options);

/// Evaluates paths as `emf eval` does. `gt_path`: a dataset folder (groundtruth.txt and
/// objects/gt-object-<k>-camera.txt) or a trajectory file. `est_path`: an emf output folder
/// (camera.txt and object-<id>.txt) or a trajectory file. Throws IoError for missing/bad files
/// and InvalidArgument when the camera trajectories do not associate.
EvalReport evaluatePaths(const std::string& gt_path, const std::string& est_path,
                         const EvalOptions& options);

/// A fixed-width table of the report (one line per trajectory).
std::string formatReport(const EvalReport& report);
/// The report as JSON (metres, degrees, seconds; see docs/evaluation.md).
nlohmann::json reportToJson(const EvalReport& report);
/// Draws the report: for the camera and every matched object, a top view of the ground truth
/// and the aligned estimate and the translational error over time. Written atomically as PNG.
void writeEvalPlot(const std::string& path, const EvalReport& report);

}  // namespace emf::eval
