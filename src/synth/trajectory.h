// Scripted smooth 6-DoF trajectories of the synthetic world: sums of sinusoids, eased moves
// (C2 "smootherstep" segments) and an optional "starts still, then accelerates" time warp.
// Poses are T_world_object (object frame O to world frame W, metres / radians); the world is
// z-up with the floor at z = 0.
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace emf::synth {

/// amplitude * sin(2 pi frequency_hz * s + phase_rad), per axis, times an envelope in clip time
/// t: 0 before on_s, rising with smootherstep over ramp_s, 1 until off_s - ramp_s, falling to 0
/// at off_s. The default window is always on.
struct Sinusoid {
  Eigen::Vector3d amplitude = Eigen::Vector3d::Zero();  // metres, or radians (rotation vector)
  double frequency_hz = 0.0;
  double phase_rad = 0.0;
  double on_s = -1e300, off_s = 1e300, ramp_s = 1.0;

  /// The envelope at clip time t, in [0, 1].
  double envelope(double t) const;
};

/// A move from start_s to end_s (clip time t, seconds): translation delta_m (world frame) and
/// rotation vector delta_rad (world frame, about the object origin), eased with smootherstep so
/// velocity and acceleration are continuous; the move's full delta holds after end_s.
struct EasedMove {
  double start_s = 0.0, end_s = 1.0;
  Eigen::Vector3d delta_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d delta_rad = Eigen::Vector3d::Zero();
};

/// One sample of a keyframed trajectory: the pose T_world_object at clip time t_s.
struct PoseKey {
  double t_s = 0.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

/// T_world_object(t) = [R(t) | p(t)] with
///   s(t)  = 0 before still_until_s, then accelerating uniformly over ramp_s to unit speed
///   p(t)  = origin_m + sum sin-terms(s) + sum moves(t)
///   R(t)  = Rz(heading) * exp(sum moves rotation + sum rotation sin-terms(s)) * R0
/// where heading (face_velocity) is the direction of the horizontal velocity of the
/// sinusoidal part, so a car points where it drives.
struct Trajectory {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  std::vector<Sinusoid> position_terms;
  std::vector<Sinusoid> rotation_terms;  // rotation vectors (rad), body frame after heading
  std::vector<EasedMove> moves;
  bool face_velocity = false;
  double still_until_s = 0.0;  // > 0: the object is at rest (s = 0) until this time
  double ramp_s = 1.0;         // duration of the uniform acceleration after still_until_s
  /// Keyframes in increasing time (the generated scenes sample their motions into them): when
  /// given, they alone define the pose, interpolated linearly (position) and by slerp
  /// (rotation) between neighbours and held before the first and after the last.
  std::vector<PoseKey> keys;

  /// Pose at clip time t (seconds).
  Eigen::Isometry3d pose(double t) const;
  /// Position only (cheaper; used for camera paths and look-at targets).
  Eigen::Vector3d position(double t) const;
  /// The warped time s(t).
  double warpedTime(double t) const;
};

/// A hand-held-like camera: centre on a smooth path, looking at a smoothly moving target with
/// world +z up, plus small rotational tremor (camera frame: x right, y down, z forward).
struct CameraRig {
  Trajectory path;                   // camera centre (position part used)
  Trajectory target;                 // look-at point (position part used)
  std::vector<Sinusoid> tremor_rad;  // rotation vector terms in the camera frame

  /// T_world_camera at clip time t (seconds).
  Eigen::Isometry3d pose(double t) const;
};

/// smootherstep on [0, 1]: 6x^5 - 15x^4 + 10x^3, clamped outside.
double smootherstep(double x);

}  // namespace emf::synth
