// The movers of the generated scenes: the shape library, the motion families, and the plan of a
// mover's motion on the stage.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "synth/motion_plan.h"
#include "synth/random_layout.h"

namespace emf::synth::random_gen {

enum Family { kDrive, kSpin, kRock, kSwing, kCarry, kTumble, kPush, kFloat, kPass, kFamilies };
inline constexpr const char* kFamilyNames[kFamilies] = {"drive",  "spin", "rock",  "swing", "carry",
                                                        "tumble", "push", "float", "pass"};
constexpr unsigned bit(Family f) { return 1u << f; }

enum class Kind {
  kMug,
  kBottle,
  kBook,
  kLaptop,
  kBackpack,
  kVase,
  kHorse,
  kAirship,
  kSkateboard,
  kSurfboard,
  kBox,
  kCar,
  kTeddy,
  kSuitcase,
  kChair
};

/// The shape library: largest dimension at scale 1, the scale range, the motion families it
/// takes, and how often it is drawn among the shapes of a family (weight).
struct ShapeDef {
  Kind kind;
  double size_m;
  double s_lo, s_hi;
  unsigned families;
  double weight = 1.0;
};
inline constexpr ShapeDef kShapes[] = {
    {Kind::kMug, 0.145, 1.2, 1.6, bit(kCarry) | bit(kTumble)},
    {Kind::kBottle, 0.3, 0.9, 1.3, bit(kCarry) | bit(kSpin) | bit(kTumble) | bit(kRock)},
    {Kind::kBook, 0.22, 1.1, 1.6, bit(kCarry) | bit(kTumble) | bit(kPush)},
    {Kind::kLaptop, 0.34, 0.9, 1.1, bit(kCarry) | bit(kPush) | bit(kSpin)},
    {Kind::kBackpack, 0.44, 0.8, 1.1, bit(kCarry) | bit(kFloat) | bit(kSwing) | bit(kPush)},
    {Kind::kVase, 0.4, 0.7, 1.3, bit(kSpin) | bit(kCarry) | bit(kPush) | bit(kRock) | bit(kSwing)},
    {Kind::kHorse, 0.8, 0.8, 1.25, bit(kRock) | bit(kPush) | bit(kSpin), 5.0},
    {Kind::kAirship, 0.8, 0.8, 1.5, bit(kFloat) | bit(kPass)},
    {Kind::kSkateboard, 0.8, 0.9, 1.05, bit(kDrive) | bit(kPass) | bit(kSpin)},
    {Kind::kSurfboard, 1.5, 0.85, 1.0, bit(kPush) | bit(kSpin) | bit(kRock), 2.0},
    {Kind::kBox, 0.6, 0.4, 1.4, bit(kPush) | bit(kTumble) | bit(kSpin) | bit(kCarry)},
    {Kind::kCar, 0.34, 1.0, 1.0, bit(kDrive) | bit(kPass) | bit(kSpin)},
    {Kind::kTeddy, 0.45, 1.0, 1.0,
     bit(kCarry) | bit(kFloat) | bit(kSwing) | bit(kSpin) | bit(kPush) | bit(kRock)},
    {Kind::kSuitcase, 0.92, 1.0, 1.0, bit(kDrive) | bit(kPush) | bit(kSpin) | bit(kPass)},
    {Kind::kChair, 0.97, 1.0, 1.0, bit(kPush) | bit(kSpin) | bit(kDrive) | bit(kRock), 2.0},
};

/// The object of `kind` at scale s, and the height of its origin when it rests on the floor.
SceneObject buildShape(Kind kind, int id, double s, Rng& rng, double* rest_z);

/// The pose at floor position p, height z, turned by yaw about the vertical.
Eigen::Isometry3d poseAt(const Eigen::Vector2d& p, double z, double yaw);

struct Mover {
  SceneObject object;
  MotionPlan plan{Eigen::Isometry3d::Identity()};
  std::string motion;
  std::vector<Primitive> stand;  // statics that belong to it (a swing's stand)
  bool leaves_view = false;
};

/// Plans `family` for `object` (already built) starting on the stage at `p`. Returns false when
/// the family cannot be planned there.
bool planMotion(Family family, Kind kind, double s, double rest_z, Rng& rng, const Layout& L,
                Mover* m);

}  // namespace emf::synth::random_gen
