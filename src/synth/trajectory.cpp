#include "synth/trajectory.h"

#include <algorithm>
#include <cmath>

namespace emf::synth {
namespace {

constexpr double kTwoPi = 6.283185307179586;

Eigen::Matrix3d expSo3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// Sum of the terms at warped time s, each with its envelope at clip time t.
Eigen::Vector3d sumTerms(const std::vector<Sinusoid>& terms, double s, double t) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (const auto& term : terms) {
    v += term.envelope(t) * term.amplitude *
         std::sin(kTwoPi * term.frequency_hz * s + term.phase_rad);
  }
  return v;
}

// Derivative by s of the sinusoids (the envelopes taken as constant: a heading only).
Eigen::Vector3d sumTermsDerivative(const std::vector<Sinusoid>& terms, double s, double t) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (const auto& term : terms) {
    const double w = kTwoPi * term.frequency_hz;
    v += term.envelope(t) * term.amplitude * w * std::cos(w * s + term.phase_rad);
  }
  return v;
}

}  // namespace

double smootherstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * x * (x * (6.0 * x - 15.0) + 10.0);
}

double Sinusoid::envelope(double t) const {
  if (t <= on_s || t >= off_s) return 0.0;
  if (ramp_s <= 0.0) return 1.0;
  return smootherstep((t - on_s) / ramp_s) * smootherstep((off_s - t) / ramp_s);
}

double Trajectory::warpedTime(double t) const {
  if (still_until_s <= 0.0) return t;  // moving from the start: no warp
  if (t <= still_until_s) return 0.0;
  const double dt = t - still_until_s;
  if (ramp_s <= 0.0) return dt;
  if (dt < ramp_s) return dt * dt / (2.0 * ramp_s);
  return dt - 0.5 * ramp_s;
}

namespace {
/// The keys around t and the fraction of the way from the first to the second.
void bracket(const std::vector<PoseKey>& keys, double t, size_t* i0, size_t* i1, double* f) {
  const auto after = std::upper_bound(keys.begin(), keys.end(), t,
                                      [](double x, const PoseKey& k) { return x < k.t_s; });
  if (after == keys.begin()) {
    *i0 = *i1 = 0;
    *f = 0.0;
    return;
  }
  if (after == keys.end()) {
    *i0 = *i1 = keys.size() - 1;
    *f = 0.0;
    return;
  }
  *i1 = static_cast<size_t>(after - keys.begin());
  *i0 = *i1 - 1;
  const double span = keys[*i1].t_s - keys[*i0].t_s;
  *f = span > 0.0 ? (t - keys[*i0].t_s) / span : 0.0;
}
}  // namespace

Eigen::Vector3d Trajectory::position(double t) const {
  if (!keys.empty()) {
    size_t i0, i1;
    double f;
    bracket(keys, t, &i0, &i1, &f);
    return (1.0 - f) * keys[i0].position_m + f * keys[i1].position_m;
  }
  const double s = warpedTime(t);
  Eigen::Vector3d p = origin_m + sumTerms(position_terms, s, t);
  for (const auto& m : moves)
    p += m.delta_m * smootherstep((t - m.start_s) / (m.end_s - m.start_s));
  return p;
}

Eigen::Isometry3d Trajectory::pose(double t) const {
  if (!keys.empty()) {
    size_t i0, i1;
    double f;
    bracket(keys, t, &i0, &i1, &f);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = keys[i0].rotation.slerp(f, keys[i1].rotation).toRotationMatrix();
    T.translation() = position(t);
    return T;
  }
  const double s = warpedTime(t);
  Eigen::Vector3d rot = sumTerms(rotation_terms, s, t);
  Eigen::Vector3d move_rot = Eigen::Vector3d::Zero();
  for (const auto& m : moves) {
    move_rot += m.delta_rad * smootherstep((t - m.start_s) / (m.end_s - m.start_s));
  }
  Eigen::Matrix3d R_heading = Eigen::Matrix3d::Identity();
  if (face_velocity) {
    // Heading of the sinusoidal path; at rest (s = 0) the heading of the first motion.
    const Eigen::Vector3d v = sumTermsDerivative(position_terms, s, t);
    if (std::hypot(v.x(), v.y()) > 1e-12) {
      R_heading =
          Eigen::AngleAxisd(std::atan2(v.y(), v.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    }
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSo3(move_rot) * R_heading * expSo3(rot) * R0;
  T.translation() = position(t);
  return T;
}

Eigen::Isometry3d CameraRig::pose(double t) const {
  const Eigen::Vector3d c = path.position(t);
  const Eigen::Vector3d f = (target.position(t) - c).normalized();
  const Eigen::Vector3d x = f.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = f.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = f;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R * expSo3(sumTerms(tremor_rad, t, t));
  T.translation() = c;
  return T;
}

}  // namespace emf::synth
