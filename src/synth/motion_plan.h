// Motion programs of the generated scenes: an object's pose over time as a sequence of actions
// (rest, eased 6-DoF moves, rotations about a pivot, oscillations, drives along a loop), each
// starting where the last one ended. A plan is sampled into Trajectory keys. Poses are
// T_world_object (metres, radians, world z up, clip time in seconds).
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <vector>

#include "synth/trajectory.h"

namespace emf::synth {

class MotionPlan {
 public:
  /// A plan that starts at `start` at time 0.
  explicit MotionPlan(const Eigen::Isometry3d& start);

  /// Time at which the last action ends (where the next one starts), seconds.
  double end() const { return end_s_; }
  /// The pose at the end of the last action.
  const Eigen::Isometry3d& endPose() const { return end_pose_; }

  /// Stays still for `duration_s`.
  void rest(double duration_s);
  /// Moves by delta_m (world frame) and turns by the rotation vector delta_rad (world frame,
  /// about the point pivot_object of the object's frame: its origin by default), eased with
  /// smootherstep over `duration_s`.
  void move(double duration_s, const Eigen::Vector3d& delta_m, const Eigen::Vector3d& delta_rad,
            const Eigen::Vector3d& pivot_object = Eigen::Vector3d::Zero());
  /// Turns by `angle_rad` about the world line through pivot_world along axis_world (unit),
  /// eased: a box tipping over its edge, a turn about a point off the origin.
  void rotateAbout(double duration_s, const Eigen::Vector3d& pivot_world,
                   const Eigen::Vector3d& axis_world, double angle_rad);
  /// Oscillates about the object's own axis `axis_object` (unit, object frame, through its
  /// origin) by amplitude_rad sin(2 pi f t), the amplitude ramped in and out over ramp_s at
  /// both ends so the motion starts and ends at rest. roll_radius_m > 0 rolls it as on rockers
  /// of that radius centred at the origin: a turn theta moves it by roll_radius_m theta along
  /// axis x z (the object's frame), so the contact point does not slide.
  void oscillate(double duration_s, const Eigen::Vector3d& axis_object, double amplitude_rad,
                 double frequency_hz, double ramp_s, double roll_radius_m);
  /// Floats: a translation (world) and a rotation (object frame) of summed sinusoids, each axis
  /// amplitude * sin(2 pi f_axis t + phase_axis), ramped in and out over ramp_s.
  void drift(double duration_s, const Eigen::Vector3d& amplitude_m,
             const Eigen::Vector3d& amplitude_rad, const Eigen::Vector3d& frequency_hz,
             const Eigen::Vector3d& phase_rad, double ramp_s);
  /// Drives along a closed planar loop `curve` (a function of the loop parameter in [0, 1),
  /// world x y) starting at parameter u0, in the direction of increasing u, with the object's x
  /// axis along the path (its z stays up; the start pose's height is kept). Speed up to
  /// max_speed_mps, lower in curves (yaw rate at most max_yaw_rate), starting and ending at
  /// rest and stopping for the windows in `stops` ([begin, end) in seconds from the action's
  /// start). The object starts at the loop's first pose: only rests may come before a drive
  /// (the object waits there).
  void drive(double duration_s, const std::function<Eigen::Vector2d(double)>& curve, double u0,
             double max_speed_mps, double max_yaw_rate, const std::vector<Eigen::Vector2d>& stops);

  /// The pose at time t (the first pose before 0, the end pose after end()).
  Eigen::Isometry3d pose(double t) const;
  /// Keys sampled every 1 / rate_hz seconds over [0, until_s] (and one at until_s).
  std::vector<PoseKey> sample(double until_s, double rate_hz) const;

 private:
  struct Action {
    double t0, t1;
    Eigen::Isometry3d start;
    std::function<Eigen::Isometry3d(const Eigen::Isometry3d& start, double tau)> at;
  };
  void add(double duration_s,
           std::function<Eigen::Isometry3d(const Eigen::Isometry3d& start, double tau)> at);

  Eigen::Isometry3d first_pose_;
  Eigen::Isometry3d end_pose_;
  double end_s_ = 0.0;
  std::vector<Action> actions_;
};

/// Max translational speed (m/s) and rotational speed (rad/s) of a trajectory over [0, until_s]
/// sampled at rate_hz (finite differences).
void peakSpeeds(const std::function<Eigen::Isometry3d(double)>& pose, double until_s,
                double rate_hz, double* speed_mps, double* rate_radps);

}  // namespace emf::synth
