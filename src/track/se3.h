// SE(3) / so(3) utilities for pose tracking.
//
// Conventions (used by the tracker and everything that consumes its increments):
// - A pose T_a_b (Eigen::Isometry3d) maps points in frame b to frame a: x_a = T_a_b * x_b.
// - A twist xi in R^6 is ordered TRANSLATION FIRST, ROTATION SECOND: xi = (v, w) with
//   v in metres (the se(3) translational part, not the translation of exp(xi) unless w = 0)
//   and w an axis-angle rotation vector in radians.
// - Increments are LEFT-multiplied: T <- exp(delta) * T. For T = T_volume_camera the increment
//   is expressed in the volume frame; the derivative of exp(delta) * x at delta = 0 is
//   [I, -[x]_x] (see pointJacobian()).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace emf::track {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Skew-symmetric matrix [w]_x with [w]_x * y = w.cross(y).
Eigen::Matrix3d hat(const Eigen::Vector3d& w);

/// Rotation matrix of the rotation vector w (radians; Rodrigues, exact near w = 0).
Eigen::Matrix3d expSo3(const Eigen::Vector3d& w);
/// Rotation vector (radians, |w| in [0, pi]) of a rotation matrix. Robust near identity and
/// near pi (computed via the quaternion).
Eigen::Vector3d logSo3(const Eigen::Matrix3d& R);

/// Left Jacobian of SO(3) at w, V(w) = sum_k [w]_x^k / (k+1)!; translation of exp(v, w) is V v.
Eigen::Matrix3d leftJacobianSo3(const Eigen::Vector3d& w);
/// Inverse of leftJacobianSo3 (valid for |w| < 2 pi).
Eigen::Matrix3d leftJacobianSo3Inverse(const Eigen::Vector3d& w);

/// exp: se(3) -> SE(3). xi = (v [m], w [rad]), translation first.
Eigen::Isometry3d expSe3(const Vector6d& xi);
/// log: SE(3) -> se(3), the inverse of expSe3 for rotation angles in [0, pi].
Vector6d logSe3(const Eigen::Isometry3d& T);

/// Left-multiplied increment: exp(delta) * T.
Eigen::Isometry3d applyLeftIncrement(const Vector6d& delta, const Eigen::Isometry3d& T);
/// The increment delta with exp(delta) * T_from = T_to, i.e. log(T_to * T_from^-1).
Vector6d leftDifference(const Eigen::Isometry3d& T_from, const Eigen::Isometry3d& T_to);

/// Adjoint of T (6x6, translation-first ordering): exp(Ad_T xi) = T exp(xi) T^-1.
Matrix6d adjoint(const Eigen::Isometry3d& T);

/// d(exp(delta) * x)/d(delta) at delta = 0: [I, -[x]_x] (3x6, translation first).
Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& x);

/// Geodesic interpolation on SE(3): T_a * exp(t * log(T_a^-1 * T_b)); t = 0 gives T_a, t = 1
/// gives T_b (screw motion; use for constant-velocity prediction and extrapolation, t may be
/// outside [0, 1]).
Eigen::Isometry3d interpolateSe3(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                 double t);
/// Decoupled interpolation: slerp of the rotation and linear interpolation of the translation
/// (what trajectory evaluation uses to interpolate poses at timestamps). t in [0, 1].
Eigen::Isometry3d interpolateDecoupled(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                       double t);

/// Rotation angle of T in radians, [0, pi].
double rotationAngle(const Eigen::Isometry3d& T);
/// Translation norm of T in metres.
double translationNorm(const Eigen::Isometry3d& T);

}  // namespace emf::track
