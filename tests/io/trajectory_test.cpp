// TUM trajectory files, timestamp association (associate.py semantics), pose interpolation.
#include "io/trajectory.h"

#include <filesystem>
#include <fstream>

#include "common/error.h"
#include "io_test_util.h"
#include "test_support.h"

namespace emf::io {
namespace {

using testing::expectErrorContaining;
using testing::writeText;

// Written values are printed with 9 decimals.
constexpr double kWriteRoundTripTol = 1e-9;

Eigen::Isometry3d makePose(double tx, double ty, double tz, double yaw, double pitch) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return T;
}

TEST(Trajectory, ReadsTheReferenceGroundTruth) {
  const auto t = readTrajectory(test::dataPath("trajectories/freiburg1_xyz-groundtruth.txt"));
  ASSERT_EQ(t.size(), 3000u);
  EXPECT_EQ(t.stamps[0], 1305031098.6659);
  // First line: 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986
  EXPECT_EQ(t.poses[0].translation(), Eigen::Vector3d(1.3563, 0.6305, 1.6380));
  const Eigen::Quaterniond q = Eigen::Quaterniond(-0.3986, 0.6132, 0.5962, -0.3311).normalized();
  EXPECT_LT((t.poses[0].rotation() - q.toRotationMatrix()).norm(), 1e-12);
}

TEST(Trajectory, WriteReadRoundTripIsAtomic) {
  const std::string dir = test::tempDir("traj");
  Trajectory t;
  for (int i = 0; i < 20; ++i) {
    t.append(100.0 + i / 30.0, makePose(0.1 * i, -0.2 * i, 1.0 + 0.01 * i, 0.05 * i, -0.02 * i));
  }
  const std::string path = dir + "/camera.txt";
  writeTrajectory(path, t, "emf test");
  const auto r = readTrajectory(path);
  ASSERT_EQ(r.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_NEAR(r.stamps[i], t.stamps[i], 1e-6);
    EXPECT_LT((r.poses[i].matrix() - t.poses[i].matrix()).cwiseAbs().maxCoeff(),
              kWriteRoundTripTol * 10);
  }
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
  EXPECT_THROW(t.append(t.stamps.back(), Eigen::Isometry3d::Identity()), InvalidArgument);
}

// A rotation that drifted from orthonormal (round-off over a long run; here exaggerated to a
// 1 % scale) is written as a unit quaternion, so that the file reads back.
constexpr double kUnitQuaternionTol = 1e-8;
constexpr double kDriftScale = 0.01;  // the rotation read back is the nearest one within that

TEST(Trajectory, AnUnfinishedLastLineOfAKilledWriterIsIgnored) {
  // SIGKILL can stop a write(2) between two pages: the file ends in part of a line.
  const std::string path = test::tempDir("traj-cut") + "/camera.txt";
  std::ofstream(path) << "# timestamp tx ty tz qx qy qz qw\n"
                      << "1.000000 0.1 0.2 0.3 0 0 0 1\n"
                      << "1.033333 0.1 0.2 0.3 0 0";
  const Trajectory t = readTrajectory(path);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_NEAR(t.poses[0].translation().z(), 0.3, 1e-12);
  // Cut inside a number: the quaternion is not a rotation: also an unfinished line.
  std::ofstream(path, std::ios::app) << " 0.9";
  EXPECT_EQ(readTrajectory(path).size(), 1u);
  // The same line with its newline is a broken file, named.
  std::ofstream(path, std::ios::app) << "\n";
  EXPECT_THROW(readTrajectory(path), IoError);
  // A complete last line without a newline (a hand-written file) is read.
  std::ofstream(path) << "1.000000 0.1 0.2 0.3 0 0 0 1";
  EXPECT_EQ(readTrajectory(path).size(), 1u);
}

TEST(Trajectory, WritesUnitQuaternionsForDriftedRotations) {
  const std::string dir = test::tempDir("traj_drift");
  Trajectory t;
  Eigen::Isometry3d T = makePose(0.5, 0.2, 1.0, 0.3, 0.1);
  T.linear() *= 1.0 - kDriftScale;
  t.append(1.0, T);
  writeTrajectory(dir + "/object-1.txt", t);
  const auto r = readTrajectory(dir + "/object-1.txt");
  ASSERT_EQ(r.size(), 1u);
  const Eigen::Matrix3d R = r.poses[0].rotation();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), kUnitQuaternionTol);
  EXPECT_LT((R - makePose(0, 0, 0, 0.3, 0.1).rotation()).norm(), kDriftScale);
}

TEST(Trajectory, AcceptsCommasTabsAndComments) {
  const std::string path = test::tempDir("traj") + "/t.txt";
  writeText(path, "# c\n1.0,0,0,0,0,0,0,1\r\n\n2.0\t1 2 3 0 0 0 1\n");
  const auto t = readTrajectory(path);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.poses[1].translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(Trajectory, BadLinesNameFileAndLine) {
  const std::string dir = test::tempDir("traj");
  const std::string p = dir + "/bad.txt";
  writeText(p, "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  expectErrorContaining([&] { readTrajectory(p); }, {p + ":3", "expected 8 fields", "got 7"});
  writeText(p, "1.0 0 0 0 0 0 0 1\n2.0 0 x 0 0 0 0 1\n");
  expectErrorContaining([&] { readTrajectory(p); }, {p + ":2", "ty 'x' is not a number"});
  writeText(p, "1.0 0 0 0 0 0 0 1\n2.0 0 0 nan 0 0 0 1\n");
  expectErrorContaining([&] { readTrajectory(p); }, {p + ":2", "tz is 'nan'"});
  writeText(p, "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 0.5\n");
  expectErrorContaining([&] { readTrajectory(p); }, {p + ":2", "norm 0.5", "not a rotation"});
  writeText(p, "1.0 0 0 0 0 0 0 1\n2.0 0 1e308 0 0 0 0 1\n");
  expectErrorContaining([&] { readTrajectory(p); },
                        {p + ":2", "ty = 1e308 m is beyond +-1000000 m"});
  writeText(p, "1.0 0 0 0 0 0 0 1\n\n1.0 0 0 0 0 0 0 1\n");
  expectErrorContaining([&] { readTrajectory(p); }, {p + ":3", "does not increase"});
  expectErrorContaining([&] { readTrajectory(dir + "/missing.txt"); },
                        {"missing.txt", "missing or unreadable"});
}

TEST(AssociateStamps, GreedyBySmallestDifferenceEachStampOnce) {
  // Candidates (diff): (0,.004)=.004 (0,.012)=.012 (.01,.004)=.006 (.01,.012)=.002.
  // Greedy: (.01,.012) then (0,.004); 0.05 has nothing within 0.02.
  const auto m = associateStamps({0.0, 0.01, 0.05}, {0.004, 0.012, 0.2}, 0.02);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].first, 0u);
  EXPECT_EQ(m[0].second, 0u);
  EXPECT_EQ(m[1].first, 1u);
  EXPECT_EQ(m[1].second, 1u);
  // Not nearest-neighbour: 0.015 takes 0.01 (diff .005) and 0 is left without a match.
  const auto g = associateStamps({0.0, 0.015}, {0.01}, 0.02);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_EQ(g[0].first, 1u);
  // The threshold is strict (|a - b| < max), as in associate.py.
  EXPECT_TRUE(associateStamps({0.0}, {0.5}, 0.5).empty());
  // Unsorted input works; output sorted by the first list's stamps.
  const auto u = associateStamps({3.0, 1.0, 2.0}, {2.001, 0.999, 3.002}, 0.02);
  ASSERT_EQ(u.size(), 3u);
  EXPECT_EQ(u[0].first, 1u);
  EXPECT_EQ(u[0].second, 1u);
  EXPECT_EQ(u[2].first, 0u);
  EXPECT_EQ(u[2].second, 2u);
}

TEST(PoseAt, InterpolatesOrTakesNearestWithinTheLimit) {
  Trajectory t;
  t.append(1.0, makePose(0, 0, 0, 0, 0));
  t.append(1.01, makePose(1, 2, 3, 0.2, 0));
  t.append(2.0, makePose(5, 5, 5, 0, 0));
  const auto mid = poseAt(t, 1.0025, 0.02);
  ASSERT_TRUE(mid.has_value());
  EXPECT_LT((mid->translation() - Eigen::Vector3d(0.25, 0.5, 0.75)).norm(), 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->rotation()).angle(), 0.05, 1e-12);
  const auto exact = poseAt(t, 2.0, 0.02);
  ASSERT_TRUE(exact.has_value());
  EXPECT_EQ(exact->translation(), Eigen::Vector3d(5, 5, 5));
  // 1.99 is 0.98 s after 1.01 but 0.01 s before 2.0: nearest.
  const auto near = poseAt(t, 1.99, 0.02);
  ASSERT_TRUE(near.has_value());
  EXPECT_EQ(near->translation(), Eigen::Vector3d(5, 5, 5));
  EXPECT_FALSE(poseAt(t, 1.5, 0.02).has_value());
  EXPECT_FALSE(poseAt(t, 0.9, 0.02).has_value());
}

}  // namespace
}  // namespace emf::io
