// Trajectories in the TUM RGB-D format (`timestamp tx ty tz qx qy qz qw`, one pose per line,
// '#' comments) and timestamp association as the TUM benchmark's associate.py does it.
// A pose T_a_b maps points in frame b to frame a; a camera trajectory holds T_world_camera, an
// object trajectory T_object_camera (the camera's pose in the object's frame).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace emf::io {

/// Timestamped poses with strictly increasing timestamps (seconds).
struct Trajectory {
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d> poses;
  std::string source;  // file it was read from (for messages); may be empty

  size_t size() const { return stamps.size(); }
  bool empty() const { return stamps.empty(); }
  /// Appends a pose; throws InvalidArgument if `stamp` is not greater than the last one.
  void append(double stamp, const Eigen::Isometry3d& pose);
};

/// Pose from TUM fields (translation in metres, unit quaternion qx qy qz qw). The quaternion is
/// normalised; returns nullopt if its norm is not within 1 +- 0.01 (not a rotation).
std::optional<Eigen::Isometry3d> poseFromTum(double tx, double ty, double tz, double qx, double qy,
                                             double qz, double qw);

/// Reads a TUM trajectory file. Fields may be separated by spaces, tabs or commas (as the TUM
/// tools accept). A last line without its newline that does not parse (a writer killed
/// mid-line) is ignored with a warning. Throws IoError naming file:line for a missing file, a line
/// without 8 numbers, NaN/inf values, a non-unit quaternion or timestamps that do not increase.
Trajectory readTrajectory(const std::string& path);

/// Writes a TUM trajectory file atomically: "%.6f" timestamps, translations and quaternions
/// with 9 decimals (qw >= 0). `comment` (without '#') becomes the first line when not empty.
void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const std::string& comment = "");

/// One pose as a TUM line ("%.6f" timestamp, 9 decimals, unit quaternion with qw >= 0, '\n').
std::string tumLine(double stamp, const Eigen::Isometry3d& pose);
/// The comment lines a TUM file starts with: "# <comment>" (when not empty), then the column
/// names.
std::string tumHeader(const std::string& comment);

/// One associated pair: indices into the first and second timestamp lists.
struct StampMatch {
  size_t first = 0, second = 0;
};

/// Associates two timestamp lists like the TUM tool associate.py (offset 0): every pair with
/// |a - b| < max_diff_s is a candidate; candidates are taken greedily by increasing difference
/// (ties: smaller a, then smaller b), each timestamp used at most once; the result is sorted by
/// the first list's timestamp.
std::vector<StampMatch> associateStamps(const std::vector<double>& first,
                                        const std::vector<double>& second, double max_diff_s);

/// The pose at time `t`: linear/spherical interpolation between the two poses around `t` when
/// both are within `max_diff_s` of it, else the nearest pose when it is within `max_diff_s`,
/// else nullopt.
std::optional<Eigen::Isometry3d> poseAt(const Trajectory& trajectory, double t, double max_diff_s);

}  // namespace emf::io
