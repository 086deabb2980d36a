// The layout of a generated scene (random_scene.h) while it is built: the room, the stage where
// objects act, and the space every placed thing occupies over the timeline; random materials.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "synth/rng.h"
#include "synth/scene.h"

namespace emf::synth::random_gen {

inline constexpr double kPi = 3.141592653589793;
inline constexpr double kDeg = kPi / 180.0;
inline constexpr double kFps = 30.0;
inline constexpr double kCheckHz = 10.0;  // collision checks, samples per second

// ---- geometry helpers -------------------------------------------------------------------------

struct Box3 {
  Eigen::Vector3d lo, hi;
};

/// Whether a and b overlap or come closer than `margin`.
bool overlaps(const Box3& a, const Box3& b, double margin);
/// The world-aligned box around the object box b placed at T.
Box3 worldBox(const Eigen::AlignedBox3d& b, const Eigen::Isometry3d& T);

/// Space a thing takes: one box (static) or one per check sample (moving).
struct Occupant {
  std::vector<Box3> boxes;
  double margin = 0.05;  // clearance it wants from others (the larger of two applies)
  const Box3& at(size_t i) const { return boxes[std::min(i, boxes.size() - 1)]; }
};

/// Whether a and b come closer than the larger of their margins at some check sample.
bool collides(const Occupant& a, const Occupant& b);
/// The box around static `parts` (world frame).
Occupant staticOccupant(const std::vector<Primitive>& parts, double margin);

// ---- random materials ---------------------------------------------------------------------------

std::array<float, 3> randomColour(Rng& rng, double lo = 0.1, double hi = 0.9);
/// A solid, checker, stripes or noise material of two related colours.
Material randomMaterial(Rng& rng);

// ---- the scene being generated ------------------------------------------------------------------

struct Layout {
  double T = 20.0;           // timeline, seconds
  std::string camera;        // family
  double D = 2.4;            // camera distance to the stage centre (sweep, xyz) or orbit radius
  double sweep_x = 0.0;      // sideways amplitude of the sweep
  double stage_far_d = 3.5;  // farthest an object stands from the camera (orbit: centre)
  double room_hx = 3.0, room_y_lo = -4.0, room_y_hi = 3.0, ceiling = 2.6;
  std::vector<Occupant> occupants;  // furniture, stands, objects, the camera
};

/// Samples a floor position on the stage (where objects act), `clearance` from its edge and, for
/// the cameras looking one way, at least `min_distance` from the camera line.
Eigen::Vector2d stagePoint(Rng& rng, const Layout& L, double clearance, double min_distance = 0,
                           double max_distance = 1e9);
/// Whether p is on the stage (with a little slack).
bool inStage(const Layout& L, const Eigen::Vector2d& p);
/// World boxes of `object` over the timeline at kCheckHz.
Occupant movingOccupant(const SceneObject& object,
                        const std::function<Eigen::Isometry3d(double)>& pose, double T,
                        double margin);
/// Whether o stays within the room's walls (sideways ones too unless allow_outside_x), floor and
/// ceiling.
bool insideRoom(const Layout& L, const Occupant& o, bool allow_outside_x);
/// Whether o is inside the room and clear of every occupant of L.
bool fits(const Layout& L, const Occupant& o);

}  // namespace emf::synth::random_gen
