// The synth: source: query parsing and errors, determinism per seed, frame contents, and the
// consistency of depth, instance ids and ground-truth poses (points on an object's pixels lie
// on that object's surface).
#include "synth/synth_source.h"

#include <gtest/gtest.h>

#include <cstring>

#include "common/error.h"
#include "synth/presets.h"

namespace emf::synth {
namespace {

/// Back-projected pixels of object k vs. its surface (noise off): float depth rounding only.
constexpr double kSurfaceToleranceM = 1e-4;

std::string errorOf(const std::string& preset, const std::map<std::string, std::string>& query,
                    const core::SourceOptions& options = {}) {
  try {
    openSynthSource(preset, query, options);
  } catch (const IoError& e) {
    return e.what();
  }
  return "(no error)";
}

bool sameBytes(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

TEST(SynthSource, QueryParametersAndErrors) {
  auto src = openSynthSource("cars",
                             {{"frames", "7"},
                              {"seed", "3"},
                              {"width", "80"},
                              {"height", "60"},
                              {"det_every", "2"},
                              {"noise", "0"}},
                             {});
  EXPECT_EQ(src->size(), 7);
  EXPECT_EQ(src->intrinsics().width, 80);
  EXPECT_DOUBLE_EQ(src->intrinsics().fx, 525.0 / 8);
  EXPECT_NE(src->describe().find("'cars' (7 frames, 80x60, seed 3, noise off, detections every 2"),
            std::string::npos)
      << src->describe();

  std::string e = errorOf("kitchen", {});
  EXPECT_NE(e.find("unknown preset 'kitchen'"), std::string::npos) << e;
  EXPECT_NE(e.find("room, cars, occlusion, enter, apartment"), std::string::npos) << e;
  e = errorOf("room", {{"fps", "60"}});
  EXPECT_NE(e.find("unknown query parameter 'fps'"), std::string::npos) << e;
  EXPECT_NE(e.find("frames, seed, width, height, det_every, noise, threads"), std::string::npos)
      << e;
  e = errorOf("room", {{"frames", "12x"}});
  EXPECT_NE(e.find("synth:room: query parameter frames=12x is not an integer"), std::string::npos)
      << e;
  e = errorOf("room", {{"width", "4"}});
  EXPECT_NE(e.find("width=4 is out of range [8, 8192]"), std::string::npos) << e;
  e = errorOf("room", {{"seed", "-1"}});
  EXPECT_NE(e.find("seed=-1 is not an unsigned 64-bit integer"), std::string::npos) << e;
  e = errorOf("room", {{"noise", "maybe"}});
  EXPECT_NE(e.find("noise=maybe is not a boolean"), std::string::npos) << e;
}

TEST(SynthSource, SourceOptionsOverrideCameraAndCapFrames) {
  core::SourceOptions so;
  so.fx = 300;
  so.cy = 50;
  so.max_frames = 4;
  auto src = openSynthSource("room", {{"width", "160"}, {"height", "120"}}, so);
  EXPECT_EQ(src->size(), 4);
  EXPECT_DOUBLE_EQ(src->intrinsics().fx, 300.0);
  EXPECT_DOUBLE_EQ(src->intrinsics().fy, 131.25);  // 525 / 4: not overridden
  EXPECT_DOUBLE_EQ(src->intrinsics().cy, 50.0);
  auto defaults = openSynthSource("occlusion", {}, {});
  EXPECT_EQ(defaults->size(), 600);
  EXPECT_EQ(defaults->intrinsics().width, 640);
}

TEST(SynthSource, DeterministicPerSeed) {
  auto render = [](uint64_t seed, int64_t index) {
    SynthOptions o;
    o.preset = "cars";
    o.width = 160;
    o.height = 120;
    o.seed = seed;
    core::Frame f;
    SynthSource(o).renderFrame(index, &f);
    return f;
  };
  const core::Frame a = render(5, 30), b = render(5, 30), c = render(6, 30);
  EXPECT_TRUE(sameBytes(a.depth, b.depth));
  EXPECT_TRUE(sameBytes(a.color, b.color));
  ASSERT_TRUE(a.detections && b.detections);
  ASSERT_EQ(a.detections->size(), b.detections->size());
  for (size_t i = 0; i < a.detections->size(); ++i) {
    EXPECT_EQ((*a.detections)[i].class_name, (*b.detections)[i].class_name);
    EXPECT_EQ((*a.detections)[i].score, (*b.detections)[i].score);
    EXPECT_TRUE(sameBytes((*a.detections)[i].mask, (*b.detections)[i].mask));
  }
  EXPECT_FALSE(sameBytes(a.depth, c.depth));
  EXPECT_FALSE(sameBytes(a.color, c.color));
  // The seed changes the sensor, not the world.
  EXPECT_TRUE(sameBytes(a.instance_ids, c.instance_ids));
  EXPECT_TRUE(a.T_world_camera_gt->isApprox(*c.T_world_camera_gt, 0.0));
}

TEST(SynthSource, FramesCarryTimestampsGroundTruthAndDetections) {
  SynthOptions o;
  o.preset = "occlusion";
  o.frames = 7;
  o.width = 64;
  o.height = 48;
  o.detector.every_n_frames = 3;
  SynthSource src(o);
  core::Frame f;
  int64_t n = 0;
  while (src.next(f)) {
    EXPECT_EQ(f.index, n);
    EXPECT_DOUBLE_EQ(f.timestamp, n / 30.0);
    EXPECT_DOUBLE_EQ(f.rgb_timestamp, f.timestamp);
    char text[32];
    std::snprintf(text, sizeof(text), "%.6f", n / 30.0);
    EXPECT_EQ(f.timestamp_text, text);
    EXPECT_EQ(f.depth.type(), CV_32F);
    EXPECT_EQ(f.color.type(), CV_8UC3);
    EXPECT_EQ(f.instance_ids.type(), CV_16U);
    EXPECT_EQ(f.depth.size(), cv::Size(64, 48));
    EXPECT_EQ(f.detections.has_value(), n % 3 == 0) << n;
    ASSERT_TRUE(f.T_world_camera_gt);
    EXPECT_TRUE(f.T_world_camera_gt->isApprox(src.scene().camera.pose(n / 30.0), 1e-15));
    ASSERT_EQ(f.T_world_object_gt.size(), 3u);
    for (const auto& obj : src.scene().objects) {
      EXPECT_TRUE(f.T_world_object_gt.at(obj.id).isApprox(obj.trajectory.pose(n / 30.0), 1e-15));
    }
    ++n;
  }
  EXPECT_EQ(n, 7);
  EXPECT_FALSE(src.next(f));
}

/// Checks that every pixel labelled k on the given frames, back-projected with its exact depth
/// and the ground-truth poses, lies on object k's surface (in the object frame); returns the
/// number of pixels checked.
int checkDepthIdsAndPoses(const SynthSource& src, const std::vector<int64_t>& frames,
                          const std::string& what) {
  const core::Intrinsics K = src.intrinsics();
  int checked = 0;
  for (int64_t index : frames) {
    core::Frame f;
    src.renderFrame(index, &f);
    for (const auto& obj : src.scene().objects) {
      const Eigen::Isometry3d T_object_camera =
          f.T_world_object_gt.at(obj.id).inverse() * *f.T_world_camera_gt;
      double worst = 0.0;
      int worst_u = -1, worst_v = -1;
      for (int v = 0; v < K.height; ++v) {
        for (int u = 0; u < K.width; ++u) {
          if (f.instance_ids.at<uint16_t>(v, u) != obj.id) continue;
          const double z = f.depth.at<float>(v, u);
          const Eigen::Vector3d p_c((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z);
          const Eigen::Vector3d p_o = T_object_camera * p_c;
          double best = 1e9;
          for (const auto& part : obj.parts) {
            const Eigen::Vector3d q = part.T_parent_primitive.inverse() * p_o;
            best = std::min(best, std::fabs(signedDistance(part.geometry, {q.x(), q.y(), q.z()})));
          }
          if (best > worst) {
            worst = best;
            worst_u = u;
            worst_v = v;
          }
          ++checked;
        }
      }
      EXPECT_LT(worst, kSurfaceToleranceM)
          << what << " frame " << index << " object " << obj.id << " (" << obj.class_name << ") px "
          << worst_u << "," << worst_v;
    }
  }
  return checked;
}

// Every pixel labelled k, back-projected with its exact depth and the ground-truth poses, lies
// on object k's surface (in the object frame), for every dynamic preset.
TEST(SynthSource, DepthIdsAndPosesAreConsistent) {
  for (const std::string preset : {"cars", "occlusion", "enter"}) {
    SynthOptions o;
    o.preset = preset;
    o.width = 160;
    o.height = 120;
    o.noise = false;
    EXPECT_GT(checkDepthIdsAndPoses(SynthSource(o), {100, 200, 250}, preset), 300) << preset;
  }
}

// The same for generated scenes: every motion family (moving parts, pivots, pushes) renders
// where its ground truth says.
TEST(SynthSource, GeneratedScenesDepthIdsAndPosesAreConsistent) {
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    SynthOptions o =
        synthOptionsFromQuery("random", {{"seed", std::to_string(seed)}}, core::SourceOptions{});
    o.width = 160;
    o.height = 120;
    o.noise = false;
    EXPECT_GT(
        checkDepthIdsAndPoses(SynthSource(o), {100, 250, 420, 550}, "seed " + std::to_string(seed)),
        300);
  }
}

}  // namespace
}  // namespace emf::synth
