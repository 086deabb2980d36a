#include "synth/motion_plan.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "common/error.h"

namespace emf::synth {
namespace {

constexpr double kTwoPi = 6.283185307179586;

Eigen::Matrix3d expSo3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

/// 0 at both ends of [0, d], rising to 1 over ramp at each end (smootherstep).
double window(double tau, double d, double ramp) {
  if (ramp <= 0.0) return 1.0;
  return smootherstep(tau / ramp) * smootherstep((d - tau) / ramp);
}

/// A drive precomputed as distance along the loop per time step.
struct DriveTable {
  std::vector<Eigen::Vector2d> points;  // the loop sampled at equal parameter steps (closed)
  std::vector<double> length;           // cumulative arc length at each point
  std::vector<double> distance;         // distance driven at each time step
  double dt = 1.0 / 240.0;
  double s0 = 0.0;  // arc length of the start parameter

  Eigen::Vector2d at(double s, Eigen::Vector2d* tangent) const {
    const double total = length.back();
    s = std::fmod(s0 + s, total);
    if (s < 0) s += total;
    const auto it = std::upper_bound(length.begin(), length.end(), s);
    const size_t i1 = std::min(static_cast<size_t>(it - length.begin()), length.size() - 1);
    const size_t i0 = i1 > 0 ? i1 - 1 : 0;
    const double span = length[i1] - length[i0];
    const double f = span > 0 ? (s - length[i0]) / span : 0.0;
    *tangent = (points[i1] - points[i0]).normalized();
    return (1.0 - f) * points[i0] + f * points[i1];
  }
};

}  // namespace

MotionPlan::MotionPlan(const Eigen::Isometry3d& start) : first_pose_(start), end_pose_(start) {}

void MotionPlan::add(
    double duration_s,
    std::function<Eigen::Isometry3d(const Eigen::Isometry3d& start, double tau)> at) {
  duration_s = std::max(duration_s, 1e-3);
  Action a{end_s_, end_s_ + duration_s, end_pose_, std::move(at)};
  end_pose_ = a.at(a.start, duration_s);
  end_s_ = a.t1;
  actions_.push_back(std::move(a));
}

void MotionPlan::rest(double duration_s) {
  add(duration_s, [](const Eigen::Isometry3d& start, double) { return start; });
}

void MotionPlan::move(double duration_s, const Eigen::Vector3d& delta_m,
                      const Eigen::Vector3d& delta_rad, const Eigen::Vector3d& pivot_object) {
  add(duration_s, [=](const Eigen::Isometry3d& start, double tau) {
    const double u = smootherstep(tau / duration_s);
    const Eigen::Matrix3d R = expSo3(u * delta_rad);
    const Eigen::Vector3d pivot = start * pivot_object;
    Eigen::Isometry3d T = start;
    T.linear() = R * start.linear();
    T.translation() = pivot + R * (start.translation() - pivot) + u * delta_m;
    return T;
  });
}

void MotionPlan::rotateAbout(double duration_s, const Eigen::Vector3d& pivot_world,
                             const Eigen::Vector3d& axis_world, double angle_rad) {
  add(duration_s, [=](const Eigen::Isometry3d& start, double tau) {
    const double u = smootherstep(tau / duration_s);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(u * angle_rad, axis_world).toRotationMatrix();
    Eigen::Isometry3d T = start;
    T.linear() = R * start.linear();
    T.translation() = pivot_world + R * (start.translation() - pivot_world);
    return T;
  });
}

void MotionPlan::oscillate(double duration_s, const Eigen::Vector3d& axis_object,
                           double amplitude_rad, double frequency_hz, double ramp_s,
                           double roll_radius_m) {
  add(duration_s, [=](const Eigen::Isometry3d& start, double tau) {
    const double theta =
        amplitude_rad * window(tau, duration_s, ramp_s) * std::sin(kTwoPi * frequency_hz * tau);
    Eigen::Isometry3d T = start;
    T.linear() = start.linear() * Eigen::AngleAxisd(theta, axis_object).toRotationMatrix();
    T.translation() +=
        start.linear() * axis_object.cross(Eigen::Vector3d::UnitZ()) * (roll_radius_m * theta);
    return T;
  });
}

void MotionPlan::drift(double duration_s, const Eigen::Vector3d& amplitude_m,
                       const Eigen::Vector3d& amplitude_rad, const Eigen::Vector3d& frequency_hz,
                       const Eigen::Vector3d& phase_rad, double ramp_s) {
  add(duration_s, [=](const Eigen::Isometry3d& start, double tau) {
    const double w = window(tau, duration_s, ramp_s);
    Eigen::Vector3d dp, dr;
    for (int k = 0; k < 3; ++k) {
      const double arg = kTwoPi * frequency_hz[k] * tau + phase_rad[k];
      dp[k] = w * amplitude_m[k] * std::sin(arg);
      dr[k] = w * amplitude_rad[k] * std::sin(arg + 1.0);
    }
    Eigen::Isometry3d T = start;
    T.linear() = start.linear() * expSo3(dr);
    T.translation() += dp;
    return T;
  });
}

void MotionPlan::drive(double duration_s, const std::function<Eigen::Vector2d(double)>& curve,
                       double u0, double max_speed_mps, double max_yaw_rate,
                       const std::vector<Eigen::Vector2d>& stops) {
  if (!(duration_s > 0.0)) {
    throw InvalidArgument("MotionPlan::drive: duration " + std::to_string(duration_s) +
                          " s; a drive needs a positive duration");
  }
  auto table = std::make_shared<DriveTable>();
  constexpr int kSamples = 2048;
  for (int i = 0; i <= kSamples; ++i) {
    table->points.push_back(curve(static_cast<double>(i) / kSamples));
    table->length.push_back(
        i == 0 ? 0.0 : table->length.back() + (table->points[i] - table->points[i - 1]).norm());
  }
  {
    // Arc length of u0.
    const double x = u0 * kSamples;
    const int i = std::clamp(static_cast<int>(x), 0, kSamples - 1);
    table->s0 = table->length[i] + (x - i) * (table->length[i + 1] - table->length[i]);
  }
  // The speed limit along the loop from its curvature (yaw rate = speed x curvature), taken
  // as the minimum over the next and last 0.2 m so the object slows before a bend.
  const double total = table->length.back();
  constexpr int kBins = 512;
  std::vector<double> limit(kBins, max_speed_mps);
  for (int b = 0; b < kBins; ++b) {
    const double s = total * b / kBins, ds = 0.02;
    Eigen::Vector2d t0, t1;
    table->at(s - table->s0 - ds, &t0);
    table->at(s - table->s0 + ds, &t1);
    const double turn = std::atan2(t0.x() * t1.y() - t0.y() * t1.x(), t0.dot(t1));
    const double curvature = std::fabs(turn) / (2 * ds);
    limit[b] = curvature > 1e-9 ? std::min(max_speed_mps, max_yaw_rate / curvature) : max_speed_mps;
  }
  std::vector<double> smoothed(kBins);
  const int reach = std::max(1, static_cast<int>(0.2 / total * kBins));
  for (int b = 0; b < kBins; ++b) {
    double m = limit[b];
    for (int k = -reach; k <= reach; ++k) m = std::min(m, limit[((b + k) % kBins + kBins) % kBins]);
    smoothed[b] = m;
  }
  // Integrate the distance with the stops, a 1 s start and end ramp and 0.6 m/s^2 at most.
  const double dt = table->dt, accel = 0.6, ramp = 1.0;
  double s = 0.0, v = 0.0;
  for (double t = 0.0; t <= duration_s + dt; t += dt) {
    table->distance.push_back(s);
    double g = window(t, duration_s, ramp);
    for (const auto& w : stops) {
      const double in = smootherstep((t - (w.x() - 0.5)) / 0.5);
      const double out = smootherstep(((w.y() + 0.5) - t) / 0.5);
      g *= 1.0 - std::min(in, out);
    }
    const double pos = std::fmod(table->s0 + s, total);
    const int bin = std::clamp(static_cast<int>(pos / total * kBins), 0, kBins - 1);
    const double target = smoothed[bin] * g;
    v += std::clamp(target - v, -accel * dt, accel * dt);
    v = std::max(0.0, v);
    s += v * dt;
  }
  add(duration_s, [table](const Eigen::Isometry3d& start, double tau) {
    const double x = tau / table->dt;
    const size_t i = std::min(static_cast<size_t>(x), table->distance.size() - 2);
    const double f = std::clamp(x - static_cast<double>(i), 0.0, 1.0);
    const double driven = (1.0 - f) * table->distance[i] + f * table->distance[i + 1];
    Eigen::Vector2d tangent;
    const Eigen::Vector2d p = table->at(driven, &tangent);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(std::atan2(tangent.y(), tangent.x()), Eigen::Vector3d::UnitZ())
                     .toRotationMatrix();
    T.translation() = Eigen::Vector3d(p.x(), p.y(), start.translation().z());
    return T;
  });
  // The object waits for the drive where it starts: the rests before it take that pose.
  const Eigen::Isometry3d first = actions_.back().at(actions_.back().start, 0.0);
  for (auto& a : actions_) a.start = first;
  first_pose_ = first;
  end_pose_ = actions_.back().at(first, duration_s);
}

Eigen::Isometry3d MotionPlan::pose(double t) const {
  if (actions_.empty() || t <= 0.0) return actions_.empty() ? first_pose_ : actions_[0].start;
  for (const auto& a : actions_) {
    if (t < a.t1) return a.at(a.start, std::max(0.0, t - a.t0));
  }
  return end_pose_;
}

std::vector<PoseKey> MotionPlan::sample(double until_s, double rate_hz) const {
  std::vector<PoseKey> keys;
  const int n = static_cast<int>(std::ceil(until_s * rate_hz));
  for (int i = 0; i <= n; ++i) {
    const double t = std::min(until_s, i / rate_hz);
    const Eigen::Isometry3d T = pose(t);
    PoseKey k;
    k.t_s = t;
    k.rotation = Eigen::Quaterniond(T.linear()).normalized();
    k.position_m = T.translation();
    keys.push_back(k);
  }
  return keys;
}

void peakSpeeds(const std::function<Eigen::Isometry3d(double)>& pose, double until_s,
                double rate_hz, double* speed_mps, double* rate_radps) {
  *speed_mps = *rate_radps = 0.0;
  const double dt = 1.0 / rate_hz;
  Eigen::Isometry3d prev = pose(0.0);
  for (double t = dt; t <= until_s + 1e-9; t += dt) {
    const Eigen::Isometry3d T = pose(t);
    *speed_mps = std::max(*speed_mps, (T.translation() - prev.translation()).norm() / dt);
    *rate_radps = std::max(*rate_radps,
                           Eigen::AngleAxisd(prev.linear().transpose() * T.linear()).angle() / dt);
    prev = T;
  }
}

}  // namespace emf::synth
