// Motion programs (motion_plan.h) and keyframed / enveloped trajectories (trajectory.h): each
// action ends where it says, a tipped box lands one side further on, rockers roll without
// sliding, a drive stays on its loop within its speed limits and stops when told.
#include "synth/motion_plan.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"

namespace emf::synth {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kTol = 1e-9;

TEST(MotionPlan, ActionsChainAndHoldTheirEnds) {
  MotionPlan p(Eigen::Isometry3d::Identity());
  p.rest(1.0);
  p.move(2.0, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, kPi / 2));
  EXPECT_DOUBLE_EQ(p.end(), 3.0);
  EXPECT_TRUE(p.pose(0.5).isApprox(Eigen::Isometry3d::Identity(), kTol));
  // Half way through the eased move: half the translation and rotation (smootherstep(0.5)).
  EXPECT_NEAR(p.pose(2.0).translation().x(), 0.5, kTol);
  EXPECT_NEAR(Eigen::AngleAxisd(p.pose(2.0).linear()).angle(), kPi / 4, 1e-9);
  EXPECT_NEAR(p.pose(10.0).translation().x(), 1.0, kTol);
  EXPECT_TRUE(p.pose(10.0).isApprox(p.endPose(), kTol));
}

TEST(MotionPlan, ABoxTippedOverItsEdgeLandsOneSideFurther) {
  // A 0.4 m cube, origin at its centre 0.2 m above the floor, tipped towards +x about its
  // bottom edge at x = 0.2.
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.translation() = Eigen::Vector3d(0, 0, 0.2);
  MotionPlan p(start);
  p.rotateAbout(2.0, Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d::UnitY(), kPi / 2);
  EXPECT_NEAR((p.endPose().translation() - Eigen::Vector3d(0.4, 0, 0.2)).norm(), 0.0, 1e-12);
  // Half way the centre stands above the edge, at half the diagonal.
  EXPECT_NEAR((p.pose(1.0).translation() - Eigen::Vector3d(0.2, 0, 0.2 * std::sqrt(2.0))).norm(),
              0.0, 1e-9);
}

TEST(MotionPlan, RockersRollWithoutSliding) {
  // Rockers of radius 0.9 m centred at the origin, 0.9 m above the floor: the contact point (the
  // rockers' lowest point) has no horizontal velocity.
  const double R = 0.9;
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  start.translation() = Eigen::Vector3d(0, 0, R);
  MotionPlan p(start);
  p.oscillate(6.0, Eigen::Vector3d::UnitY(), 10 * kPi / 180, 0.5, 1.0, R);
  for (double t = 0.5; t < 5.5; t += 0.37) {
    const double dt = 1e-5;
    // The rocker point under the centre of curvature at time t, in the object frame.
    const Eigen::Isometry3d T = p.pose(t);
    const Eigen::Vector3d down_world(0, 0, -R);
    const Eigen::Vector3d contact_object = T.linear().transpose() * down_world;
    const Eigen::Vector3d a = T * contact_object, b = p.pose(t + dt) * contact_object;
    EXPECT_NEAR(a.z(), 0.0, 1e-9);
    EXPECT_LT(std::fabs(b.x() - a.x()) / dt, 1e-3) << t;
  }
  EXPECT_TRUE(p.endPose().isApprox(start, 1e-9));
}

TEST(MotionPlan, DriveWithoutTimeIsAnError) {
  MotionPlan p(Eigen::Isometry3d::Identity());
  auto loop = [](double u) {
    return Eigen::Vector2d(std::cos(2 * kPi * u), std::sin(2 * kPi * u));
  };
  EXPECT_THROW(p.drive(-0.5, loop, 0.0, 0.3, 1.0, {}), InvalidArgument);
  EXPECT_THROW(p.drive(0.0, loop, 0.0, 0.3, 1.0, {}), InvalidArgument);
}

TEST(MotionPlan, DriveStaysOnItsLoopWithinLimitsAndStops) {
  const double a = 0.8, b = 0.5;
  auto loop = [=](double u) {
    return Eigen::Vector2d(a * std::cos(2 * kPi * u), b * std::sin(2 * kPi * u));
  };
  MotionPlan p(Eigen::Isometry3d::Identity());
  p.rest(1.0);
  const double vmax = 0.3, yaw_max = 50 * kPi / 180;
  p.drive(12.0, loop, 0.0, vmax, yaw_max, {Eigen::Vector2d(5.0, 7.0)});
  EXPECT_NEAR(p.pose(0.0).translation().x(), a, 1e-6);
  double v_peak = 0, yaw_peak = 0;
  const double dt = 1.0 / 60;
  for (double t = 0; t + dt <= 13.0; t += dt) {
    const Eigen::Isometry3d T0 = p.pose(t), T1 = p.pose(t + dt);
    const Eigen::Vector3d q = T0.translation();
    EXPECT_NEAR(q.x() * q.x() / (a * a) + q.y() * q.y() / (b * b), 1.0, 2e-3);
    v_peak = std::max(v_peak, (T1.translation() - T0.translation()).norm() / dt);
    yaw_peak =
        std::max(yaw_peak, Eigen::AngleAxisd(T0.linear().transpose() * T1.linear()).angle() / dt);
    // Heading along the path.
    const Eigen::Vector3d step = T1.translation() - T0.translation();
    if (step.norm() > 1e-4) {
      EXPECT_GT(step.normalized().dot(T0.linear().col(0)), 0.99) << t;
    }
  }
  EXPECT_LE(v_peak, vmax * 1.01);
  EXPECT_LE(yaw_peak, yaw_max * 1.15);
  EXPECT_GT(v_peak, 0.8 * vmax);
  // Stopped inside the stop window (1 s of rest comes first: the drive's 5-7 s is 6-8 s).
  EXPECT_LT((p.pose(7.0).translation() - p.pose(6.5).translation()).norm(), 1e-6);
}

TEST(Trajectory, KeysInterpolateAndHoldAtTheEnds) {
  Trajectory tr;
  PoseKey k0, k1;
  k0.t_s = 1.0;
  k1.t_s = 2.0;
  k1.position_m = Eigen::Vector3d(2, 0, 0);
  k1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  tr.keys = {k0, k1};
  EXPECT_NEAR(tr.pose(1.5).translation().x(), 1.0, kTol);
  EXPECT_NEAR(Eigen::AngleAxisd(tr.pose(1.5).linear()).angle(), 0.5, 1e-12);
  EXPECT_TRUE(tr.pose(0.0).isApprox(tr.pose(1.0)));
  EXPECT_TRUE(tr.pose(9.0).isApprox(tr.pose(2.0)));
}

TEST(Trajectory, SinusoidEnvelope) {
  Sinusoid s{Eigen::Vector3d(1, 0, 0), 0.25, 0.0};
  EXPECT_EQ(s.envelope(123.0), 1.0);  // the default window is always on
  s.on_s = 2.0;
  s.off_s = 10.0;
  s.ramp_s = 1.0;
  EXPECT_EQ(s.envelope(1.9), 0.0);
  EXPECT_EQ(s.envelope(10.5), 0.0);
  EXPECT_DOUBLE_EQ(s.envelope(2.5), 0.5);
  EXPECT_EQ(s.envelope(6.0), 1.0);
  Trajectory tr;
  tr.position_terms = {s};
  EXPECT_EQ(tr.position(1.0).x(), 0.0);
  EXPECT_NEAR(tr.position(5.0).x(), std::sin(2 * kPi * 0.25 * 5.0), 1e-12);
}

}  // namespace
}  // namespace emf::synth
