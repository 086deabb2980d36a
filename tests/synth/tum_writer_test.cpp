// TUM writer and atomic files: every file of a written synthetic sequence read back and compared
// with the frames (depth quantised at 1/5000 m, colour exact, poses to 1e-6, masks and their
// text), visibility-filtered object trajectories, errors naming the file/frame.
#include "io/tum_writer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "common/error.h"
#include "io/atomic_output.h"
#include "synth/synth_source.h"
#include "test_support.h"

namespace emf::io {
namespace {
namespace fs = std::filesystem;

/// Pose read back from text vs. the exact one (translation metres / quaternion components).
constexpr double kPoseTolerance = 1e-6;

std::vector<std::string> lines(const std::string& path, bool skip_comments = true) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    if (skip_comments && !line.empty() && line[0] == '#') continue;
    out.push_back(line);
  }
  return out;
}

/// Parses "t tx ty tz qx qy qz qw" into (timestamp text, pose).
std::pair<std::string, Eigen::Isometry3d> parsePose(const std::string& line) {
  std::istringstream is(line);
  std::string t;
  double tx, ty, tz, qx, qy, qz, qw;
  is >> t >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
  EXPECT_FALSE(is.fail()) << line;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return {t, T};
}

void expectPoseNear(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                    const std::string& what) {
  EXPECT_LT((a.translation() - b.translation()).cwiseAbs().maxCoeff(), kPoseTolerance) << what;
  EXPECT_LT((a.linear() - b.linear()).cwiseAbs().maxCoeff(), 2 * kPoseTolerance) << what;
}

TEST(TumWriter, WritesEveryFileWithTheFramesContent) {
  const std::string dir = test::tempDir("tum-writer") + "/seq";
  synth::SynthOptions o;
  o.preset = "occlusion";
  o.frames = 6;
  o.width = 96;
  o.height = 72;
  o.detector.every_n_frames = 2;
  o.detector.false_positive_rate = 1.0;  // at least one detection per detection frame
  synth::SynthSource src(o);
  TumWriterOptions wo;
  wo.readme_about = "About this test sequence.";
  std::vector<core::Frame> frames;
  {
    TumWriter writer(dir, src.intrinsics(), wo);
    core::Frame f;
    // Start late so the suitcase (object 2) enters view during the written frames.
    for (int64_t i = 0; i < 6; ++i) {
      src.renderFrame(60 + 20 * i, &f);
      f.index = i;
      writer.write(f);
      frames.push_back(f);
    }
    writer.finish();
    EXPECT_EQ(writer.framesWritten(), 6);
  }

  const auto rgb = lines(dir + "/rgb.txt"), depth = lines(dir + "/depth.txt"),
             assoc = lines(dir + "/associations.txt"), gt = lines(dir + "/groundtruth.txt");
  ASSERT_EQ(rgb.size(), 6u);
  ASSERT_EQ(depth.size(), 6u);
  ASSERT_EQ(assoc.size(), 6u);
  ASSERT_EQ(gt.size(), 6u);
  EXPECT_EQ(lines(dir + "/rgb.txt", false).size(), 9u);  // 3 comment lines, as TUM's
  for (size_t i = 0; i < frames.size(); ++i) {
    const core::Frame& f = frames[i];
    const std::string t = f.timestamp_text;
    EXPECT_EQ(rgb[i], t + " rgb/" + t + ".png");
    EXPECT_EQ(depth[i], t + " depth/" + t + ".png");
    EXPECT_EQ(assoc[i], t + " rgb/" + t + ".png " + t + " depth/" + t + ".png");
    // Depth: uint16 PNG = round(depth * 5000), NaN -> 0.
    const cv::Mat d16 = cv::imread(dir + "/depth/" + t + ".png", cv::IMREAD_UNCHANGED);
    ASSERT_EQ(d16.type(), CV_16U) << t;
    ASSERT_EQ(d16.size(), f.depth.size());
    int invalid = 0;
    for (int v = 0; v < d16.rows; ++v) {
      for (int u = 0; u < d16.cols; ++u) {
        const float z = f.depth.at<float>(v, u);
        const uint16_t expected =
            std::isnan(z) ? 0 : static_cast<uint16_t>(std::lround(z * 5000.0));
        invalid += expected == 0;
        ASSERT_EQ(d16.at<uint16_t>(v, u), expected) << t << " " << u << "," << v;
      }
    }
    EXPECT_GT(invalid, 0);  // noisy depth has holes
    const cv::Mat color = cv::imread(dir + "/rgb/" + t + ".png", cv::IMREAD_UNCHANGED);
    ASSERT_EQ(color.type(), CV_8UC3);
    EXPECT_EQ(cv::countNonZero(color.reshape(1) != f.color.reshape(1)), 0) << t;
    // Ground truth.
    const auto [gt_t, T] = parsePose(gt[i]);
    EXPECT_EQ(gt_t, t);
    expectPoseNear(T, *f.T_world_camera_gt, "groundtruth " + t);
    // Detections on frames 0, 2, 4.
    const bool has_masks = fs::exists(dir + "/masks/" + t + ".png");
    EXPECT_EQ(has_masks, f.detections.has_value()) << t;
    if (!f.detections) continue;
    const cv::Mat ids = cv::imread(dir + "/masks/" + t + ".png", cv::IMREAD_UNCHANGED);
    ASSERT_EQ(ids.type(), CV_16U);
    ASSERT_EQ(ids.size(), f.depth.size());
    const auto det_lines = lines(dir + "/masks/" + t + ".txt", false);
    // Detections hidden entirely under higher-scoring ones are not listed.
    std::vector<const core::Detection*> listed;
    for (const auto& d : *f.detections) {
      if (cv::countNonZero(ids == d.id) > 0) listed.push_back(&d);
    }
    ASSERT_EQ(det_lines.size(), listed.size());
    ASSERT_FALSE(det_lines.empty());
    for (size_t k = 0; k < det_lines.size(); ++k) {
      const core::Detection& d = *listed[k];
      std::istringstream is(det_lines[k]);
      int id;
      std::string cls;
      double score;
      is >> id >> cls >> score;
      EXPECT_EQ(id, d.id);
      EXPECT_EQ(cls, maskClassToken(d.class_name));
      EXPECT_EQ(cls.find(' '), std::string::npos);
      EXPECT_NEAR(score, d.score, 1e-6);
      // Pixels of this id are inside its mask; its mask pixels carry its id unless a
      // higher-scoring detection overlaps there.
      const cv::Mat mine = ids == d.id;
      EXPECT_EQ(cv::countNonZero(mine & (d.mask < 0.5f)), 0);
      bool top = true;
      for (const auto& other : *f.detections) {
        if (other.id != d.id && other.score > d.score)
          top = top && cv::countNonZero((other.mask >= 0.5f) & (d.mask >= 0.5f)) == 0;
      }
      if (top) {
        EXPECT_EQ(cv::countNonZero(mine), cv::countNonZero(d.mask >= 0.5f));
      }
    }
    // Every painted pixel belongs to a listed detection.
    cv::Mat listed_pixels = cv::Mat::zeros(ids.size(), CV_8U);
    for (const core::Detection* d : listed) listed_pixels |= (ids == d->id);
    EXPECT_EQ(cv::countNonZero((ids > 0) & ~listed_pixels), 0);
  }
  // Class names with spaces are written with '_' (the teddy bear is usually detected).
  EXPECT_EQ(maskClassToken("teddy bear"), "teddy_bear");

  // Calibration.
  const auto calib = lines(dir + "/calibration.txt");
  ASSERT_EQ(calib.size(), 1u);
  EXPECT_EQ(calib[0], "78.750000 78.750000 47.500000 35.500000 96 72");

  // Objects: world poses every frame; camera-in-object poses only where visible.
  const int min_pixels = synth::minVisiblePixels(96, 72);
  for (int id : {1, 2, 3}) {
    const auto world = lines(dir + "/objects/gt-object-" + std::to_string(id) + "-world.txt");
    const auto cam = lines(dir + "/objects/gt-object-" + std::to_string(id) + "-camera.txt");
    ASSERT_EQ(world.size(), 6u);
    size_t c = 0;
    for (size_t i = 0; i < frames.size(); ++i) {
      const core::Frame& f = frames[i];
      const auto [tw, Tw] = parsePose(world[i]);
      EXPECT_EQ(tw, f.timestamp_text);
      expectPoseNear(Tw, f.T_world_object_gt.at(id), "object world");
      const auto counts = synth::instancePixelCounts(f.instance_ids);
      const bool visible = static_cast<size_t>(id) < counts.size() && counts[id] >= min_pixels;
      if (!visible) continue;
      ASSERT_LT(c, cam.size()) << "object " << id;
      const auto [tc, Tc] = parsePose(cam[c++]);
      EXPECT_EQ(tc, f.timestamp_text);
      expectPoseNear(Tc, f.T_world_object_gt.at(id).inverse() * *f.T_world_camera_gt,
                     "object camera");
    }
    EXPECT_EQ(c, cam.size()) << "object " << id;
  }
  // The suitcase is out of view in the first written frame: fewer camera lines than frames.
  EXPECT_LT(lines(dir + "/objects/gt-object-2-camera.txt").size(), 6u);

  const auto readme = lines(dir + "/README.md", false);
  std::string all;
  for (const auto& l : readme) all += l + "\n";
  EXPECT_NE(all.find("About this test sequence."), std::string::npos);
  EXPECT_NE(all.find("masks/<t>.png"), std::string::npos);
  EXPECT_NE(all.find("det_id class_name score"), std::string::npos);
  // Atomic writes leave no temporaries behind.
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
}

TEST(TumWriter, RejectsBadFramesNamingThem) {
  const std::string dir = test::tempDir("tum-writer-bad");
  core::Intrinsics k;
  k.fx = k.fy = 50;
  k.cx = 15.5;
  k.cy = 11.5;
  k.width = 32;
  k.height = 24;
  TumWriter writer(dir, k);
  core::Frame f;
  f.index = 7;
  f.timestamp_text = "0.233333";
  f.depth = cv::Mat(24, 32, CV_16U, cv::Scalar(1000));
  f.color = cv::Mat(24, 32, CV_8UC3, cv::Scalar(1, 2, 3));
  try {
    writer.write(f);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("frame 7 (t=0.233333) has no CV_32F depth"),
              std::string::npos)
        << e.what();
  }
  f.depth = cv::Mat(20, 32, CV_32F, cv::Scalar(1.0));
  try {
    writer.write(f);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("depth is 32x20 but the calibration says 32x24"),
              std::string::npos)
        << e.what();
  }
  f.depth = cv::Mat(24, 32, CV_32F, cv::Scalar(20.0));  // beyond 13.1 m: not representable
  writer.write(f);
  writer.finish();
  EXPECT_THROW(writer.write(f), IoError);
  const cv::Mat d16 = cv::imread(dir + "/depth/0.233333.png", cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::countNonZero(d16), 0);
}

TEST(AtomicFile, ReplacesContentAndNamesUnwritablePaths) {
  const std::string dir = test::tempDir("atomic");
  const std::string path = dir + "/a.txt";
  writeFileAtomically(path, "first");
  writeFileAtomically(path, "second");
  EXPECT_EQ(lines(path, false), std::vector<std::string>{"second"});
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  try {
    writeFileAtomically(dir + "/missing/b.txt", "x");
    FAIL();
  } catch (const IoError& e) {
    // Names the destination and says what to check.
    EXPECT_NE(std::string(e.what()).find("to write '" + dir + "/missing/b.txt'"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("check that the folder exists"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(writeImageAtomically(dir + "/noext", cv::Mat(2, 2, CV_8U)), IoError);
  writeImageAtomically(dir + "/img.png", cv::Mat(3, 4, CV_16U, cv::Scalar(4242)));
  const cv::Mat back = cv::imread(dir + "/img.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_16U);
  EXPECT_EQ(back.at<uint16_t>(2, 3), 4242);
}

}  // namespace
}  // namespace emf::io
