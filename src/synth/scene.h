// Description of a synthetic scene: static primitives (room, furniture), rigid objects made of
// primitives with scripted trajectories, and a hand-held camera rig. World frame W is z-up with
// the floor at z = 0; every object has its own frame O (origin on its base or at its centre,
// as its preset says).
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "synth/primitives.h"
#include "synth/trajectory.h"

namespace emf::synth {

/// Procedural surface pattern, evaluated in the primitive's local frame (so it moves with it).
enum class Texture {
  kSolid,    // albedo only
  kChecker,  // 3-D checkerboard of cell scale_m alternating albedo / albedo2
  kStripes,  // smooth stripes across local x with period scale_m
  kNoise,    // value noise of feature size scale_m blending albedo and albedo2
  kTiles,    // checker modulated by noise (floors, wood)
};

/// Colours are linear BGR in [0, 1].
struct Material {
  std::array<float, 3> albedo_bgr{0.7f, 0.7f, 0.7f};
  std::array<float, 3> albedo2_bgr{0.4f, 0.4f, 0.4f};
  Texture texture = Texture::kSolid;
  double scale_m = 0.1;
};

/// Albedo (BGR, [0, 1]) of `material` at point p of the primitive's local frame.
std::array<float, 3> albedoAt(const Material& material, V3 p);

/// One primitive placed in its parent frame (world for statics, O for object parts).
struct Primitive {
  PrimitiveGeometry geometry;
  Eigen::Isometry3d T_parent_primitive = Eigen::Isometry3d::Identity();
  Material material;
};

/// A rigid object: the union of its parts, moving along its trajectory (T_world_object).
struct SceneObject {
  int id = 1;  // 1..n, the value in instance-id images
  std::string class_name;
  std::vector<Primitive> parts;
  Trajectory trajectory;
  /// How it moves, for reports: the generated scenes' motion families joined by '+' (e.g.
  /// "rock+push"), "still" for an object that never moves; empty in the presets.
  std::string motion;
};

struct Scene {
  std::string name;
  std::string description;  // what is in the scene and what moves when (for READMEs)
  std::vector<Primitive> statics;
  std::vector<SceneObject> objects;
  CameraRig camera;
  int default_frames = 300;
  double fps = 30.0;

  double timeOf(int64_t frame_index) const { return static_cast<double>(frame_index) / fps; }
};

/// The box around an object's parts in its own frame (unbounded parts are skipped).
Eigen::AlignedBox3d objectBounds(const SceneObject& object);

/// Objects count as visible in a frame when at least this fraction of the image shows them
/// (0.1 %: 307 pixels at 640x480).
constexpr double kMinVisibleFraction = 0.001;
/// The pixel count kMinVisibleFraction gives for an image (at least 1).
int minVisiblePixels(int width, int height);
/// Pixel counts per instance id (index = id) of a CV_16U instance image.
std::vector<int> instancePixelCounts(const cv::Mat& instance_ids);

// Helpers for building scenes (poses in the parent frame, metres / radians).
Primitive makeBox(V3 half_extents_m, const Eigen::Isometry3d& T_parent_primitive,
                  const Material& material);
Primitive makeRoundedBox(V3 half_extents_m, double radius_m,
                         const Eigen::Isometry3d& T_parent_primitive, const Material& material);
Primitive makeSphere(double radius_m, const Eigen::Isometry3d& T_parent_primitive,
                     const Material& material);
Primitive makeCylinder(double radius_m, double half_height_m,
                       const Eigen::Isometry3d& T_parent_primitive, const Material& material);
Primitive makeCapsule(double radius_m, double half_length_m,
                      const Eigen::Isometry3d& T_parent_primitive, const Material& material);
Primitive makePlane(const Eigen::Isometry3d& T_parent_primitive, const Material& material);
Primitive makeRoom(V3 half_extents_m, const Eigen::Isometry3d& T_parent_primitive,
                   const Material& material);
/// Translation then rotation about z (yaw), y (pitch), x (roll), radians.
Eigen::Isometry3d at(double x, double y, double z, double yaw = 0, double pitch = 0,
                     double roll = 0);

}  // namespace emf::synth
