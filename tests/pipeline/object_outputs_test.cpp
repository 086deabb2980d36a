// Per-object outputs written from constructed FrameOutcomes and read back: trajectories
// (T_object_camera at tracked frames), summaries and their JSON, meshes in the object frame,
// and the overlay / association images (sizes and pixel colours at known mask pixels).
#include "pipeline/object_outputs.h"

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"
#include "io/ply.h"
#include "io/trajectory.h"
#include "map/map_math.h"
#include "map/mesh.h"
#include "pipeline/run_outputs.h"
#include "test_support.h"

namespace emf::pipeline {
namespace {

// TUM files store translations and quaternions with 9 decimals.
constexpr double kTumPoseTolerance = 1e-8;
// Marching cubes on an exact sphere SDF: vertices within a tenth of a voxel of the surface.
constexpr float kMeshToleranceVoxels = 0.1f;

Eigen::Isometry3d pose(double x, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, 0.25, -1.5);
  return T;
}

ObjectOutcome object(int id, const std::string& cls, ObjectState state, double x) {
  ObjectOutcome o;
  o.id = id;
  o.class_name = cls;
  o.state = state;
  o.T_object_camera = pose(x, 0.1 * x);
  o.T_world_object = pose(-x, 0.2);
  o.existence = 0.5 + 0.01 * x;
  return o;
}

FrameOutcome frame(int64_t index, std::vector<ObjectOutcome> objects) {
  FrameOutcome f;
  f.index = index;
  f.timestamp = 10.0 + 0.5 * static_cast<double>(index);
  f.objects = std::move(objects);
  return f;
}

// Object 1 (car): tracked 0, 1, lost 2, tracked 3, 4. Object 2 (cup): appears at 1, invisible
// at 2, tracked 3, deleted at 4.
std::vector<FrameOutcome> sequence() {
  using S = ObjectState;
  std::vector<FrameOutcome> f;
  f.push_back(frame(0, {object(1, "car", S::kTracked, 0.0)}));
  f.push_back(frame(1, {object(1, "car", S::kTracked, 1.0), object(2, "cup", S::kTracked, 11.0)}));
  f.push_back(frame(2, {object(1, "car", S::kLost, 2.0), object(2, "cup", S::kInvisible, 12.0)}));
  f.push_back(frame(3, {object(1, "car", S::kTracked, 3.0), object(2, "cup", S::kTracked, 13.0)}));
  ObjectOutcome gone = object(2, "cup", S::kDeleted, 14.0);
  gone.deleted_reason = "existence 0.08 < 0.1";
  f.push_back(frame(4, {object(1, "car", S::kTracked, 4.0), gone}));
  return f;
}

TEST(ObjectOutputs, TrajectoriesHoldTrackedFramesOnly) {
  const std::string dir = test::tempDir("objout-traj");
  ObjectOutputs out(dir, true);
  for (const FrameOutcome& f : sequence()) out.add(f);
  const io::Trajectory car = io::readTrajectory(dir + "/object-1.txt");
  ASSERT_EQ(car.size(), 4u);
  const double xs[] = {0.0, 1.0, 3.0, 4.0};
  const int64_t frames[] = {0, 1, 3, 4};
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(car.stamps[i], 10.0 + 0.5 * static_cast<double>(frames[i]), 1e-6);
    EXPECT_TRUE(car.poses[i].isApprox(pose(xs[i], 0.1 * xs[i]), kTumPoseTolerance))
        << i << "\n"
        << car.poses[i].matrix();
  }
  const io::Trajectory cup = io::readTrajectory(dir + "/object-2.txt");
  ASSERT_EQ(cup.size(), 2u);
  EXPECT_TRUE(cup.poses[1].isApprox(pose(13.0, 1.3), kTumPoseTolerance));
}

TEST(ObjectOutputs, AConfirmedObjectsEarlierPosesComeFirst) {
  // Object 3 was created on frame 0 and confirmed on frame 2 (objects.confirm_detections): the
  // outcome of frame 2 carries its poses of frames 0 and 1, then reports it as tracked.
  const std::string dir = test::tempDir("objout-confirmed");
  ObjectOutputs out(dir, true);
  out.add(frame(0, {}));
  out.add(frame(1, {}));
  FrameOutcome f2 = frame(2, {object(3, "box", ObjectState::kTracked, 2.0)});
  ConfirmedObject c;
  c.id = 3;
  c.class_name = "box";
  for (int64_t i : {0, 1})
    c.earlier.push_back({i, 10.0 + 0.5 * static_cast<double>(i), pose(i, 0.1 * i)});
  f2.confirmed = {c};
  out.add(f2);
  const io::Trajectory box = io::readTrajectory(dir + "/object-3.txt");
  ASSERT_EQ(box.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(box.stamps[i], 10.0 + 0.5 * static_cast<double>(i), 1e-6);
    EXPECT_TRUE(box.poses[i].isApprox(pose(i, 0.1 * i), kTumPoseTolerance)) << i;
  }
  ASSERT_EQ(out.summaries().size(), 1u);
  EXPECT_EQ(out.summaries()[0].first_frame, 0);
  EXPECT_EQ(out.summaries()[0].frames_tracked, 3);
}

TEST(ObjectOutputs, EachFramesPosesAreInTheFileAsSoonAsItIsAdded) {
  // Nothing waits for the end of the run: after each add() the file holds every pose so far (a
  // process killed now keeps them), under a header naming the run.
  const std::string dir = test::tempDir("objout-stream");
  ObjectOutputs out(dir, true, "20261127T000000Z-42");
  size_t car_poses = 0;
  for (const FrameOutcome& f : sequence()) {
    out.add(f);
    for (const ObjectOutcome& o : f.objects)
      car_poses += (o.id == 1 && o.state == ObjectState::kTracked);
    EXPECT_EQ(io::readTrajectory(dir + "/object-1.txt").size(), car_poses) << "frame " << f.index;
  }
  EXPECT_EQ(car_poses, 4u);
  // The cup was deleted in frame 4: its file is closed and a stray pose for it changes nothing.
  out.add(frame(5, {object(2, "cup", ObjectState::kTracked, 15.0)}));
  EXPECT_EQ(io::readTrajectory(dir + "/object-2.txt").size(), 2u);
  EXPECT_NE(test::readText(dir + "/object-1.txt").find("emf run 20261127T000000Z-42"),
            std::string::npos);
  EXPECT_EQ(out.summaries()[0].trajectory_file, "object-1.txt");
}

TEST(ObjectOutputs, SummariesAndTheirJson) {
  const std::string dir = test::tempDir("objout-summary");
  ObjectOutputs out(dir, true);
  for (const FrameOutcome& f : sequence()) out.add(f);
  const std::vector<ObjectSummary> s = out.summaries();
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].id, 1);
  EXPECT_EQ(s[0].class_name, "car");
  EXPECT_EQ(s[0].first_frame, 0);
  EXPECT_EQ(s[0].last_frame, 4);
  EXPECT_EQ(s[0].frames_tracked, 4);
  EXPECT_EQ(s[0].frames_lost, 1);
  EXPECT_FALSE(s[0].deleted);
  EXPECT_DOUBLE_EQ(s[0].existence, 0.54);
  EXPECT_TRUE(s[0].T_world_object.isApprox(pose(-4.0, 0.2), 1e-12));
  EXPECT_EQ(s[0].trajectory_file, "object-1.txt");
  EXPECT_EQ(s[1].first_frame, 1);
  EXPECT_EQ(s[1].last_frame, 3);
  EXPECT_DOUBLE_EQ(s[1].last_timestamp, 11.5);
  EXPECT_EQ(s[1].frames_tracked, 2);
  EXPECT_EQ(s[1].frames_invisible, 1);
  EXPECT_TRUE(s[1].deleted);
  EXPECT_EQ(s[1].deleted_frame, 4);
  EXPECT_DOUBLE_EQ(s[1].deleted_timestamp, 12.0);
  EXPECT_EQ(s[1].deleted_reason, "existence 0.08 < 0.1");

  const nlohmann::json j = objectSummariesJson(s);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["class"], "car");
  EXPECT_EQ(j[0]["state"], "alive");
  EXPECT_EQ(j[0]["frames_tracked"], 4);
  EXPECT_FALSE(j[0].contains("deleted_reason"));
  EXPECT_DOUBLE_EQ(j[0]["T_world_object"][0][3].get<double>(), -4.0);
  EXPECT_EQ(j[1]["state"], "deleted");
  EXPECT_EQ(j[1]["deleted_frame"], 4);
  EXPECT_EQ(j[1]["deleted_reason"], "existence 0.08 < 0.1");
  EXPECT_EQ(j[1]["first_frame"], 1);
  EXPECT_EQ(j[1]["last_frame"], 3);
}

TEST(ObjectOutputs, DetectorStatsJson) {
  DetectorStats st;
  st.plugin = "maskfile";
  st.mode = "sequential";
  st.runs = 7;
  st.failures = 1;
  st.rejected = 2;
  st.dropped_frames = 3;
  st.detector_ms_median = 4.5;
  st.problems["frame # failed"] = 1;
  const nlohmann::json j = detectorStatsJson(st);
  EXPECT_EQ(j["plugin"], "maskfile");
  EXPECT_EQ(j["runs"], 7);
  EXPECT_EQ(j["failures"], 1);
  EXPECT_EQ(j["rejected_detections"], 2);
  EXPECT_EQ(j["dropped_frames"], 3);
  EXPECT_DOUBLE_EQ(j["detector_ms_median"].get<double>(), 4.5);
  EXPECT_EQ(j["problems"]["frame # failed"], 1);
}

TEST(ObjectOutputs, RepeatedTimestampKeepsTheFirstPose) {
  const std::string dir = test::tempDir("objout-stamp");
  ObjectOutputs out(dir, true);
  FrameOutcome a = frame(0, {object(1, "car", ObjectState::kTracked, 1.0)});
  FrameOutcome b = frame(1, {object(1, "car", ObjectState::kTracked, 2.0)});
  b.timestamp = a.timestamp;
  out.add(a);
  out.add(b);
  const io::Trajectory t = io::readTrajectory(dir + "/object-1.txt");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_TRUE(t.poses[0].isApprox(pose(1.0, 0.1), kTumPoseTolerance));
  EXPECT_EQ(out.summaries()[0].frames_tracked, 2);
}

// A host volume of 3^3 blocks (every block allocated) holding an exact sphere SDF.
map::VolumeHostData sphereVolume(const Eigen::Vector3f& centre, float radius, float voxel) {
  map::VolumeHostData h;
  h.dims_blocks = Eigen::Vector3i(3, 3, 3);
  h.voxel_size_m = voxel;
  h.truncation_m = 4 * voxel;
  h.T_world_volume = pose(2.0, 0.7);  // must not be applied: the mesh is in the object frame
  const int n = h.dims_blocks.prod();
  h.index.resize(static_cast<size_t>(n));
  h.voxels.resize(static_cast<size_t>(n) * map::kBlockVoxels);
  for (int lin = 0; lin < n; ++lin) {
    h.index[static_cast<size_t>(lin)] = lin;
    const Eigen::Vector3i base = map::blockCoords(h.dims_blocks, lin) * map::kBlockSize;
    for (int i = 0; i < map::kBlockVoxels; ++i) {
      const Eigen::Vector3i v = base + Eigen::Vector3i(i % 8, (i / 8) % 8, i / 64);
      const Eigen::Vector3f p = (v.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * voxel;
      h.voxels[static_cast<size_t>(lin) * map::kBlockVoxels + static_cast<size_t>(i)] =
          map::Voxel::make(((p - centre).norm() - radius) / h.truncation_m, 1.0f);
    }
  }
  return h;
}

TEST(ObjectOutputs, MeshIsInTheObjectFrame) {
  const std::string dir = test::tempDir("objout-mesh");
  ObjectOutputs out(dir, false);
  const float voxel = 0.01f, radius = 0.07f;
  const Eigen::Vector3f centre(0.12f, 0.12f, 0.12f);  // volume frame, metres
  out.add(frame(0, {object(5, "bottle", ObjectState::kTracked, 0.0)}));
  const map::VolumeHostData sphere = sphereVolume(centre, radius, voxel);
  out.writeMesh(5, sphere.view(), sphere.T_volume_initial);
  const map::Mesh m = io::readPly(dir + "/object-5.ply");
  ASSERT_GT(m.vertices.size(), 100u);
  float max_err = 0;
  for (const Eigen::Vector3f& v : m.vertices) {
    max_err = std::max(max_err, std::abs((v - centre).norm() - radius));
  }
  EXPECT_LT(max_err, kMeshToleranceVoxels * voxel);
  EXPECT_EQ(out.summaries()[0].mesh_file, "object-5.ply");
  // An object that never got a mesh reports none.
  out.add(frame(1, {object(6, "cup", ObjectState::kTracked, 0.0)}));
  EXPECT_EQ(out.summaries()[1].mesh_file, "");
  // After growth the volume origin moved by whole blocks (-low); the mesh stays in the
  // object's frame (the volume frame at creation), where the sphere is at centre - low.
  map::VolumeHostData grown = sphereVolume(centre, radius, voxel);
  const Eigen::Vector3d low_m(0.08, 0.0, 0.16);
  grown.T_volume_initial.translation() = low_m;
  out.writeMesh(7, grown.view(), grown.T_volume_initial);
  const map::Mesh g = io::readPly(dir + "/object-7.ply");
  ASSERT_EQ(g.vertices.size(), m.vertices.size());
  float max_grown_err = 0;
  for (const Eigen::Vector3f& v : g.vertices) {
    max_grown_err =
        std::max(max_grown_err, std::abs((v - (centre - low_m.cast<float>())).norm() - radius));
  }
  EXPECT_LT(max_grown_err, kMeshToleranceVoxels * voxel);
}

TEST(ObjectOutputs, ObjectColorsAreDistinct) {
  constexpr int kIds = 24;
  constexpr int kMinL1Distance = 40;  // sum of |dB| + |dG| + |dR| between any two ids
  for (int a = 1; a <= kIds; ++a) {
    for (int b = a + 1; b <= kIds; ++b) {
      const cv::Vec3b ca = objectColor(a), cb = objectColor(b);
      int d = 0;
      for (int c = 0; c < 3; ++c) d += std::abs(ca[c] - cb[c]);
      EXPECT_GE(d, kMinL1Distance) << a << " vs " << b;
    }
  }
}

TEST(ObjectOutputs, ImagesOverlayIdsAndFalseColourAssociation) {
  const std::string dir = test::tempDir("objout-images");
  ObjectOutputs out(dir, true);
  const int w = 40, h = 30;
  cv::Mat color(h, w, CV_8UC3, cv::Scalar(100, 150, 200));
  cv::Mat ids(h, w, CV_32S, cv::Scalar(-1));
  ids(cv::Rect(0, 0, 20, 30)).setTo(0);    // background
  ids(cv::Rect(5, 5, 6, 4)).setTo(3);      // object 3
  ids(cv::Rect(25, 10, 10, 10)).setTo(7);  // object 7
  cv::Mat q0(h, w, CV_32F, cv::Scalar(1.0f)), q3(h, w, CV_32F, cv::Scalar(0.0f));
  q3(cv::Rect(5, 5, 6, 4)).setTo(1.0f);
  q0.at<float>(0, 39) = std::nanf("");
  FrameOutcome f = frame(42, {});
  out.writeFrameImages(f, color, ids, {{0, q0}, {3, q3}});

  const cv::Mat overlay = cv::imread(dir + "/images/000042-objects.png", cv::IMREAD_COLOR);
  ASSERT_EQ(overlay.size(), cv::Size(w, h));
  auto blended = [&](int id) {
    const cv::Vec3b c = objectColor(id);
    cv::Vec3b v;
    const cv::Vec3b base(100, 150, 200);
    for (int ch = 0; ch < 3; ++ch) {
      v[ch] = cv::saturate_cast<uint8_t>((1 - kOverlayAlpha) * base[ch] + kOverlayAlpha * c[ch]);
    }
    return v;
  };
  EXPECT_EQ(overlay.at<cv::Vec3b>(6, 7), blended(3));
  EXPECT_EQ(overlay.at<cv::Vec3b>(15, 30), blended(7));
  EXPECT_EQ(overlay.at<cv::Vec3b>(20, 2), cv::Vec3b(100, 150, 200));  // background untouched
  EXPECT_EQ(overlay.at<cv::Vec3b>(0, 39), cv::Vec3b(100, 150, 200));  // nothing rendered
  EXPECT_NE(blended(3), blended(7));

  // JET: q = 1 is dark red, q = 0 dark blue (as OpenCV's colour map of 255 and 0).
  cv::Mat jet_ends, gray(1, 2, CV_8U);
  gray.at<uint8_t>(0, 0) = 0;
  gray.at<uint8_t>(0, 1) = 255;
  cv::applyColorMap(gray, jet_ends, cv::COLORMAP_JET);
  const cv::Mat qi0 = cv::imread(dir + "/images/000042-q0.png", cv::IMREAD_COLOR);
  const cv::Mat qi3 = cv::imread(dir + "/images/000042-q3.png", cv::IMREAD_COLOR);
  ASSERT_EQ(qi0.size(), cv::Size(w, h));
  ASSERT_EQ(qi3.size(), cv::Size(w, h));
  EXPECT_EQ(qi0.at<cv::Vec3b>(20, 20), jet_ends.at<cv::Vec3b>(0, 1));
  EXPECT_EQ(qi0.at<cv::Vec3b>(0, 39), cv::Vec3b(0, 0, 0));  // NaN: black
  EXPECT_EQ(qi3.at<cv::Vec3b>(6, 7), jet_ends.at<cv::Vec3b>(0, 1));
  EXPECT_EQ(qi3.at<cv::Vec3b>(20, 20), jet_ends.at<cv::Vec3b>(0, 0));
  EXPECT_NE(jet_ends.at<cv::Vec3b>(0, 0), jet_ends.at<cv::Vec3b>(0, 1));
}

TEST(ObjectOutputs, ColourOfAnotherSizeIsResizedAndBadImagesNameTheFrame) {
  const std::string dir = test::tempDir("objout-bad");
  ObjectOutputs out(dir, true);
  const cv::Mat color(60, 80, CV_8UC3, cv::Scalar(9, 9, 9));
  const cv::Mat ids(30, 40, CV_32S, cv::Scalar(0));
  out.writeFrameImages(frame(3, {}), color, ids, {});
  const cv::Mat overlay = cv::imread(dir + "/images/000003-objects.png", cv::IMREAD_COLOR);
  ASSERT_EQ(overlay.size(), cv::Size(40, 30));
  EXPECT_EQ(overlay.at<cv::Vec3b>(10, 10), cv::Vec3b(9, 9, 9));
  try {
    out.writeFrameImages(frame(8, {}), color, cv::Mat(30, 40, CV_16U, cv::Scalar(0)), {});
    FAIL() << "no error for CV_16U ids";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 8"), std::string::npos) << e.what();
  }
  try {
    out.writeFrameImages(frame(9, {}), color, ids, {{2, cv::Mat(10, 10, CV_32F, 0.5f)}});
    FAIL() << "no error for a wrong-size association map";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("frame 9: association map of volume 2 is 10x10"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace emf::pipeline
