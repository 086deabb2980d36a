// The objects suite's scoring (bench/objects_suite/scoring.h) on constructed runs with known
// answers: labels, splits, re-creations in view, spurious estimates, ATE and coverage.
#include <gtest/gtest.h>

#include <cmath>

#include "objects_suite/scoring.h"

namespace emf::bench {
namespace {

constexpr int kFrames = 100;
constexpr double kTol = 1e-9;

Eigen::Isometry3d at(double x, double y, double z, double yaw = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// A camera standing at (0, -2, 1) (its first pose is the SLAM's world: the estimate uses
/// world = first camera), a 0.4 m box driving along x, visible on frames 0-89.
RunRecord run() {
  RunRecord r;
  GtObject box;
  box.id = 1;
  box.class_name = "suitcase";
  box.motion = "drive";
  box.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(-0.2, -0.2, 0), Eigen::Vector3d(0.2, 0.2, 0.4));
  for (int f = 0; f < kFrames; ++f) {
    r.stamps.push_back(f / 30.0);
    r.T_world_camera_gt.push_back(at(0, -2, 1));
    r.T_world_camera.push_back(Eigen::Isometry3d::Identity());  // the SLAM's own world
    box.T_world_object.push_back(at(0.01 * f, 0, 0, 0.01 * f));
    box.visible.push_back(f < 90);
    r.ms_per_frame.push_back(10.0 + f % 10);
  }
  r.gt = {box};
  return r;
}

/// An estimate of the box on frames [from, to): its own object frame is the box's shifted by
/// `offset` (any frame works for ATE), tracked exactly; its mask on the box (label 1).
EstObject estimate(const RunRecord& r, int id, int from, int to, double offset) {
  EstObject e;
  e.id = id;
  for (int f = from; f < to; ++f) {
    const Eigen::Isometry3d T_world_object = r.gt[0].T_world_object[f] * at(offset, 0, 0);
    e.frames.push_back(f);
    e.T_object_camera.push_back(T_world_object.inverse() * r.T_world_camera_gt[f]);
    e.labels.push_back(1);
  }
  return e;
}

TEST(SuiteScoring, SplitsRecreationsAndSpuriousEstimates) {
  RunRecord r = run();
  r.est.push_back(estimate(r, 3, 0, 50, 0.3));
  r.est.push_back(estimate(r, 5, 60, 95, -0.1));
  // An estimate whose mask lies on nothing but the static scene.
  EstObject far = estimate(r, 6, 10, 20, 0.0);
  for (auto& l : far.labels) l = 0;
  far.lost_frames = 4;
  r.est.push_back(far);
  const RunScore s = scoreRun(r);
  ASSERT_TRUE(s.camera_ate_m.has_value());
  EXPECT_NEAR(*s.camera_ate_m, 0.0, kTol);
  ASSERT_EQ(s.objects.size(), 1u);
  const ObjectScore& o = s.objects[0];
  EXPECT_TRUE(o.moving);
  EXPECT_EQ(o.visible_frames, 90);
  EXPECT_EQ(o.estimates, 2);
  EXPECT_EQ(o.recreated_in_view, 1);  // visible on frames 49-60: a re-creation in view
  ASSERT_TRUE(o.ate_m.has_value());
  EXPECT_NEAR(*o.ate_m, 0.0, 1e-6);
  EXPECT_EQ(*o.est_id, 3);  // both exact: the first (50 of 90) wins the tie
  EXPECT_NEAR(o.coverage, 50.0 / 90, kTol);
  EXPECT_NEAR(o.union_coverage, 80.0 / 90, kTol);  // frames 0-49 and 60-89
  EXPECT_EQ(s.spurious_ids, std::vector<int>{6});
  EXPECT_EQ(s.lost_object_frames, 4);
  EXPECT_EQ(s.id_switches, 0);
  EXPECT_NEAR(s.ms_median, 14.5, kTol);
}

TEST(SuiteScoring, AnEstimateOutOfViewInBetweenIsNoRecreationInView) {
  RunRecord r = run();
  for (int f = 40; f < 70; ++f) r.gt[0].visible[f] = false;  // gone from frame 40 to 69
  r.est.push_back(estimate(r, 1, 0, 40, 0.0));
  r.est.push_back(estimate(r, 2, 70, 90, 0.0));
  const RunScore s = scoreRun(r);
  EXPECT_EQ(s.objects[0].estimates, 2);
  EXPECT_EQ(s.objects[0].recreated_in_view, 0);
}

TEST(SuiteScoring, ADriftingEstimateHasItsAte) {
  RunRecord r = run();
  EstObject e = estimate(r, 1, 0, 90, 0.0);
  // 2 cm off along its own x on every other frame: the aligned RMSE is about 1 cm.
  for (size_t i = 0; i < e.frames.size(); i += 2) {
    e.T_object_camera[i] = at(0.02, 0, 0) * e.T_object_camera[i];
  }
  r.est.push_back(e);
  const RunScore s = scoreRun(r);
  ASSERT_TRUE(s.objects[0].ate_m.has_value());
  EXPECT_NEAR(*s.objects[0].ate_m, 0.01, 1e-3);
  EXPECT_NEAR(s.objects[0].coverage, 1.0, kTol);
}

TEST(SuiteScoring, StillObjectsAndLabels) {
  RunRecord r = run();
  for (auto& T : r.gt[0].T_world_object) T = at(0.5, 0, 0);
  EXPECT_FALSE(isMoving(r.gt[0]));
  // Mask labels: the instance under at least 30 % of the estimate's pixels, else nothing.
  cv::Mat rendered(4, 10, CV_32S, cv::Scalar(-1)), truth(4, 10, CV_16U, cv::Scalar(0));
  rendered(cv::Rect(0, 0, 10, 1)).setTo(7);  // estimate 7: 10 px
  truth(cv::Rect(0, 0, 4, 1)).setTo(2);      // 4 of them on object 2
  truth(cv::Rect(4, 0, 2, 1)).setTo(3);      // 2 on object 3, 4 on the static scene
  EXPECT_EQ(labelFromMasks(rendered, truth, 7), 2);
  truth(cv::Rect(0, 0, 2, 1)).setTo(0);  // 2 of 10 on object 2: below 30 %
  EXPECT_EQ(labelFromMasks(rendered, truth, 7), 0);
  EXPECT_EQ(labelFromMasks(rendered, truth, 8), -1);  // renders nothing
  // An estimate that is the box on 26 voting frames and nothing on 24 (and 10 it was not
  // rendered on): the box, no id switch (that needs two objects).
  EstObject e = estimate(r, 1, 0, 60, 0.0);
  for (size_t i = 0; i < 24; ++i) e.labels[i] = 0;
  for (size_t i = 50; i < 60; ++i) e.labels[i] = -1;
  r.est.push_back(e);
  const RunScore s = scoreRun(r);
  EXPECT_EQ(s.objects[0].estimates, 1);
  EXPECT_TRUE(s.spurious_ids.empty());
  EXPECT_EQ(s.id_switches, 0);
}

TEST(SuiteScoring, AnEstimateOnTwoObjectsIsAnIdSwitch) {
  RunRecord r = run();
  GtObject other = r.gt[0];
  other.id = 2;
  r.gt.push_back(other);
  EstObject e = estimate(r, 1, 0, 50, 0.0);
  for (size_t i = 30; i < 50; ++i) e.labels[i] = 2;  // 40 % of its frames on object 2
  r.est.push_back(e);
  const RunScore s = scoreRun(r);
  EXPECT_EQ(s.id_switches, 1);
  EXPECT_EQ(s.objects[0].estimates, 1);  // the majority
  EXPECT_EQ(s.objects[1].estimates, 0);
}

TEST(SuiteScoring, Quantile) {
  EXPECT_EQ(quantile({}, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(quantile({3, 1, 2}, 0.5), 2.0);
  EXPECT_DOUBLE_EQ(quantile({1, 2, 3, 4}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(quantile({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, 0.9), 10.0);
  EXPECT_TRUE(std::isinf(quantile({1, INFINITY}, 1.0)));
  EXPECT_DOUBLE_EQ(quantile({1, INFINITY}, 0.0), 1.0);
}

}  // namespace
}  // namespace emf::bench
