// Evaluation: the TUM tools' reference figures, hand-made cases with known answers, object
// matching, errors, and the `emf eval` command.
#include "eval/eval.h"

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "common/error.h"
#include "eval/surface_coverage.h"
#include "io_test_util.h"
#include "test_support.h"

namespace emf::io {
namespace {
namespace fs = std::filesystem;

using testing::expectErrorContaining;
using testing::writeText;

// The reference figures are given to 6 decimals (metres) / 6 decimals (degrees).
constexpr double kReferenceTolM = 1e-6;
constexpr double kReferenceTolDeg = 1e-4;
// Hand-made cases are exact up to floating-point rounding.
constexpr double kExactTolM = 1e-9;
constexpr double kExactTolDeg = 1e-6;
// A zero rotation error is computed as acos((trace - 1) / 2), which turns rounding of 1e-16 in
// the trace into ~1e-8 rad: "zero" angles are only zero to about 1e-6 deg.
constexpr double kZeroAngleTolDeg = 2e-5;

std::string refGt() { return test::dataPath("trajectories/freiburg1_xyz-groundtruth.txt"); }
std::string refEst() { return test::dataPath("trajectories/freiburg1_xyz-rgbdslam.txt"); }

Eigen::Isometry3d pose(const Eigen::Vector3d& t, double yaw, double pitch = 0, double roll = 0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = t;
  return T;
}

TEST(Eval, ReproducesTheTumToolsOnTheReferencePair) {
  const Trajectory gt = readTrajectory(refGt()), est = readTrajectory(refEst());
  const eval::AteResult ate = eval::computeAte(gt, est, 0.02);
  EXPECT_EQ(ate.pairs, 786u);
  EXPECT_NEAR(ate.trans_m.rmse, 0.013473, kReferenceTolM);
  EXPECT_NEAR(ate.trans_m.mean, 0.012029, kReferenceTolM);
  EXPECT_NEAR(ate.trans_m.median, 0.011176, kReferenceTolM);
  EXPECT_NEAR(ate.trans_m.max, 0.034727, kReferenceTolM);
  const eval::RpeResult rpe = eval::computeRpe(gt, est, 1.0);
  EXPECT_EQ(rpe.pairs, 753u);
  EXPECT_NEAR(rpe.trans_m.rmse, 0.021217, kReferenceTolM);
  EXPECT_NEAR(rpe.rot_deg.rmse, 0.934480, kReferenceTolDeg);
}

TEST(Eval, RigidlyMovedCopyHasZeroError) {
  const Trajectory gt = readTrajectory(refGt());
  Trajectory est;
  const Eigen::Isometry3d T = pose(Eigen::Vector3d(3, -2, 0.5), 1.1, -0.4, 0.3);
  for (size_t i = 0; i < gt.size(); i += 3) est.append(gt.stamps[i] + 0.001, T * gt.poses[i]);
  const eval::AteResult ate = eval::computeAte(gt, est, 0.02);
  EXPECT_EQ(ate.pairs, est.size());
  EXPECT_LT(ate.trans_m.max, kExactTolM);
  // The alignment found is the inverse of the applied transform.
  EXPECT_LT(((ate.T_gt_est * T).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-9);
  const eval::RpeResult rpe = eval::computeRpe(gt, est, 1.0);
  EXPECT_LT(rpe.trans_m.max, kExactTolM);
  EXPECT_LT(rpe.rot_deg.max, kZeroAngleTolDeg);
}

TEST(Eval, KnownOffsetOnHalfThePosesIsHalvedByTheAlignment) {
  // Poses come in pairs at the same position (a helix); the second of each pair is offset by
  // d in the estimate. The offset poses and the others have the same centroid and the cross-
  // covariance stays symmetric, so the optimal alignment is a pure shift by d/2: every pose
  // then has error |d|/2 exactly.
  const Eigen::Vector3d d(0.03, -0.04, 0.12);  // |d| = 0.13 m
  Trajectory gt, est;
  for (int i = 0; i < 200; ++i) {
    const double s = 0.1 * (i / 2);
    const Eigen::Vector3d p(std::cos(s), std::sin(s), 0.2 * s);
    gt.append(i * 0.1, pose(p, s));
    est.append(i * 0.1 + 0.005, pose(p + (i % 2 ? d : Eigen::Vector3d::Zero()), s));
  }
  const eval::AteResult ate = eval::computeAte(gt, est, 0.02);
  EXPECT_EQ(ate.pairs, 200u);
  for (double e :
       {ate.trans_m.rmse, ate.trans_m.mean, ate.trans_m.median, ate.trans_m.min, ate.trans_m.max}) {
    EXPECT_NEAR(e, 0.065, kExactTolM);
  }
  EXPECT_LT((ate.T_gt_est.translation() + d / 2).norm(), kExactTolM);
  // The same offset on every pose is absorbed completely.
  Trajectory all;
  for (size_t i = 0; i < gt.size(); ++i) {
    all.append(gt.stamps[i], pose(gt.poses[i].translation() + d, 0));
  }
  EXPECT_LT(eval::computeAte(gt, all, 0.02).trans_m.max, kExactTolM);
}

// Constant-velocity cases at 30 Hz: the RPE over 1 s is the velocity difference x 1 s.
TEST(Eval, RpeOnConstantVelocityMotion) {
  const int n = 150;
  const double yaw_rate = 10.0 * M_PI / 180;  // rad/s, same for both
  Trajectory gt, faster;
  for (int k = 0; k < n; ++k) {
    const double t = k / 30.0;
    gt.append(t, pose(Eigen::Vector3d(0.5 * t, 0, 0), yaw_rate * t));
    faster.append(t, pose(Eigen::Vector3d(0.6 * t, 0, 0), yaw_rate * t));
  }
  // For each i, j = i + 30 (closest to t_i + 1 s); pairs whose j is the last pose are dropped.
  const eval::RpeResult r = eval::computeRpe(gt, faster, 1.0);
  EXPECT_EQ(r.pairs, static_cast<size_t>(n - 31));
  EXPECT_NEAR(r.trans_m.rmse, 0.1, kExactTolM);
  EXPECT_NEAR(r.trans_m.min, 0.1, kExactTolM);
  EXPECT_NEAR(r.trans_m.max, 0.1, kExactTolM);
  EXPECT_LT(r.rot_deg.max, kZeroAngleTolDeg);
  // Turning in place at 20 vs 22 deg/s: 2 degrees of rotation error, no translation error.
  Trajectory spin_gt, spin_est;
  for (int k = 0; k < n; ++k) {
    const double t = k / 30.0;
    spin_gt.append(t, pose(Eigen::Vector3d(1, 2, 3), 20.0 * M_PI / 180 * t, 0.3));
    spin_est.append(t, pose(Eigen::Vector3d(1, 2, 3), 22.0 * M_PI / 180 * t, 0.3));
  }
  const eval::RpeResult s = eval::computeRpe(spin_gt, spin_est, 1.0);
  EXPECT_NEAR(s.rot_deg.rmse, 2.0, kExactTolDeg);
  EXPECT_NEAR(s.rot_deg.min, 2.0, kExactTolDeg);
  EXPECT_LT(s.trans_m.max, kExactTolM);
}

// Three copies of one smooth motion, each with its own independent per-pose noise (a exact,
// b and c with a rotation of sigma per axis and a translation of sigma_t per axis, drawn anew
// for every pose): the one-step RPE between two copies has the rms of both their noises, and
// the three-cornered hat recovers each copy's own. A per-pose noise of sigma per axis gives a
// step error of sqrt(2 * 3) sigma (two poses, three axes).
TEST(Eval, ThreeCorneredHatRecoversEachTrajectorysOwnStepError) {
  const int n = 3000;
  const double sigma_deg[3] = {0.0, 0.1, 0.2};
  const double sigma_m[3] = {0.0, 0.002, 0.001};
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  Trajectory traj[3];
  for (int k = 0; k < n; ++k) {
    const double t = k / 30.0;
    const Eigen::Isometry3d truth =
        pose(Eigen::Vector3d(std::sin(0.3 * t), 0.2 * t, 0.1 * std::cos(0.5 * t)), 0.2 * t,
             0.1 * std::sin(0.4 * t));
    for (int i = 0; i < 3; ++i) {
      const double s = sigma_deg[i] * M_PI / 180;
      Eigen::Isometry3d noise = Eigen::Isometry3d::Identity();
      const Eigen::Vector3d w = s * test::drawXyz<Eigen::Vector3d>([&] { return unit(rng); });
      if (w.norm() > 0) noise.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).matrix();
      noise.translation() = sigma_m[i] * test::drawXyz<Eigen::Vector3d>([&] { return unit(rng); });
      traj[i].append(t, truth * noise);
    }
  }
  const eval::ThreeCorneredHat h = eval::threeCorneredHat(traj[0], traj[1], traj[2], 1.0 / 30);
  EXPECT_EQ(h.ab.pairs, static_cast<size_t>(n - 1));  // every pose and the next one
  // 3000 steps: the rms of each pairwise RPE is within ~2 % of its expectation, and the exact
  // copy's share comes out of differences of such figures.
  constexpr double kShareRelTol = 0.05;
  constexpr double kExactShareTolDeg = 0.05;
  constexpr double kExactShareTolM = 0.0006;
  EXPECT_LT(h.rot_deg[0], kExactShareTolDeg);
  EXPECT_LT(h.trans_m[0], kExactShareTolM);
  for (int i = 1; i < 3; ++i) {
    SCOPED_TRACE(i);
    const double want_deg = std::sqrt(6.0) * sigma_deg[i];
    EXPECT_NEAR(h.rot_deg[i], want_deg, kShareRelTol * want_deg);
    const double want_m = std::sqrt(6.0) * sigma_m[i];
    EXPECT_NEAR(h.trans_m[i], want_m, kShareRelTol * want_m);
  }
  // The pairwise figures themselves: b against c carries both their noises.
  const double bc_deg = std::sqrt(6.0) * std::hypot(sigma_deg[1], sigma_deg[2]);
  EXPECT_NEAR(h.bc.rot_deg.rmse, bc_deg, kShareRelTol * bc_deg);

  // b lost a stretch of frames and c every third one: only the poses all three have are
  // compared (same pairs in all three RPEs), and the shares stay where they were.
  Trajectory b_gaps, c_gaps;
  for (size_t k = 0; k < traj[1].size(); ++k) {
    if (k < 1000 || k >= 1500) b_gaps.append(traj[1].stamps[k], traj[1].poses[k]);
    if (k % 3 != 0) c_gaps.append(traj[2].stamps[k], traj[2].poses[k]);
  }
  const eval::ThreeCorneredHat g = eval::threeCorneredHat(traj[0], b_gaps, c_gaps, 1.0 / 30);
  // b keeps 2500 poses; c drops the multiples of 3 among them: 334 below 1000, 500 from 1500.
  EXPECT_EQ(g.common_poses, static_cast<size_t>(2500 - 334 - 500));
  EXPECT_EQ(g.ab.pairs, g.ac.pairs);
  EXPECT_EQ(g.ab.pairs, g.bc.pairs);
  EXPECT_LT(g.rot_deg[0], kExactShareTolDeg);
  for (int i = 1; i < 3; ++i) {
    SCOPED_TRACE(i);
    EXPECT_NEAR(g.rot_deg[i], h.rot_deg[i], kShareRelTol * h.rot_deg[i]);
  }
}

TEST(Eval, StatsFollowNumpy) {
  const eval::ErrorStats s = eval::errorStats({4, 1, 3, 2});
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(s.min, 1);
  EXPECT_DOUBLE_EQ(s.max, 4);
  EXPECT_DOUBLE_EQ(eval::errorStats({3, 1, 2}).median, 2);
}

// ---- objects and folders ----------------------------------------------------------------------

// A dataset folder with two ground-truth objects and an emf output folder with four estimates:
//  object-7: GT object 1 in another frame + 2 mm noise        -> matches GT 1
//  object-3: GT object 2 + 5 mm noise                          -> matches GT 2
//  object-9: GT object 2 + 50 mm noise (worse ATE)             -> not chosen
//  object-5: GT object 2 exactly, but only 20% of its frames   -> not eligible (coverage)
struct ObjectScene {
  std::string gt_dir, est_dir;
  ObjectScene() {
    gt_dir = test::tempDir("eval-gt");
    est_dir = test::tempDir("eval-est");
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 1.0);
    auto jitter = [&](const Eigen::Isometry3d& T, double sigma) {
      Eigen::Isometry3d J = T;
      J.translation() += sigma * test::drawXyz<Eigen::Vector3d>([&] { return noise(rng); });
      return J;
    };
    Trajectory cam, obj1, obj2, e7, e3, e9, e5;
    const Eigen::Isometry3d other_frame = pose(Eigen::Vector3d(1, 2, 3), 0.7, 0.2);
    for (int k = 0; k < 150; ++k) {
      const double t = k / 30.0;
      cam.append(t, pose(Eigen::Vector3d(0.3 * t, 0.1 * std::sin(t), 0), 0.1 * t));
      const Eigen::Isometry3d o1 = pose(Eigen::Vector3d(1 + 0.2 * t, std::cos(t), 0.1 * t), t);
      const Eigen::Isometry3d o2 =
          pose(Eigen::Vector3d(-0.5 * t, 0.3, std::sin(2 * t)), -0.5 * t, 0.1 * t);
      if (k < 100) {
        obj1.append(t, o1);
        e7.append(t, jitter(other_frame * o1, 0.002));
      }
      if (k >= 50) {
        obj2.append(t, o2);
        e3.append(t, jitter(o2, 0.005));
        e9.append(t, jitter(o2, 0.05));
        if (k < 70) e5.append(t, o2);
      }
    }
    writeTrajectory(gt_dir + "/groundtruth.txt", cam);
    fs::create_directories(gt_dir + "/objects");
    writeTrajectory(gt_dir + "/objects/gt-object-1-camera.txt", obj1);
    writeTrajectory(gt_dir + "/objects/gt-object-2-camera.txt", obj2);
    writeTrajectory(est_dir + "/camera.txt", cam);
    writeTrajectory(est_dir + "/object-7.txt", e7);
    writeTrajectory(est_dir + "/object-3.txt", e3);
    writeTrajectory(est_dir + "/object-9.txt", e9);
    writeTrajectory(est_dir + "/object-5.txt", e5);
  }
};

TEST(Eval, ObjectsMatchTheLowestAteAmongCoveringEstimates) {
  const ObjectScene scene;
  const eval::EvalReport r = eval::evaluatePaths(scene.gt_dir, scene.est_dir, eval::EvalOptions{});
  ASSERT_TRUE(r.camera.ate.has_value());
  EXPECT_LT(r.camera.ate->trans_m.max, kExactTolM * 10);  // camera.txt = ground truth (9 decimals)
  EXPECT_DOUBLE_EQ(r.camera.coverage, 1.0);
  ASSERT_EQ(r.objects.size(), 2u);

  const eval::ObjectEval& o1 = r.objects[0];
  EXPECT_EQ(o1.gt_id, 1);
  ASSERT_TRUE(o1.est_id.has_value());
  EXPECT_EQ(*o1.est_id, 7);
  EXPECT_DOUBLE_EQ(o1.eval.coverage, 1.0);
  ASSERT_TRUE(o1.eval.ate.has_value());
  EXPECT_EQ(o1.eval.ate->pairs, 100u);
  // 2 mm isotropic noise: RMSE close to 2 mm * sqrt(3).
  EXPECT_NEAR(o1.eval.ate->trans_m.rmse, 0.002 * std::sqrt(3.0), 0.0008);
  EXPECT_TRUE(o1.eval.rpe.has_value());

  const eval::ObjectEval& o2 = r.objects[1];
  EXPECT_EQ(o2.gt_id, 2);
  ASSERT_TRUE(o2.est_id.has_value());
  EXPECT_EQ(*o2.est_id, 3);
  EXPECT_DOUBLE_EQ(o2.eval.coverage, 1.0);
  for (const auto& c : o2.candidates) {
    if (c.est_id == 5) {
      EXPECT_DOUBLE_EQ(c.coverage, 0.2);
      EXPECT_FALSE(c.ate_rmse_m.has_value());  // exact, but covers only 20% < 30%
    }
    if (c.est_id == 9) {
      ASSERT_TRUE(c.ate_rmse_m.has_value());
      EXPECT_GT(*c.ate_rmse_m, o2.eval.ate->trans_m.rmse);
    }
    if (c.est_id == 7) {
      EXPECT_NEAR(c.coverage, 50.0 / 100.0, 1e-12);  // frames 50..99 of GT object 2's 100
    }
  }
  EXPECT_EQ(r.unmatched_est_ids, (std::vector<int>{5, 9}));

  // With a 15% threshold the exact partial estimate wins.
  eval::EvalOptions low;
  low.min_object_coverage = 0.15;
  const eval::EvalReport r2 = eval::evaluatePaths(scene.gt_dir, scene.est_dir, low);
  EXPECT_EQ(*r2.objects[1].est_id, 5);
  EXPECT_DOUBLE_EQ(r2.objects[1].eval.coverage, 0.2);
}

TEST(Eval, UnmatchedObjectIsReportedNotFatal) {
  const ObjectScene scene;
  for (const char* f : {"object-3.txt", "object-9.txt", "object-5.txt"}) {
    fs::remove(scene.est_dir + "/" + f);
  }
  // object-7 covers all of GT object 1 but only half of GT object 2.
  eval::EvalOptions options;
  options.min_object_coverage = 0.6;
  const eval::EvalReport r = eval::evaluatePaths(scene.gt_dir, scene.est_dir, options);
  ASSERT_EQ(r.objects.size(), 2u);
  EXPECT_EQ(r.objects[0].est_id, 7);
  EXPECT_FALSE(r.objects[1].est_id.has_value());
  EXPECT_FALSE(r.objects[1].eval.ate.has_value());
  EXPECT_DOUBLE_EQ(r.objects[1].eval.coverage, 0.5);
  EXPECT_NE(r.objects[1].eval.note.find("no estimated object covers 60% of its 100 timestamps "
                                        "(best 50.0%)"),
            std::string::npos)
      << r.objects[1].eval.note;
  EXPECT_NE(eval::formatReport(r).find("object 2"), std::string::npos);
}

TEST(Eval, OneEstimatePerGroundTruthObject) {
  // Two ground-truth objects that move alike up to a rigid offset (as two still objects do in
  // T_object_camera): estimate 4, a copy of object 1, also fits object 2 perfectly. It is
  // credited once; object 2 gets estimate 6 (1 cm off), not estimate 4 a second time.
  Trajectory a, b, copy_a, near_b;
  copy_a.source = "object-4.txt";
  near_b.source = "object-6.txt";
  for (int i = 0; i < 50; ++i) {
    const double t = i / 30.0;
    const Eigen::Isometry3d T = pose({0.02 * i, 0.5 * std::sin(0.2 * i), 1.0}, 0.03 * i, 0.01 * i);
    a.append(t, T);
    b.append(t, pose({1.0, 2.0, 0.0}, 0.7) * T);
    copy_a.append(t, T);
    near_b.append(t, pose({1.0, 2.0, 0.0}, 0.7) * pose({i % 2 ? 0.01 : -0.01, 0.0, 0.0}, 0.0) * T);
  }
  const std::vector<eval::ObjectEval> r =
      eval::evaluateObjects({{1, a}, {2, b}}, {{4, copy_a}, {6, near_b}}, eval::EvalOptions{});
  ASSERT_EQ(r.size(), 2u);
  ASSERT_TRUE(r[0].est_id && r[1].est_id);
  EXPECT_EQ(*r[0].est_id, 4);
  EXPECT_NEAR(r[0].eval.ate->trans_m.rmse, 0.0, kExactTolM);
  EXPECT_EQ(*r[1].est_id, 6);
  EXPECT_GT(r[1].eval.ate->trans_m.rmse, 0.005);
  // Estimate 4 was eligible for object 2 at ATE 0: what made the difference is the matching.
  for (const auto& c : r[1].candidates) {
    if (c.est_id == 4) {
      ASSERT_TRUE(c.ate_rmse_m.has_value());
      EXPECT_NEAR(*c.ate_rmse_m, 0.0, kExactTolM);
    }
  }
  // With estimate 4 alone, object 2 is left without one and says why.
  const std::vector<eval::ObjectEval> alone =
      eval::evaluateObjects({{1, a}, {2, b}}, {{4, copy_a}}, {});
  EXPECT_FALSE(alone[1].est_id.has_value());
  EXPECT_NE(alone[1].eval.note.find("fits another ground-truth object better"), std::string::npos)
      << alone[1].eval.note;
  EXPECT_EQ(alone[1].eval.coverage, 0.0);  // no estimate left for it covers anything
  // A ground-truth object never in view has an empty trajectory: said so, not "covers 30% of
  // its 0 timestamps".
  const std::vector<eval::ObjectEval> unseen =
      eval::evaluateObjects({{5, Trajectory()}}, {{4, copy_a}}, {});
  EXPECT_FALSE(unseen[0].est_id.has_value());
  EXPECT_NE(unseen[0].eval.note.find("the ground truth has no poses"), std::string::npos)
      << unseen[0].eval.note;
}

TEST(Eval, TwoPosesGiveAnAteAsTheTumToolDoes) {
  // evaluate_ate.py needs 2 matches: here 0.05 m each after the alignment.
  Trajectory gt, est;
  gt.append(1.0, pose({0, 0, 0}, 0));
  gt.append(2.0, pose({1, 0, 0}, 0));
  est.append(1.0, pose({0, 0, 0}, 0));
  est.append(2.0, pose({1.1, 0, 0}, 0));
  const eval::AteResult ate = eval::computeAte(gt, est);
  EXPECT_EQ(ate.pairs, 2u);
  EXPECT_NEAR(ate.trans_m.rmse, 0.05, kExactTolM);
  // One pose: the message says the trajectory is too short, not that the clocks differ.
  Trajectory one;
  one.source = "camera.txt";
  one.append(1.0, pose({0, 0, 0}, 0));
  expectErrorContaining([&] { eval::computeAte(gt, one); }, {"'camera.txt' has only 1 pose"});
  Trajectory none;
  none.source = "empty.txt";
  expectErrorContaining([&] { eval::computeAte(gt, none); }, {"'empty.txt' has no poses"});
}

TEST(Eval, BadInputsAreErrorsNamingFiles) {
  const std::string dir = test::tempDir("eval");
  writeText(dir + "/est.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0\n");
  expectErrorContaining(
      [&] { eval::evaluatePaths(refGt(), dir + "/est.txt", eval::EvalOptions{}); },
      {dir + "/est.txt:3", "expected 8 fields"});
  writeText(dir + "/late.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n3.0 0 0 0 0 0 0 1\n");
  expectErrorContaining(
      [&] { eval::evaluatePaths(refGt(), dir + "/late.txt", eval::EvalOptions{}); },
      {"only 0 timestamps", "late.txt", "same clock"});
  expectErrorContaining([&] { eval::evaluatePaths(refGt(), dir, eval::EvalOptions{}); },
                        {"has no camera.txt"});
  expectErrorContaining([&] { eval::evaluatePaths(dir, refEst(), eval::EvalOptions{}); },
                        {"has no groundtruth.txt"});
  expectErrorContaining([&] { eval::evaluatePaths(dir + "/nope", refEst(), eval::EvalOptions{}); },
                        {"nope", "does not exist"});
  // A folder where a trajectory file should be.
  fs::create_directories(dir + "/g/groundtruth.txt");
  expectErrorContaining([&] { eval::evaluatePaths(dir + "/g", refEst(), eval::EvalOptions{}); },
                        {dir + "/g/groundtruth.txt' is a folder"});
  // Object files: two with the same id, an id beyond int.
  const std::string gt_dir = dir + "/gt", est_dir = dir + "/est";
  fs::create_directories(gt_dir + "/objects");
  fs::create_directories(est_dir);
  fs::copy_file(refGt(), gt_dir + "/groundtruth.txt");
  fs::copy_file(refGt(), gt_dir + "/objects/gt-object-1-camera.txt");
  fs::copy_file(refEst(), est_dir + "/camera.txt");
  fs::copy_file(refEst(), est_dir + "/object-3.txt");
  fs::copy_file(refEst(), est_dir + "/object-03.txt");
  expectErrorContaining([&] { eval::evaluatePaths(gt_dir, est_dir, eval::EvalOptions{}); },
                        {"object-3.txt", "object-03.txt", "both have id 3"});
  fs::remove(est_dir + "/object-03.txt");
  fs::copy_file(refEst(), est_dir + "/object-99999999999.txt");
  expectErrorContaining([&] { eval::evaluatePaths(gt_dir, est_dir, eval::EvalOptions{}); },
                        {"object-99999999999.txt", "is too large"});
}

// ---- emf eval -----------------------------------------------------------------------------------

std::string cli() { return EMF_CLI_PATH; }

TEST(EvalCli, PrintsTableAndWritesJsonAndPlot) {
  const std::string out = test::tempDir("eval-cli");
  std::string text;
  ASSERT_EQ(test::runCommand(
                cli() + " eval --gt " + refGt() + " --est " + refEst() + " --out " + out, &text),
            0)
      << text;
  EXPECT_NE(text.find("camera"), std::string::npos) << text;
  EXPECT_NE(text.find("0.013473"), std::string::npos) << text;
  EXPECT_NE(text.find("0.934480"), std::string::npos) << text;
  std::ifstream in(out + "/eval.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["camera"]["ate_m"]["pairs"], 786);
  EXPECT_NEAR(j["camera"]["ate_m"]["rmse"].get<double>(), 0.013473, kReferenceTolM);
  EXPECT_EQ(j["camera"]["rpe"]["pairs"], 753);
  EXPECT_NEAR(j["camera"]["rpe"]["trans_m"]["rmse"].get<double>(), 0.021217, kReferenceTolM);
  EXPECT_NEAR(j["camera"]["rpe"]["rot_deg"]["rmse"].get<double>(), 0.934480, kReferenceTolDeg);
  const cv::Mat png = cv::imread(out + "/eval.png");
  EXPECT_EQ(png.rows, 480);  // one row of panels: the camera
  EXPECT_EQ(png.cols, 1200);
  // Only eval.json and eval.png: no temporary files left.
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(out)) files += e.is_regular_file();
  EXPECT_EQ(files, 2u);
}

TEST(EvalCli, FoldersWithObjectsWriteIntoTheEstimateFolder) {
  const ObjectScene scene;
  std::string text;
  ASSERT_EQ(
      test::runCommand(cli() + " eval --gt " + scene.gt_dir + " --est " + scene.est_dir, &text), 0)
      << text;
  EXPECT_NE(text.find("object 1   object-7.txt"), std::string::npos) << text;
  EXPECT_NE(text.find("object 2   object-3.txt"), std::string::npos) << text;
  EXPECT_NE(text.find("matched to no ground-truth object: 5 9"), std::string::npos) << text;
  std::ifstream in(scene.est_dir + "/eval.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["objects"].size(), 2u);
  EXPECT_EQ(j["objects"][0]["est_id"], 7);
  EXPECT_EQ(j["objects"][1]["est_id"], 3);
  EXPECT_EQ(j["objects"][1]["coverage"], 1.0);
  EXPECT_EQ(cv::imread(scene.est_dir + "/eval.png").rows, 3 * 480);
}

TEST(EvalCli, UsageAndErrors) {
  std::string text;
  EXPECT_EQ(test::runCommand(cli() + " eval --help", &text), 0);
  EXPECT_NE(text.find("usage: emf eval"), std::string::npos) << text;
  EXPECT_EQ(test::runCommand(cli() + " eval --gt " + refGt(), &text), 2);
  EXPECT_NE(text.find("--gt and --est are required"), std::string::npos) << text;
  EXPECT_EQ(test::runCommand(cli() + " eval --gt /nonexistent-gt --est " + refEst(), &text), 1);
  EXPECT_NE(text.find("ground truth '/nonexistent-gt' does not exist"), std::string::npos) << text;
  EXPECT_EQ(test::runCommand(cli() + " eval --gt " + refGt() + " --est " + refEst() + " --delta x",
                             &text),
            1);
  EXPECT_NE(text.find("--delta must be a positive number"), std::string::npos) << text;
  EXPECT_EQ(
      test::runCommand(cli() + " eval --gt " + refGt() + " --est " + refEst() + " --min-coverage 2",
                       &text),
      1);
  EXPECT_NE(text.find("--min-coverage is a fraction of the timestamps in [0, 1], got '2'"),
            std::string::npos)
      << text;
}

// Surface coverage: a point is covered by a reference point within the distance, across cell
// borders and not beyond it.
TEST(SurfaceCoverage, CountsPointsWithAReferencePointWithinTheDistance) {
  const std::vector<Eigen::Vector3f> reference = {{0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}};
  const std::vector<Eigen::Vector3f> points = {
      {0.009f, 0.0f, 0.0f},     // within 1 cm of the first
      {-0.006f, 0.006f, 0.0f},  // 8.5 mm, in a neighbouring cell
      {0.0f, 0.0f, 0.011f},     // 1.1 cm: not covered
      {1.0f, 1.0f, 0.995f},     // the second
      {5.0f, 5.0f, 5.0f}};      // far from both
  EXPECT_EQ(eval::uncoveredPoints(reference, points, 0.01), 2u);
  EXPECT_DOUBLE_EQ(eval::coveredFraction(reference, points, 0.01), 0.6);
  EXPECT_DOUBLE_EQ(eval::coveredFraction(reference, {}, 0.01), 0.0);
  EXPECT_DOUBLE_EQ(eval::coveredFraction({}, points, 0.01), 0.0);
}

}  // namespace
}  // namespace emf::io
