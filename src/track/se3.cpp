#include "track/se3.h"

#include <cmath>

namespace emf::track {
namespace {

// Below these angles the closed forms lose digits to cancellation; Taylor series are exact to
// double precision there (next term < 1e-18).
constexpr double kSmallAngleRad = 1e-2;

struct SinCosTerms {
  double a;  // sin(t) / t
  double b;  // (1 - cos(t)) / t^2
  double c;  // (t - sin(t)) / t^3
};

SinCosTerms sinCosTerms(double theta) {
  const double t2 = theta * theta;
  if (theta < kSmallAngleRad) {
    return {1.0 - t2 / 6.0 * (1.0 - t2 / 20.0), 0.5 - t2 / 24.0 * (1.0 - t2 / 30.0),
            1.0 / 6.0 - t2 / 120.0 * (1.0 - t2 / 42.0)};
  }
  const double s = std::sin(theta);
  const double half = std::sin(0.5 * theta);
  return {s / theta, 2.0 * half * half / t2, (theta - s) / (t2 * theta)};
}

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

Eigen::Matrix3d expSo3(const Eigen::Vector3d& w) {
  const SinCosTerms k = sinCosTerms(w.norm());
  const Eigen::Matrix3d W = hat(w);
  return Eigen::Matrix3d::Identity() + k.a * W + k.b * W * W;
}

Eigen::Vector3d logSo3(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double n = v.norm();
  if (n < 1e-8) {
    // theta = 2 atan(n / w) ~ 2 n / w (1 - n^2 / (3 w^2)); w ~ 1 here.
    return (2.0 / q.w()) * (1.0 - n * n / (3.0 * q.w() * q.w())) * v;
  }
  const double theta = 2.0 * std::atan2(n, q.w());
  return (theta / n) * v;
}

Eigen::Matrix3d leftJacobianSo3(const Eigen::Vector3d& w) {
  const SinCosTerms k = sinCosTerms(w.norm());
  const Eigen::Matrix3d W = hat(w);
  return Eigen::Matrix3d::Identity() + k.b * W + k.c * W * W;
}

Eigen::Matrix3d leftJacobianSo3Inverse(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  const double t2 = theta * theta;
  double d;  // (1 - a / (2 b)) / t^2
  if (theta < kSmallAngleRad) {
    d = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0;
  } else {
    const SinCosTerms k = sinCosTerms(theta);
    d = (1.0 - k.a / (2.0 * k.b)) / t2;
  }
  const Eigen::Matrix3d W = hat(w);
  return Eigen::Matrix3d::Identity() - 0.5 * W + d * W * W;
}

Eigen::Isometry3d expSe3(const Vector6d& xi) {
  const Eigen::Vector3d v = xi.head<3>();
  const Eigen::Vector3d w = xi.tail<3>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSo3(w);
  T.translation() = leftJacobianSo3(w) * v;
  return T;
}

Vector6d logSe3(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d w = logSo3(T.linear());
  Vector6d xi;
  xi.head<3>() = leftJacobianSo3Inverse(w) * T.translation();
  xi.tail<3>() = w;
  return xi;
}

Eigen::Isometry3d applyLeftIncrement(const Vector6d& delta, const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = expSe3(delta) * T;
  // Re-orthonormalise so that thousands of small increments cannot accumulate drift off SO(3).
  Eigen::Quaterniond q(out.linear());
  out.linear() = q.normalized().toRotationMatrix();
  return out;
}

Vector6d leftDifference(const Eigen::Isometry3d& T_from, const Eigen::Isometry3d& T_to) {
  return logSe3(T_to * T_from.inverse());
}

Matrix6d adjoint(const Eigen::Isometry3d& T) {
  Matrix6d ad = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  ad.topLeftCorner<3, 3>() = R;
  ad.topRightCorner<3, 3>() = hat(T.translation()) * R;
  ad.bottomRightCorner<3, 3>() = R;
  return ad;
}

Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& x) {
  Eigen::Matrix<double, 3, 6> j;
  j.leftCols<3>() = Eigen::Matrix3d::Identity();
  j.rightCols<3>() = -hat(x);
  return j;
}

Eigen::Isometry3d interpolateSe3(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                 double t) {
  return T_a * expSe3(t * logSe3(T_a.inverse() * T_b));
}

Eigen::Isometry3d interpolateDecoupled(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                       double t) {
  const Eigen::Quaterniond qa(T_a.linear());
  const Eigen::Quaterniond qb(T_b.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = qa.slerp(t, qb).normalized().toRotationMatrix();
  out.translation() = (1.0 - t) * T_a.translation() + t * T_b.translation();
  return out;
}

double rotationAngle(const Eigen::Isometry3d& T) { return logSo3(T.linear()).norm(); }

double translationNorm(const Eigen::Isometry3d& T) { return T.translation().norm(); }

}  // namespace emf::track
