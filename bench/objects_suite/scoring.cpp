#include "objects_suite/scoring.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "eval/eval.h"

namespace emf::bench {
namespace {

std::optional<double> ate(const io::Trajectory& gt, const io::Trajectory& est) {
  if (gt.size() < eval::kMinAtePairs || est.size() < eval::kMinAtePairs) return std::nullopt;
  try {
    return eval::computeAte(gt, est).trans_m.rmse;
  } catch (const std::exception&) {
    return std::nullopt;  // too few associated pairs
  }
}

}  // namespace

bool isMoving(const GtObject& o) {
  if (o.T_world_object.empty()) return false;
  const Eigen::Isometry3d& first = o.T_world_object.front();
  const Eigen::Vector3d c = o.bounds.center();
  for (const auto& T : o.T_world_object) {
    if ((T * c - first * c).norm() > kMovingM) return true;
    if (Eigen::AngleAxisd(first.linear().transpose() * T.linear()).angle() >
        kMovingDeg * M_PI / 180.0) {
      return true;
    }
  }
  return false;
}

int labelFromMasks(const cv::Mat& rendered_ids, const cv::Mat& instance_ids, int id) {
  CV_Assert(rendered_ids.type() == CV_32S && instance_ids.type() == CV_16U &&
            rendered_ids.size() == instance_ids.size());
  std::map<int, int> under;
  int pixels = 0;
  for (int v = 0; v < rendered_ids.rows; ++v) {
    const int32_t* r = rendered_ids.ptr<int32_t>(v);
    const uint16_t* g = instance_ids.ptr<uint16_t>(v);
    for (int u = 0; u < rendered_ids.cols; ++u) {
      if (r[u] != id) continue;
      ++pixels;
      ++under[g[u]];
    }
  }
  if (pixels == 0) return -1;
  int best = 0, best_n = 0;
  for (const auto& [gt, n] : under) {
    if (gt != 0 && n > best_n) {
      best = gt;
      best_n = n;
    }
  }
  return best_n >= kLabelMinShare * pixels ? best : 0;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double x = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(x));
  const size_t j = std::min(i + 1, values.size() - 1);
  const double f = x - static_cast<double>(i);
  if (f == 0.0 || !std::isfinite(values[j])) return values[i];
  return values[i] + f * (values[j] - values[i]);
}

RunScore scoreRun(const RunRecord& run) {
  RunScore score;
  const size_t frames = run.stamps.size();
  // Camera ATE over the tracked frames.
  {
    io::Trajectory gt, est;
    for (size_t f = 0; f < frames; ++f) {
      gt.append(run.stamps[f], run.T_world_camera_gt[f]);
      if (f < run.T_world_camera.size() && run.T_world_camera[f]) {
        est.append(run.stamps[f], *run.T_world_camera[f]);
      }
    }
    score.camera_ate_m = ate(gt, est);
  }
  // Label every estimate.
  std::vector<int> label_of(run.est.size(), 0);
  for (size_t e = 0; e < run.est.size(); ++e) {
    const EstObject& est = run.est[e];
    std::map<int, int> votes;
    int voting = 0;
    for (int label : est.labels) {
      if (label < 0) continue;
      ++votes[label];
      ++voting;
    }
    int best = 0, best_votes = -1;
    for (const auto& [id, n] : votes) {
      if (n > best_votes) {
        best = id;
        best_votes = n;
      }
    }
    label_of[e] = best;
    int strong = 0;
    for (const auto& [id, n] : votes) {
      if (id != 0 && n >= 0.2 * static_cast<double>(voting)) ++strong;
    }
    if (strong >= 2) ++score.id_switches;
    if (best == 0 && !est.frames.empty()) score.spurious_ids.push_back(est.id);
    score.lost_object_frames += est.lost_frames;
  }

  for (const GtObject& o : run.gt) {
    ObjectScore s;
    s.gt_id = o.id;
    s.class_name = o.class_name;
    s.motion = o.motion;
    s.moving = isMoving(o);
    std::vector<size_t> visible;
    io::Trajectory gt;
    for (size_t f = 0; f < frames && f < o.visible.size(); ++f) {
      if (!o.visible[f]) continue;
      visible.push_back(f);
      gt.append(run.stamps[f], o.T_world_object[f].inverse() * run.T_world_camera_gt[f]);
    }
    s.visible_frames = static_cast<int>(visible.size());
    std::vector<const EstObject*> mine;
    for (size_t e = 0; e < run.est.size(); ++e) {
      if (label_of[e] == o.id && !run.est[e].frames.empty()) mine.push_back(&run.est[e]);
    }
    std::sort(mine.begin(), mine.end(), [](const EstObject* a, const EstObject* b) {
      return a->frames.front() < b->frames.front();
    });
    s.estimates = static_cast<int>(mine.size());
    std::vector<bool> covered(frames, false);
    double best_ate = 1e300;
    for (size_t k = 0; k < mine.size(); ++k) {
      const EstObject& est = *mine[k];
      if (k > 0) {
        // Re-created in view: visible on most frames since the previous estimate ended.
        const int64_t from = mine[k - 1]->frames.back(), to = est.frames.front();
        int seen = 0, span = 0;
        for (int64_t f = std::max<int64_t>(0, from); f <= to && f < static_cast<int64_t>(frames);
             ++f, ++span) {
          if (o.visible[static_cast<size_t>(f)]) ++seen;
        }
        if (span > 0 && seen >= kInViewFraction * span) ++s.recreated_in_view;
      }
      int hits = 0;
      io::Trajectory tr;
      for (size_t i = 0; i < est.frames.size(); ++i) {
        const size_t f = static_cast<size_t>(est.frames[i]);
        if (f < frames && o.visible[f]) {
          ++hits;
          covered[f] = true;
        }
        tr.append(run.stamps[f], est.T_object_camera[i]);
      }
      const double coverage = visible.empty() ? 0.0 : static_cast<double>(hits) / visible.size();
      if (coverage < kMinCoverage) continue;
      const std::optional<double> a = ate(gt, tr);
      if (a && *a < best_ate) {
        best_ate = *a;
        s.est_id = est.id;
        s.ate_m = a;
        s.coverage = coverage;
      }
    }
    int any = 0;
    for (size_t f : visible) any += covered[f] ? 1 : 0;
    s.union_coverage = visible.empty() ? 0.0 : static_cast<double>(any) / visible.size();
    score.objects.push_back(s);
  }
  score.ms_median = quantile(run.ms_per_frame, 0.5);
  score.ms_p90 = quantile(run.ms_per_frame, 0.9);
  return score;
}

}  // namespace emf::bench
