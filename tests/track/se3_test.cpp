// Property tests of the SE(3) utilities: exp/log round trips over many random poses (including
// near-identity and near-pi rotations), left increments, adjoint, Jacobians, interpolation.
#include "track/se3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "track_test_support.h"

namespace emf::track {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Round trips are exact up to a few ulps times the magnitudes involved.
constexpr double kRoundTripTolerance = 1e-9;
// Near pi the rotation axis is recovered from a tiny quaternion part: allow more.
constexpr double kNearPiTolerance = 1e-7;
// Central differences with step 1e-6 on smooth functions.
constexpr double kFiniteDifferenceTolerance = 1e-7;

Eigen::Isometry3d randomPose(std::mt19937& rng, double max_angle, double max_translation) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Vector6d xi;
  // One draw per statement (test::drawXyz): each length before its direction.
  const double t = u(rng);
  xi.head<3>() = test::randomUnit(rng) * max_translation * t;
  const double a = u(rng);
  xi.tail<3>() = test::randomUnit(rng) * max_angle * a;
  return expSe3(xi);
}

double poseDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

TEST(Se3, HatIsCrossProduct) {
  const Eigen::Vector3d w(0.3, -1.2, 2.5), y(-0.7, 0.1, 0.9);
  EXPECT_LT((hat(w) * y - w.cross(y)).norm(), 1e-15);
  EXPECT_LT((hat(w) + hat(w).transpose()).norm(), 1e-15);
}

TEST(Se3, ExpOfPureTranslationAndKnownRotation) {
  Vector6d xi;
  xi << 0.1, -0.2, 0.3, 0.0, 0.0, 0.0;
  const Eigen::Isometry3d T = expSe3(xi);
  EXPECT_LT((T.translation() - Eigen::Vector3d(0.1, -0.2, 0.3)).norm(), 1e-15);
  EXPECT_LT((T.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  // 90 degrees about z: x -> y.
  xi << 0, 0, 0, 0, 0, kPi / 2;
  const Eigen::Vector3d y = expSe3(xi) * Eigen::Vector3d(1, 0, 0);
  EXPECT_LT((y - Eigen::Vector3d(0, 1, 0)).norm(), 1e-15);
  // Translation first: a screw motion of angle pi about z with v = (0,0,1) moves along z by 1.
  xi << 0, 0, 1, 0, 0, kPi;
  EXPECT_LT((expSe3(xi).translation() - Eigen::Vector3d(0, 0, 1)).norm(), 1e-15);
}

TEST(Se3, ExpLogRoundTripRandomPoses) {
  std::mt19937 rng(1);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Isometry3d T = randomPose(rng, 3.0, 5.0);
    const Eigen::Isometry3d back = expSe3(logSe3(T));
    ASSERT_LT(poseDistance(T, back), kRoundTripTolerance) << "pose " << i;
    // And log(exp(xi)) == xi for angles below pi.
    Vector6d xi;
    xi.head<3>() = test::randomUnit(rng) * 2.0;
    xi.tail<3>() = test::randomUnit(rng) * 3.0;
    ASSERT_LT((logSe3(expSe3(xi)) - xi).norm(), kRoundTripTolerance) << "twist " << i;
  }
}

TEST(Se3, ExpLogRoundTripNearIdentity) {
  std::mt19937 rng(2);
  for (double scale : {1e-3, 1e-5, 1e-8, 1e-12, 0.0}) {
    for (int i = 0; i < 200; ++i) {
      Vector6d xi;
      xi.head<3>() = test::randomUnit(rng) * scale;
      xi.tail<3>() = test::randomUnit(rng) * scale;
      const Vector6d back = logSe3(expSe3(xi));
      ASSERT_LE((back - xi).norm(), 1e-15 + 1e-12 * scale) << "scale " << scale;
      // Small rotations: exp agrees with the first-order expansion to second order.
      const Eigen::Matrix3d R = expSo3(xi.tail<3>());
      ASSERT_LT((R - Eigen::Matrix3d::Identity() - hat(xi.tail<3>())).norm(),
                scale * scale + 1e-16);
    }
  }
}

TEST(Se3, ExpLogRoundTripNearPi) {
  std::mt19937 rng(3);
  for (double gap : {1e-2, 1e-4, 1e-6, 1e-9, 0.0}) {
    for (int i = 0; i < 200; ++i) {
      Vector6d xi;
      xi.head<3>() = test::randomUnit(rng) * 1.5;
      xi.tail<3>() = test::randomUnit(rng) * (kPi - gap);
      const Eigen::Isometry3d T = expSe3(xi);
      const Eigen::Isometry3d back = expSe3(logSe3(T));
      ASSERT_LT(poseDistance(T, back), kNearPiTolerance) << "gap " << gap << " pose " << i;
      ASSERT_NEAR(logSe3(T).tail<3>().norm(), kPi - gap, kNearPiTolerance);
    }
  }
}

TEST(Se3, LeftJacobianInverse) {
  std::mt19937 rng(4);
  for (double angle : {0.0, 1e-6, 1e-3, 0.5, 2.0, 3.0, kPi}) {
    const Eigen::Vector3d w = test::randomUnit(rng) * angle;
    const Eigen::Matrix3d I = leftJacobianSo3(w) * leftJacobianSo3Inverse(w);
    EXPECT_LT((I - Eigen::Matrix3d::Identity()).norm(), 1e-12) << angle;
  }
}

TEST(Se3, LeftIncrementAndDifference) {
  std::mt19937 rng(5);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Isometry3d T = randomPose(rng, 3.0, 3.0);
    Vector6d delta;
    delta.head<3>() = test::randomUnit(rng) * 0.3;
    delta.tail<3>() = test::randomUnit(rng) * 0.5;
    const Eigen::Isometry3d T2 = applyLeftIncrement(delta, T);
    ASSERT_LT(poseDistance(T2, expSe3(delta) * T), 1e-12);
    ASSERT_LT((leftDifference(T, T2) - delta).norm(), 1e-9);
    ASSERT_LT((T2.linear().transpose() * T2.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  }
}

TEST(Se3, AdjointMapsTwists) {
  std::mt19937 rng(6);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Isometry3d T = randomPose(rng, 3.0, 2.0);
    Vector6d xi;
    xi.head<3>() = test::randomUnit(rng) * 0.4;
    xi.tail<3>() = test::randomUnit(rng) * 0.7;
    const Eigen::Isometry3d lhs = T * expSe3(xi) * T.inverse();
    ASSERT_LT(poseDistance(lhs, expSe3(adjoint(T) * xi)), 1e-9);
  }
}

TEST(Se3, PointJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(7);
  const double h = 1e-6;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d x = test::randomUnit(rng) * 2.5;
    const Eigen::Matrix<double, 3, 6> J = pointJacobian(x);
    for (int k = 0; k < 6; ++k) {
      Vector6d d = Vector6d::Zero();
      d(k) = h;
      const Eigen::Vector3d fd = (expSe3(d) * x - expSe3(-d) * x) / (2 * h);
      ASSERT_LT((fd - J.col(k)).norm(), kFiniteDifferenceTolerance) << "column " << k;
    }
  }
}

TEST(Se3, InterpolationEndpointsAndMidpoint) {
  std::mt19937 rng(8);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Isometry3d A = randomPose(rng, 3.0, 2.0);
    const Eigen::Isometry3d B = randomPose(rng, 3.0, 2.0);
    ASSERT_LT(poseDistance(interpolateSe3(A, B, 0.0), A), 1e-12);
    ASSERT_LT(poseDistance(interpolateSe3(A, B, 1.0), B), 1e-9);
    ASSERT_LT(poseDistance(interpolateDecoupled(A, B, 0.0), A), 1e-12);
    ASSERT_LT(poseDistance(interpolateDecoupled(A, B, 1.0), B), 1e-12);
    // Geodesic midpoint: half the relative motion twice gives the whole.
    const Eigen::Isometry3d M = interpolateSe3(A, B, 0.5);
    const Eigen::Isometry3d half = A.inverse() * M;
    ASSERT_LT(poseDistance(A * half * half, B), 1e-9);
    // Decoupled midpoint: translation is the average, rotation angle is half of the relative.
    const Eigen::Isometry3d D = interpolateDecoupled(A, B, 0.5);
    ASSERT_LT((D.translation() - 0.5 * (A.translation() + B.translation())).norm(), 1e-12);
    const double full = rotationAngle(A.inverse() * B);
    ASSERT_NEAR(rotationAngle(A.inverse() * D), 0.5 * full, 1e-9);
  }
  // Extrapolation with t = 2 repeats the relative motion (constant velocity).
  const Eigen::Isometry3d A = randomPose(rng, 1.0, 1.0);
  const Eigen::Isometry3d step = randomPose(rng, 0.2, 0.1);
  EXPECT_LT(poseDistance(interpolateSe3(A, A * step, 2.0), A * step * step), 1e-9);
}

TEST(Se3, AngleAndTranslationNorm) {
  Vector6d xi;
  xi << 0.3, 0.4, 0.0, 0.0, 0.25, 0.0;
  const Eigen::Isometry3d T = expSe3(xi);
  EXPECT_NEAR(rotationAngle(T), 0.25, 1e-14);
  Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
  P.translation() << 0.3, 0.4, 0.0;
  EXPECT_NEAR(translationNorm(P), 0.5, 1e-15);
}

}  // namespace
}  // namespace emf::track
