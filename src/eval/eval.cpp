#include "eval/eval.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <numeric>
#include <regex>
#include <utility>

#include "common/error.h"

namespace emf::eval {
namespace fs = std::filesystem;

ErrorStats errorStats(std::vector<double> errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  const double n = static_cast<double>(errors.size());
  double sum = 0, sum_sq = 0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  std::sort(errors.begin(), errors.end());
  s.min = errors.front();
  s.max = errors.back();
  const size_t mid = errors.size() / 2;
  s.median = errors.size() % 2 ? errors[mid] : 0.5 * (errors[mid - 1] + errors[mid]);
  return s;
}

AteResult computeAte(const io::Trajectory& gt, const io::Trajectory& est, double max_diff_s) {
  const auto matches = io::associateStamps(gt.stamps, est.stamps, max_diff_s);
  for (const io::Trajectory* t : {&gt, &est}) {
    if (t->size() < kMinAtePairs) {
      throw InvalidArgument(
          "'" + t->source + "' has " +
          (t->empty() ? std::string("no poses") : "only " + std::to_string(t->size()) + " pose") +
          "; an ATE needs at least " + std::to_string(kMinAtePairs) +
          (t == &est && t->empty()
               ? " (an emf run stopped before its first tracked frame writes an empty camera.txt)"
               : ""));
    }
  }
  if (matches.size() < kMinAtePairs) {
    throw InvalidArgument(
        "only " + std::to_string(matches.size()) + " timestamps of '" + est.source + "' (" +
        std::to_string(est.size()) + " poses) are within " + std::to_string(max_diff_s) +
        " s of '" + gt.source + "' (" + std::to_string(gt.size()) + " poses); need at least " +
        std::to_string(kMinAtePairs) + ": do both files use the same clock / the right files?");
  }
  const size_t n = matches.size();
  Eigen::Matrix3Xd model(3, n), data(3, n);  // model = estimate, data = ground truth
  AteResult r;
  r.pairs = n;
  for (size_t k = 0; k < n; ++k) {
    model.col(static_cast<Eigen::Index>(k)) = est.poses[matches[k].second].translation();
    data.col(static_cast<Eigen::Index>(k)) = gt.poses[matches[k].first].translation();
    r.gt_stamps.push_back(gt.stamps[matches[k].first]);
  }
  // Horn's method as evaluate_ate.py's align(): W = sum model_c data_c^T, SVD of W^T.
  const Eigen::Vector3d model_mean = model.rowwise().mean();
  const Eigen::Vector3d data_mean = data.rowwise().mean();
  const Eigen::Matrix3Xd model_c = model.colwise() - model_mean;
  const Eigen::Matrix3Xd data_c = data.colwise() - data_mean;
  const Eigen::Matrix3d W = model_c * data_c.transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(W.transpose(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (U.determinant() * V.determinant() < 0) S(2, 2) = -1;
  const Eigen::Matrix3d R = U * S * V.transpose();
  const Eigen::Vector3d t = data_mean - R * model_mean;
  r.T_gt_est.linear() = R;
  r.T_gt_est.translation() = t;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d aligned = R * model.col(static_cast<Eigen::Index>(k)) + t;
    r.est_positions_aligned.push_back(aligned);
    r.gt_positions.push_back(data.col(static_cast<Eigen::Index>(k)));
    r.errors_m.push_back((aligned - data.col(static_cast<Eigen::Index>(k))).norm());
  }
  r.trans_m = errorStats(r.errors_m);
  return r;
}

namespace {

constexpr double kDegPerRad = 57.29577951308232;

// evaluate_rpe.py's find_closest_index(), literally (a binary search that keeps the closest
// element seen; ties go to the first one visited).
size_t findClosestIndex(const std::vector<double>& L, double t) {
  size_t beginning = 0, end = L.size(), best = 0;
  double difference = std::abs(L[0] - t);
  while (beginning < end) {
    const size_t middle = (end + beginning) / 2;
    if (std::abs(L[middle] - t) < difference) {
      difference = std::abs(L[middle] - t);
      best = middle;
    }
    if (t == L[middle]) return middle;
    if (L[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

double medianOf(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t mid = v.size() / 2;
  return v.size() % 2 ? v[mid] : 0.5 * (v[mid - 1] + v[mid]);
}

/// The relative pose error of one pair as evaluate_rpe.py computes it: translation norm
/// (metres) and rotation angle (degrees) of (E_i^-1 E_j)^-1 (G_i^-1 G_j), appended.
void addRelativeError(const Eigen::Isometry3d& est_i, const Eigen::Isometry3d& est_j,
                      const Eigen::Isometry3d& gt_i, const Eigen::Isometry3d& gt_j,
                      std::vector<double>* trans, std::vector<double>* rot) {
  const Eigen::Isometry3d est_rel = est_j.inverse() * est_i;
  const Eigen::Isometry3d gt_rel = gt_j.inverse() * gt_i;
  const Eigen::Isometry3d error = est_rel.inverse() * gt_rel;
  trans->push_back(error.translation().norm());
  const double c = std::min(1.0, std::max(-1.0, (error.linear().trace() - 1.0) / 2.0));
  rot->push_back(std::acos(c) * kDegPerRad);
}

RpeResult rpeResult(std::vector<double> trans, std::vector<double> rot, double delta_s) {
  RpeResult r;
  r.pairs = trans.size();
  r.delta_s = delta_s;
  r.trans_m = errorStats(std::move(trans));
  r.rot_deg = errorStats(std::move(rot));
  return r;
}

}  // namespace

RpeResult computeRpe(const io::Trajectory& gt, const io::Trajectory& est, double delta_s) {
  if (gt.size() < 2 || est.size() < 2) {
    throw InvalidArgument("RPE needs at least 2 poses in each trajectory ('" + gt.source +
                          "' has " + std::to_string(gt.size()) + ", '" + est.source + "' " +
                          std::to_string(est.size()) + ")");
  }
  // Trajectory stamps are strictly increasing, i.e. already the sorted key lists of the tool.
  const std::vector<double>& stamps_gt = gt.stamps;
  const std::vector<double>& stamps_est = est.stamps;
  std::vector<double> gt_intervals;
  for (size_t k = 1; k < stamps_gt.size(); ++k) {
    gt_intervals.push_back(stamps_gt[k] - stamps_gt[k - 1]);
  }
  const double gt_max_time_difference = 2 * medianOf(gt_intervals);

  std::vector<double> trans, rot;
  for (size_t i = 0; i < stamps_est.size(); ++i) {
    const size_t j = findClosestIndex(stamps_est, stamps_est[i] + delta_s);
    if (j == stamps_est.size() - 1) continue;
    const size_t g0 = findClosestIndex(stamps_gt, stamps_est[i]);
    const size_t g1 = findClosestIndex(stamps_gt, stamps_est[j]);
    if (std::abs(stamps_gt[g0] - stamps_est[i]) > gt_max_time_difference ||
        std::abs(stamps_gt[g1] - stamps_est[j]) > gt_max_time_difference) {
      continue;
    }
    addRelativeError(est.poses[i], est.poses[j], gt.poses[g0], gt.poses[g1], &trans, &rot);
  }
  if (trans.size() < 2) {
    throw InvalidArgument("RPE: only " + std::to_string(trans.size()) + " pose pairs " +
                          std::to_string(delta_s) + " s apart in '" + est.source +
                          "' have ground truth in '" + gt.source + "'; need at least 2");
  }
  return rpeResult(std::move(trans), std::move(rot), delta_s);
}

ThreeCorneredHat threeCorneredHat(const io::Trajectory& a, const io::Trajectory& b,
                                  const io::Trajectory& c, double delta_s, double max_diff_s) {
  // The poses all three have (a and b associated, then b's matched stamps with c), so that
  // the three RPEs compare the same pose pairs.
  const std::vector<io::StampMatch> ab = io::associateStamps(a.stamps, b.stamps, max_diff_s);
  std::vector<double> b_matched;
  for (const io::StampMatch& m : ab) b_matched.push_back(b.stamps[m.second]);
  const std::vector<io::StampMatch> bc = io::associateStamps(b_matched, c.stamps, max_diff_s);
  io::Trajectory common[3];
  for (int i = 0; i < 3; ++i) common[i].source = (i == 0 ? a : i == 1 ? b : c).source;
  for (const io::StampMatch& m : bc) {
    const io::StampMatch& first = ab[m.first];
    common[0].append(a.stamps[first.first], a.poses[first.first]);
    common[1].append(b.stamps[first.second], b.poses[first.second]);
    common[2].append(c.stamps[m.second], c.poses[m.second]);
  }
  // Pairs (i, j) of common poses, j > i the one closest to t_i + delta_s (a gap in the
  // common poses stretches a step; evaluate_rpe.py's closest index may be i itself there).
  std::vector<std::pair<size_t, size_t>> pairs;
  const std::vector<double>& t = common[1].stamps;
  for (size_t i = 0; i + 1 < t.size(); ++i) {
    const size_t j = std::max(i + 1, findClosestIndex(t, t[i] + delta_s));
    pairs.emplace_back(i, j);
  }
  if (pairs.size() < 2) {
    throw InvalidArgument("three-cornered hat: only " + std::to_string(common[0].size()) +
                          " poses are common to '" + a.source + "', '" + b.source + "' and '" +
                          c.source + "'; need at least 3");
  }
  const auto rpe = [&](const io::Trajectory& ref, const io::Trajectory& est) {
    std::vector<double> trans, rot;
    for (const auto& [i, j] : pairs) {
      addRelativeError(est.poses[i], est.poses[j], ref.poses[i], ref.poses[j], &trans, &rot);
    }
    return rpeResult(std::move(trans), std::move(rot), delta_s);
  };
  ThreeCorneredHat h;
  h.common_poses = common[0].size();
  h.ab = rpe(common[0], common[1]);
  h.ac = rpe(common[0], common[2]);
  h.bc = rpe(common[1], common[2]);
  const auto share = [](double with_first, double with_second, double between_others) {
    const double sq =
        (with_first * with_first + with_second * with_second - between_others * between_others) / 2;
    return std::sqrt(std::max(0.0, sq));
  };
  h.rot_deg[0] = share(h.ab.rot_deg.rmse, h.ac.rot_deg.rmse, h.bc.rot_deg.rmse);
  h.rot_deg[1] = share(h.ab.rot_deg.rmse, h.bc.rot_deg.rmse, h.ac.rot_deg.rmse);
  h.rot_deg[2] = share(h.ac.rot_deg.rmse, h.bc.rot_deg.rmse, h.ab.rot_deg.rmse);
  h.trans_m[0] = share(h.ab.trans_m.rmse, h.ac.trans_m.rmse, h.bc.trans_m.rmse);
  h.trans_m[1] = share(h.ab.trans_m.rmse, h.bc.trans_m.rmse, h.ac.trans_m.rmse);
  h.trans_m[2] = share(h.ac.trans_m.rmse, h.bc.trans_m.rmse, h.ab.trans_m.rmse);
  return h;
}

TrajectoryEval evaluateTrajectory(const std::string& name, const io::Trajectory& gt,
                                  const io::Trajectory& est, const EvalOptions& options) {
  TrajectoryEval e;
  e.name = name;
  e.gt_file = gt.source;
  e.est_file = est.source;
  e.gt_poses = gt.size();
  e.est_poses = est.size();
  const size_t matched = io::associateStamps(gt.stamps, est.stamps, options.max_diff_s).size();
  e.coverage = gt.empty() ? 0.0 : static_cast<double>(matched) / static_cast<double>(gt.size());
  try {
    e.ate = computeAte(gt, est, options.max_diff_s);
  } catch (const InvalidArgument& ex) {
    e.note = std::string("no ATE: ") + ex.what();
  }
  try {
    e.rpe = computeRpe(gt, est, options.rpe_delta_s);
  } catch (const InvalidArgument& ex) {
    e.note += std::string(e.note.empty() ? "" : "; ") + "no RPE: " + ex.what();
  }
  return e;
}

std::vector<ObjectEval> evaluateObjects(
    const std::vector<std::pair<int, io::Trajectory>>& gts,
    const std::vector<std::pair<int, io::Trajectory>>& estimates, const EvalOptions& options) {
  // Every candidate of every ground-truth object, with its ATE where it is eligible.
  std::vector<ObjectEval> out(gts.size());
  std::vector<double> best_coverage(gts.size(), 0.0);
  struct Eligible {
    double ate_rmse_m;
    size_t gt, est;
  };
  std::vector<Eligible> eligible;
  for (size_t g = 0; g < gts.size(); ++g) {
    const io::Trajectory& gt = gts[g].second;
    out[g].gt_id = gts[g].first;
    for (size_t e = 0; e < estimates.size(); ++e) {
      const io::Trajectory& est = estimates[e].second;
      ObjectCandidate c;
      c.est_id = estimates[e].first;
      c.est_file = est.source;
      const size_t matched = io::associateStamps(gt.stamps, est.stamps, options.max_diff_s).size();
      c.coverage = gt.empty() ? 0.0 : static_cast<double>(matched) / static_cast<double>(gt.size());
      best_coverage[g] = std::max(best_coverage[g], c.coverage);
      if (c.coverage >= options.min_object_coverage && matched >= kMinAtePairs) {
        c.ate_rmse_m = computeAte(gt, est, options.max_diff_s).trans_m.rmse;
        eligible.push_back({*c.ate_rmse_m, g, e});
      }
      out[g].candidates.push_back(c);
    }
  }
  // One estimate per ground-truth object and vice versa: the pairs in order of ATE, each taken
  // when neither side is taken yet. (Scored as T_object_camera, any still estimate fits any still
  // object perfectly, so without this one estimate could be credited to several objects.)
  std::stable_sort(eligible.begin(), eligible.end(), [](const Eligible& a, const Eligible& b) {
    return a.ate_rmse_m < b.ate_rmse_m;
  });
  std::vector<bool> gt_taken(gts.size(), false), est_taken(estimates.size(), false);
  std::vector<std::optional<size_t>> match(gts.size());
  for (const Eligible& p : eligible) {
    if (gt_taken[p.gt] || est_taken[p.est]) continue;
    gt_taken[p.gt] = est_taken[p.est] = true;
    match[p.gt] = p.est;
  }
  for (size_t g = 0; g < gts.size(); ++g) {
    const io::Trajectory& gt = gts[g].second;
    const std::string name = "object " + std::to_string(gts[g].first);
    ObjectEval& o = out[g];
    if (match[g]) {
      o.est_id = estimates[*match[g]].first;
      o.eval = evaluateTrajectory(name, gt, estimates[*match[g]].second, options);
      continue;
    }
    o.eval.name = name;
    o.eval.gt_file = gt.source;
    o.eval.gt_poses = gt.size();
    const bool had_eligible = std::any_of(o.candidates.begin(), o.candidates.end(),
                                          [](const ObjectCandidate& c) { return c.ate_rmse_m; });
    // Its coverage: the best of all candidates when none was eligible (what the note explains),
    // else the best among the estimates still free (those taken belong to other objects).
    o.eval.coverage = had_eligible ? 0.0 : best_coverage[g];
    for (size_t e = 0; had_eligible && e < estimates.size(); ++e) {
      if (!est_taken[e]) o.eval.coverage = std::max(o.eval.coverage, o.candidates[e].coverage);
    }
    char text[200];
    if (had_eligible) {
      std::snprintf(text, sizeof(text),
                    "every estimated object covering %.0f%% of its %zu timestamps fits another "
                    "ground-truth object better (one estimate per object)",
                    options.min_object_coverage * 100, gt.size());
    } else {
      std::snprintf(text, sizeof(text),
                    "no estimated object covers %.0f%% of its %zu timestamps (best %.1f%%)",
                    options.min_object_coverage * 100, gt.size(), best_coverage[g] * 100);
    }
    o.eval.note = gt.empty()          ? "the ground truth has no poses (the object is never "
                                        "in view in these frames); nothing to match"
                  : estimates.empty() ? "no estimated objects"
                                      : text;
  }
  return out;
}

ObjectEval evaluateObject(int gt_id, const io::Trajectory& gt,
                          const std::vector<std::pair<int, io::Trajectory>>& estimates,
                          const EvalOptions& options) {
  return evaluateObjects({{gt_id, gt}}, estimates, options).front();
}

namespace {

// `<dir>/<files matching re>` by the integer of the first capture group.
std::map<int, std::string> numberedTrajectories(const fs::path& dir, const std::regex& re) {
  std::map<int, std::string> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (!std::regex_match(name, m, re)) continue;
    const std::string digits = m[1].str();
    if (digits.size() > 9) {
      throw IoError("'" + entry.path().string() + "': id " + digits +
                    " is too large (ids are below 10^9); rename or remove the file");
    }
    const int id = std::stoi(digits);
    const auto [it, inserted] = out.emplace(id, entry.path().string());
    if (!inserted) {
      throw IoError("'" + entry.path().string() + "' and '" + it->second + "' both have id " +
                    std::to_string(id) + "; remove one of them");
    }
  }
  return out;
}

}  // namespace

EvalReport evaluatePaths(const std::string& gt_path, const std::string& est_path,
                         const EvalOptions& options) {
  EvalReport report;
  report.gt_path = gt_path;
  report.est_path = est_path;
  report.options = options;
  if (!fs::exists(gt_path)) throw IoError("ground truth '" + gt_path + "' does not exist");
  if (!fs::exists(est_path)) throw IoError("estimate '" + est_path + "' does not exist");

  const bool gt_dir = fs::is_directory(gt_path), est_dir = fs::is_directory(est_path);
  const std::string gt_camera_file =
      gt_dir ? (fs::path(gt_path) / "groundtruth.txt").string() : gt_path;
  const std::string est_camera_file =
      est_dir ? (fs::path(est_path) / "camera.txt").string() : est_path;
  if (!fs::exists(gt_camera_file)) {
    throw IoError("ground-truth folder '" + gt_path + "' has no groundtruth.txt");
  }
  if (!fs::exists(est_camera_file)) {
    throw IoError("estimate folder '" + est_path +
                  "' has no camera.txt (an emf output folder "
                  "has camera.txt and object-<id>.txt)");
  }
  const io::Trajectory gt_camera = io::readTrajectory(gt_camera_file);
  const io::Trajectory est_camera = io::readTrajectory(est_camera_file);
  report.camera = evaluateTrajectory("camera", gt_camera, est_camera, options);
  if (!report.camera.ate) {
    throw InvalidArgument("camera: " + report.camera.note.substr(std::string("no ATE: ").size()));
  }

  if (!gt_dir) return report;
  const auto gt_objects = numberedTrajectories(fs::path(gt_path) / "objects",
                                               std::regex(R"(gt-object-(\d+)-camera\.txt)"));
  std::vector<std::pair<int, io::Trajectory>> estimates;
  if (est_dir) {
    for (const auto& [id, file] :
         numberedTrajectories(est_path, std::regex(R"(object-(\d+)\.txt)"))) {
      estimates.emplace_back(id, io::readTrajectory(file));
    }
  }
  std::vector<std::pair<int, io::Trajectory>> gts;
  for (const auto& [k, file] : gt_objects) gts.emplace_back(k, io::readTrajectory(file));
  report.objects = evaluateObjects(gts, estimates, options);
  std::vector<int> chosen;
  for (const ObjectEval& o : report.objects) {
    if (o.est_id) chosen.push_back(*o.est_id);
  }
  for (const auto& [id, est] : estimates) {
    if (std::find(chosen.begin(), chosen.end(), id) == chosen.end()) {
      report.unmatched_est_ids.push_back(id);
    }
  }
  return report;
}

std::string formatReport(const EvalReport& report) {
  std::vector<const TrajectoryEval*> rows = {&report.camera};
  for (const auto& o : report.objects) rows.push_back(&o.eval);
  auto estName = [](const TrajectoryEval& e) {
    return e.est_file.empty() ? std::string("-") : fs::path(e.est_file).filename().string();
  };
  int est_w = 8;
  for (const auto* e : rows) est_w = std::max(est_w, static_cast<int>(estName(*e).size()));
  std::string out;
  char line[1024];
  std::snprintf(line, sizeof(line), "%-10s %-*s %6s %7s %9s %9s %9s %9s %6s %10s %9s\n",
                "trajectory", est_w, "estimate", "pairs", "cover", "ATE rmse", "mean", "median",
                "max", "RPE n", "RPE trans", "RPE rot");
  out += line;
  std::snprintf(line, sizeof(line), "%-10s %-*s %6s %7s %9s %9s %9s %9s %6s %10s %9s\n", "", est_w,
                "", "", "[%]", "[m]", "[m]", "[m]", "[m]", "", "rmse [m]", "rmse[deg]");
  out += line;
  for (const auto* e : rows) {
    const std::string est = estName(*e);
    if (!e->ate) {
      std::snprintf(line, sizeof(line), "%-10s %-*s %6s %6.1f%%  %s\n", e->name.c_str(), est_w,
                    est.c_str(), "-", e->coverage * 100, e->note.c_str());
      out += line;
      continue;
    }
    const ErrorStats& a = e->ate->trans_m;
    std::snprintf(line, sizeof(line), "%-10s %-*s %6zu %6.1f%% %9.6f %9.6f %9.6f %9.6f",
                  e->name.c_str(), est_w, est.c_str(), e->ate->pairs, e->coverage * 100, a.rmse,
                  a.mean, a.median, a.max);
    out += line;
    if (e->rpe) {
      std::snprintf(line, sizeof(line), " %6zu %10.6f %9.6f\n", e->rpe->pairs, e->rpe->trans_m.rmse,
                    e->rpe->rot_deg.rmse);
    } else {
      std::snprintf(line, sizeof(line), " %6s %10s %9s\n", "-", "-", "-");
    }
    out += line;
  }
  if (!report.unmatched_est_ids.empty()) {
    out += "estimated objects matched to no ground-truth object:";
    for (int id : report.unmatched_est_ids) out += " " + std::to_string(id);
    out += "\n";
  }
  return out;
}

namespace {

nlohmann::json statsJson(const ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},   {"min", s.min},   {"max", s.max}};
}

nlohmann::json trajectoryJson(const TrajectoryEval& e) {
  nlohmann::json j = {{"name", e.name},           {"gt_file", e.gt_file},
                      {"est_file", e.est_file},   {"gt_poses", e.gt_poses},
                      {"est_poses", e.est_poses}, {"coverage", e.coverage}};
  if (e.ate) {
    j["ate_m"] = statsJson(e.ate->trans_m);
    j["ate_m"]["pairs"] = e.ate->pairs;
  } else {
    j["ate_m"] = nullptr;
  }
  if (e.rpe) {
    j["rpe"] = {{"pairs", e.rpe->pairs},
                {"delta_s", e.rpe->delta_s},
                {"trans_m", statsJson(e.rpe->trans_m)},
                {"rot_deg", statsJson(e.rpe->rot_deg)}};
  } else {
    j["rpe"] = nullptr;
  }
  if (!e.note.empty()) j["note"] = e.note;
  return j;
}

}  // namespace

nlohmann::json reportToJson(const EvalReport& report) {
  nlohmann::json j;
  j["gt"] = report.gt_path;
  j["est"] = report.est_path;
  j["options"] = {{"max_diff_s", report.options.max_diff_s},
                  {"rpe_delta_s", report.options.rpe_delta_s},
                  {"min_object_coverage", report.options.min_object_coverage}};
  j["camera"] = trajectoryJson(report.camera);
  j["objects"] = nlohmann::json::array();
  for (const auto& o : report.objects) {
    nlohmann::json oj = trajectoryJson(o.eval);
    oj["gt_id"] = o.gt_id;
    oj["est_id"] = o.est_id ? nlohmann::json(*o.est_id) : nlohmann::json(nullptr);
    oj["candidates"] = nlohmann::json::array();
    for (const auto& c : o.candidates) {
      oj["candidates"].push_back(
          {{"est_id", c.est_id},
           {"est_file", c.est_file},
           {"coverage", c.coverage},
           {"ate_rmse_m", c.ate_rmse_m ? nlohmann::json(*c.ate_rmse_m) : nlohmann::json()}});
    }
    j["objects"].push_back(oj);
  }
  j["unmatched_est_ids"] = report.unmatched_est_ids;
  return j;
}

}  // namespace emf::eval
