#include "io/trajectory.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <tuple>

#include "common/error.h"
#include "common/log.h"
#include "io/atomic_output.h"
#include "io/text_table.h"

namespace emf::io {

void Trajectory::append(double stamp, const Eigen::Isometry3d& pose) {
  if (!stamps.empty() && !(stamp > stamps.back())) {
    throw InvalidArgument("trajectory timestamps must increase: " + std::to_string(stamp) +
                          " after " + std::to_string(stamps.back()));
  }
  stamps.push_back(stamp);
  poses.push_back(pose);
}

std::optional<Eigen::Isometry3d> poseFromTum(double tx, double ty, double tz, double qx, double qy,
                                             double qz, double qw) {
  Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= 0.01)) return std::nullopt;
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return T;
}

/// Positions farther from the origin than this (metres) are not a camera trajectory.
constexpr double kMaxCoordinateM = 1e6;

namespace {

// Whether the file's last byte is a newline (true for an empty or unreadable file).
bool endsWithNewline(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return true;
  bool newline = true;
  if (std::fseek(f, -1, SEEK_END) == 0) newline = std::fgetc(f) == '\n';
  std::fclose(f);
  return newline;
}

// Parses one row and appends its pose; throws IoError naming file:line.
void appendRow(Trajectory& traj, const TableRow& row, const std::string& path);

}  // namespace

Trajectory readTrajectory(const std::string& path) {
  Trajectory traj;
  traj.source = path;
  const std::vector<TableRow> rows = readTable(path, /*commas_separate=*/true);
  // A process killed while appending (emf run streams its trajectories) can leave the last line
  // cut short, without its newline: if that line does not parse, it is that, not a bad file.
  const bool unfinished_last = !rows.empty() && !endsWithNewline(path);
  for (size_t r = 0; r < rows.size(); ++r) {
    const TableRow& row = rows[r];
    if (unfinished_last && r + 1 == rows.size()) {
      try {
        appendRow(traj, row, path);  // appends only after every check passed
      } catch (const IoError&) {
        logWarning(fileLine(path, row.line),
                   ": an unfinished last line (a write that was interrupted); ignored");
      }
      break;
    }
    appendRow(traj, row, path);
  }
  return traj;
}

namespace {

void appendRow(Trajectory& traj, const TableRow& row, const std::string& path) {
  expectFields(row, 8, path, "timestamp tx ty tz qx qy qz qw");
  double v[8];
  static const char* kNames[8] = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  for (int i = 0; i < 8; ++i) v[i] = parseFinite(row.fields[i], path, row.line, kNames[i]);
  for (int i = 1; i <= 3; ++i) {
    // Squared in the statistics: 1e308 would turn every figure into inf.
    if (std::abs(v[i]) > kMaxCoordinateM) {
      throw IoError(fileLine(path, row.line) + ": " + kNames[i] + " = " + row.fields[i] +
                    " m is beyond +-" + std::to_string(static_cast<int>(kMaxCoordinateM)) +
                    " m: not a camera position; fix or remove that line");
    }
  }
  const auto pose = poseFromTum(v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
  if (!pose) {
    const double n = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7]);
    throw IoError(fileLine(path, row.line) + ": quaternion (qx qy qz qw) has norm " +
                  std::to_string(n) + ", not 1: not a rotation; fix or remove that line");
  }
  if (!traj.empty() && !(v[0] > traj.stamps.back())) {
    throw IoError(fileLine(path, row.line) + ": timestamp " + row.fields[0] +
                  " does not increase (previous line has " + std::to_string(traj.stamps.back()) +
                  "); sort the file and remove duplicates");
  }
  traj.stamps.push_back(v[0]);
  traj.poses.push_back(*pose);
}

}  // namespace

std::string tumLine(double stamp, const Eigen::Isometry3d& T) {
  // Normalised: a rotation composed over many frames drifts from orthonormal by round-off,
  // and readers (ours included) reject quaternions whose norm is not 1.
  Eigen::Quaterniond q(T.rotation());
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d t = T.translation();
  char line[256];
  std::snprintf(line, sizeof(line), "%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", stamp, t.x(),
                t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  return line;
}

std::string tumHeader(const std::string& comment) {
  std::string out;
  if (!comment.empty()) out += "# " + comment + "\n";
  return out + "# timestamp tx ty tz qx qy qz qw\n";
}

void writeTrajectory(const std::string& path, const Trajectory& trajectory,
                     const std::string& comment) {
  std::string out = tumHeader(comment);
  for (size_t i = 0; i < trajectory.size(); ++i) {
    out += tumLine(trajectory.stamps[i], trajectory.poses[i]);
  }
  writeFileAtomically(path, out);
}

std::vector<StampMatch> associateStamps(const std::vector<double>& first,
                                        const std::vector<double>& second, double max_diff_s) {
  // Sorted views of the second list for a windowed candidate search (the lists need not be
  // sorted; associate.py works on dictionaries).
  std::vector<size_t> order2(second.size());
  for (size_t j = 0; j < order2.size(); ++j) order2[j] = j;
  std::sort(order2.begin(), order2.end(),
            [&](size_t a, size_t b) { return second[a] < second[b]; });
  std::vector<double> sorted2(second.size());
  for (size_t j = 0; j < order2.size(); ++j) sorted2[j] = second[order2[j]];

  struct Candidate {
    double diff, a, b;
    size_t i, j;
  };
  std::vector<Candidate> candidates;
  for (size_t i = 0; i < first.size(); ++i) {
    const double a = first[i];
    auto it = std::lower_bound(sorted2.begin(), sorted2.end(), a - max_diff_s);
    for (; it != sorted2.end() && *it <= a + max_diff_s; ++it) {
      const double diff = std::abs(a - *it);
      if (diff < max_diff_s) {
        const size_t k = static_cast<size_t>(it - sorted2.begin());
        candidates.push_back({diff, a, *it, i, order2[k]});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.diff, x.a, x.b) < std::tie(y.diff, y.a, y.b);
  });
  std::vector<bool> used1(first.size(), false), used2(second.size(), false);
  std::vector<StampMatch> matches;
  for (const Candidate& c : candidates) {
    if (used1[c.i] || used2[c.j]) continue;
    used1[c.i] = used2[c.j] = true;
    matches.push_back({c.i, c.j});
  }
  std::sort(matches.begin(), matches.end(), [&](const StampMatch& x, const StampMatch& y) {
    return std::tie(first[x.first], second[x.second]) < std::tie(first[y.first], second[y.second]);
  });
  return matches;
}

std::optional<Eigen::Isometry3d> poseAt(const Trajectory& trajectory, double t, double max_diff_s) {
  const auto& s = trajectory.stamps;
  if (s.empty()) return std::nullopt;
  const size_t hi = static_cast<size_t>(std::lower_bound(s.begin(), s.end(), t) - s.begin());
  if (hi < s.size() && s[hi] == t) return trajectory.poses[hi];
  const bool has_lo = hi > 0 && t - s[hi - 1] <= max_diff_s;
  const bool has_hi = hi < s.size() && s[hi] - t <= max_diff_s;
  if (has_lo && has_hi) {
    const double w = (t - s[hi - 1]) / (s[hi] - s[hi - 1]);
    const Eigen::Isometry3d& A = trajectory.poses[hi - 1];
    const Eigen::Isometry3d& B = trajectory.poses[hi];
    const Eigen::Quaterniond qa(A.rotation()), qb(B.rotation());
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = qa.slerp(w, qb).toRotationMatrix();
    T.translation() = (1.0 - w) * A.translation() + w * B.translation();
    return T;
  }
  if (has_lo) return trajectory.poses[hi - 1];
  if (has_hi) return trajectory.poses[hi];
  return std::nullopt;
}

}  // namespace emf::io
