// A small synthetic scene for pipeline tests of one object: a room (floor, walls and five static
// pillars for the camera to track against) with a 40 cm box standing on the floor, plus the
// box's exact silhouette as a detection and the SLAM options these tests share. The tests add
// their own camera path and further objects.
#pragma once

#include <opencv2/imgproc.hpp>
#include <string>

#include "core/frame.h"
#include "pipeline/config.h"
#include "synth/scene.h"

namespace emf::pipeline::test_scene {

inline synth::Material solidMaterial(float r, float g, float b) {
  return {{r, g, b}, {r, g, b}, synth::Texture::kSolid, 1.0};
}

/// The room with the box (object `box_id`, class "box") at (x, y) on the floor.
inline synth::Scene boxRoomScene(const std::string& name, int box_id, double box_x, double box_y) {
  using synth::at;
  synth::Scene s;
  s.name = name;
  const synth::Material floor{
      {0.3f, 0.45f, 0.6f}, {0.5f, 0.6f, 0.75f}, synth::Texture::kTiles, 0.4};
  const synth::Material walls{
      {0.8f, 0.85f, 0.88f}, {0.55f, 0.66f, 0.74f}, synth::Texture::kNoise, 0.3};
  const synth::Material solid = solidMaterial(0.3f, 0.3f, 0.7f);
  s.statics.push_back(synth::makePlane(at(0, 0, 0), floor));
  s.statics.push_back(synth::makeRoom({3.0, 2.5, 1.5}, at(0, 0.5, 1.3), walls));
  for (int i = 0; i < 5; ++i) {
    s.statics.push_back(synth::makeBox({0.15, 0.15, 0.3 + 0.1 * i},
                                       at(-1.2 + 0.8 * i, 2.2, 0.3 + 0.1 * i, 0.3 * i), solid));
  }
  synth::SceneObject box;
  box.id = box_id;
  box.class_name = "box";
  box.parts.push_back(synth::makeBox({0.2, 0.2, 0.2}, at(0, 0, 0.2), solid));
  box.trajectory.origin_m = Eigen::Vector3d(box_x, box_y, 0);
  s.objects.push_back(box);
  return s;
}

/// A yaw (rad, about the world's z) for a box the camera would face square-on. Square-on, a box
/// shows only its front and top, planes that leave its sideways translation free: without depth
/// noise its tracking is refused as degenerate, with noise the noise sets that translation
/// (docs/benchmarks.md, "A box seen square-on"). Turned, two of its sides fix it.
constexpr double kBoxYawRad = 0.4;
inline Eigen::Matrix3d yawed(double yaw_rad) {
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

/// The box room seen from 1 m up and 1.6 m in front of the box (at (0, 0.6) on the floor), the
/// camera swaying 8 cm sideways: the box stands in the middle of the image, floor and wall
/// around it.
inline synth::Scene standingBoxScene(const std::string& name, int box_id, int frames) {
  synth::Scene s = boxRoomScene(name, box_id, 0.0, 0.6);
  s.camera.path.origin_m = Eigen::Vector3d(0, -1.0, 1.0);
  s.camera.path.position_terms.push_back({Eigen::Vector3d(0.08, 0, 0.03), 0.3, 0.0});
  s.camera.target.origin_m = Eigen::Vector3d(0, 0.6, 0.2);
  s.default_frames = frames;
  return s;
}

/// Object `id`'s exact silhouette in a synthetic frame as a detection of class "box".
inline core::Detection exactDetection(const core::Frame& f, int id) {
  core::Detection det;
  det.id = 1;
  det.class_name = "box";
  det.score = 1.0f;
  cv::Mat(f.instance_ids == id).convertTo(det.mask, CV_32F, 1.0 / 255);
  det.box = cv::boundingRect(f.instance_ids == id);
  return det;
}

/// The error of an object's tracked pose where it matters to a user: a point of the object
/// (its frame, m), seen from the camera, estimated against true, as object-<id>.txt is
/// scored. The estimate's object frame (placed at creation) is mapped onto the true one on
/// the first call.
class PointError {
 public:
  PointError(int object_id, const Eigen::Vector3d& point) : id_(object_id), point_(point) {}
  /// Metres, for the estimate T_object_camera of frame `f`.
  double operator()(const core::Frame& f, const Eigen::Isometry3d& T_object_camera) {
    const Eigen::Isometry3d T_object_camera_gt =
        f.T_world_object_gt.at(id_).inverse() * *f.T_world_camera_gt;
    if (!started_) T_gt_est_ = T_object_camera_gt * T_object_camera.inverse();
    started_ = true;
    return ((T_gt_est_ * T_object_camera).inverse() * point_ -
            T_object_camera_gt.inverse() * point_)
        .norm();
  }

 private:
  int id_;
  Eigen::Vector3d point_;
  bool started_ = false;
  Eigen::Isometry3d T_gt_est_ = Eigen::Isometry3d::Identity();  // estimated frame -> true
};

/// A 64 MiB pool and a 5.12 m background at 2 cm: room enough for the small scene. The tests
/// detect their objects once: an object is reported from its first detection
/// (objects.confirm_detections 1; tests/pipeline/slam_confirm_test.cpp tests confirmation).
inline Config smallSceneConfig() {
  Config config;
  config.map.memory_mb = 64;
  config.map.background_voxel_m = 0.02;
  config.map.background_resolution = 256;
  config.objects.confirm_detections = 1;
  return config;
}

}  // namespace emf::pipeline::test_scene
