#include "io/synth/random_scene.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/error.h"
#include "io/synth/motion_plan.h"
#include "io/synth/renderer.h"
#include "io/synth/rng.h"
#include "io/synth/shapes.h"

namespace emf::io::synth {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kDeg = kPi / 180.0;
constexpr uint64_t kSceneStream = 0x72616e646f6dull;  // "random"
constexpr double kFps = 30.0;
constexpr double kCheckHz = 10.0;  // collision checks, samples per second
constexpr double kKeyHz = 60.0;    // trajectory keys per second
constexpr int kMaxAttempts = 40;
// The static scene in view must pin the camera down (normalSpread) on every frame checked
// (kMinNormalSpread) and on 90 % of them with some margin (kLowNormalSpread). The presets'
// smallest and 10th percentile: cars 0.007 / 0.013, occlusion 0.012 / 0.018, enter 0.003 /
// 0.004, room 0.023 / 0.044.
constexpr double kMinNormalSpread = 0.004;
constexpr double kLowNormalSpread = 0.01;

enum Family { kDrive, kSpin, kRock, kSwing, kCarry, kTumble, kPush, kFloat, kPass, kFamilies };
const char* const kFamilyNames[kFamilies] = {"drive",  "spin", "rock",  "swing", "carry",
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
const ShapeDef kShapes[] = {
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

// ---- geometry helpers -------------------------------------------------------------------------

struct Box3 {
  Eigen::Vector3d lo, hi;
};

bool overlaps(const Box3& a, const Box3& b, double margin) {
  for (int k = 0; k < 3; ++k) {
    if (a.lo[k] - margin > b.hi[k] || b.lo[k] - margin > a.hi[k]) return false;
  }
  return true;
}

Box3 worldBox(const Eigen::AlignedBox3d& b, const Eigen::Isometry3d& T) {
  Eigen::AlignedBox3d w;
  for (int c = 0; c < 8; ++c)
    w.extend(T * b.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)));
  return {w.min(), w.max()};
}

/// Space a thing takes: one box (static) or one per check sample (moving).
struct Occupant {
  std::vector<Box3> boxes;
  double margin = 0.05;  // clearance it wants from others (the larger of two applies)
  const Box3& at(size_t i) const { return boxes[std::min(i, boxes.size() - 1)]; }
};

bool collides(const Occupant& a, const Occupant& b) {
  const size_t n = std::max(a.boxes.size(), b.boxes.size());
  const double margin = std::max(a.margin, b.margin);
  for (size_t i = 0; i < n; ++i) {
    if (overlaps(a.at(i), b.at(i), margin)) return true;
  }
  return false;
}

Occupant staticOccupant(const std::vector<Primitive>& parts, double margin) {
  Eigen::AlignedBox3d box;
  for (const auto& part : parts) {
    V3 h;
    if (!localBounds(part.geometry, &h)) continue;
    for (int c = 0; c < 8; ++c) {
      box.extend(part.T_parent_primitive *
                 Eigen::Vector3d((c & 1) ? h.x : -h.x, (c & 2) ? h.y : -h.y, (c & 4) ? h.z : -h.z));
    }
  }
  return {{{box.min(), box.max()}}, margin};
}

// ---- random materials ---------------------------------------------------------------------------

std::array<float, 3> randomColour(Rng& rng, double lo = 0.1, double hi = 0.9) {
  return {static_cast<float>(rng.uniform(lo, hi)), static_cast<float>(rng.uniform(lo, hi)),
          static_cast<float>(rng.uniform(lo, hi))};
}

Material randomMaterial(Rng& rng) {
  const Texture textures[] = {Texture::kSolid, Texture::kChecker, Texture::kStripes,
                              Texture::kNoise};
  const Texture t = textures[rng.uniformInt(0, 3)];
  const auto a = randomColour(rng);
  auto b = a;
  for (auto& c : b) c = std::clamp(c * static_cast<float>(rng.uniform(0.4, 0.8)), 0.0f, 1.0f);
  return pattern(t, a, b, rng.uniform(0.03, 0.12));
}

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
                           double max_distance = 1e9) {
  if (L.camera == "orbit") {
    const double Rs = std::max(0.3, std::min(1.3, L.D - 1.0) - clearance);
    const double r = Rs * std::sqrt(rng.uniform()), a = rng.uniform(0.0, 2 * kPi);
    return {r * std::cos(a), r * std::sin(a)};
  }
  // Distance from the camera line (y = -D) and the view's half width there (fx 525 at 640).
  const double lo = std::min(L.D + 0.6, std::max({1.0, 0.6 * L.D, min_distance}));
  const double d = rng.uniform(lo, std::max(lo, std::min(max_distance, L.stage_far_d)));
  const double half = std::max(0.1, 0.5 * d - clearance);
  return {rng.uniform(-half, half), d - L.D};
}

bool inStage(const Layout& L, const Eigen::Vector2d& p) {
  if (L.camera == "orbit") return p.norm() <= std::max(0.3, std::min(1.3, L.D - 1.0)) + 0.2;
  const double d = p.y() + L.D;
  return d >= std::max(0.9, 0.55 * L.D) && d <= L.stage_far_d + 0.2 && std::fabs(p.x()) <= 0.55 * d;
}

/// World boxes of `object` over the timeline at kCheckHz.
Occupant movingOccupant(const SceneObject& object,
                        const std::function<Eigen::Isometry3d(double)>& pose, double T,
                        double margin) {
  const Eigen::AlignedBox3d b = objectBounds(object);
  Occupant o;
  o.margin = margin;
  for (double t = 0.0; t <= T + 1e-9; t += 1.0 / kCheckHz) o.boxes.push_back(worldBox(b, pose(t)));
  return o;
}

bool insideRoom(const Layout& L, const Occupant& o, bool allow_outside_x) {
  for (const auto& b : o.boxes) {
    // The box of a turned object reaches lower than its parts: the floor check is loose.
    if (b.lo.z() < -0.15 || b.hi.z() > L.ceiling - 0.1) return false;
    if (b.lo.y() < L.room_y_lo + 0.1 || b.hi.y() > L.room_y_hi - 0.1) return false;
    if (!allow_outside_x && (b.lo.x() < -L.room_hx + 0.1 || b.hi.x() > L.room_hx - 0.1)) {
      return false;
    }
  }
  return true;
}

bool fits(const Layout& L, const Occupant& o) {
  if (!insideRoom(L, o, false)) return false;
  return std::none_of(L.occupants.begin(), L.occupants.end(),
                      [&](const Occupant& other) { return collides(o, other); });
}

// ---- shapes -------------------------------------------------------------------------------------

/// The object of `kind` at scale s, and the height of its origin when it rests on the floor.
SceneObject buildShape(Kind kind, int id, double s, Rng& rng, double* rest_z) {
  *rest_z = 0.0;
  const Material a = randomMaterial(rng), b = randomMaterial(rng);
  switch (kind) {
    case Kind::kMug:
      return mug(id, s, a);
    case Kind::kBottle:
      return bottle(id, s, a, b);
    case Kind::kBook:
      return book(id, s, a);
    case Kind::kLaptop:
      return laptop(id, s, solid(0.6f, 0.6f, 0.62f), b);
    case Kind::kBackpack:
      return backpack(id, s, a, b);
    case Kind::kVase:
      return vase(id, s, a);
    case Kind::kHorse:
      *rest_z = kRockerRadius * s;
      return rockingHorse(id, s, a, b);
    case Kind::kAirship:
      return airship(id, s, a, b);
    case Kind::kSkateboard:
      return skateboard(id, s, a);
    case Kind::kSurfboard:
      return surfboard(id, s, a);
    case Kind::kBox: {
      const double hx = rng.uniform(0.12, 0.3) * s, hy = rng.uniform(0.1, 0.25) * s,
                   hz = rng.uniform(0.08, 0.25) * s;
      return box(id, {hx, hy, hz},
                 pattern(Texture::kNoise, {0.35f, 0.55f, 0.7f}, {0.28f, 0.45f, 0.6f}, 0.05));
    }
    case Kind::kCar:
      return car(id, a, b);
    case Kind::kTeddy:
      *rest_z = 0.175;
      return teddy(id);
    case Kind::kSuitcase:
      return suitcase(id);
    case Kind::kChair:
      return chairObject(id);
  }
  return car(id, a, b);
}

// ---- motions ------------------------------------------------------------------------------------

Eigen::Isometry3d poseAt(const Eigen::Vector2d& p, double z, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x(), p.y(), z);
  return T;
}

double yawOf(const Eigen::Matrix3d& R) { return std::atan2(R(1, 0), R(0, 0)); }

/// Rotation vector (world) that turns R upright (z up) keeping its heading.
Eigen::Vector3d uprightDelta(const Eigen::Matrix3d& R) {
  const Eigen::Matrix3d up =
      Eigen::AngleAxisd(yawOf(R), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::AngleAxisd d(up * R.transpose());
  return d.angle() * d.axis();
}

/// Lowest point of the object under T.
double lowestZ(const SceneObject& o, const Eigen::Isometry3d& T) {
  return worldBox(objectBounds(o), T).lo.z();
}

/// A horizontal unit direction that keeps p + length * dir on the stage, if one is found.
std::optional<Eigen::Vector2d> stageDirection(Rng& rng, const Layout& L, const Eigen::Vector2d& p,
                                              double length) {
  for (int k = 0; k < 12; ++k) {
    const double a = rng.uniform(0.0, 2 * kPi);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    if (inStage(L, p + length * dir)) return dir;
  }
  return std::nullopt;
}

/// Eased moves peak at 1.875 x their mean speed: the drawn duration, or longer so that the
/// object's origin, `lever_m` from the turn's centre, stays under 0.45 m/s and the turn under
/// 90 deg/s.
double easedDuration(double drawn_s, double distance_m, double angle_rad, double lever_m) {
  constexpr double kPeak = 1.875, kSpeed = 0.45, kRate = 90 * kDeg;
  return std::max(
      {drawn_s, kPeak * (distance_m + angle_rad * lever_m) / kSpeed, kPeak * angle_rad / kRate});
}

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
                Mover* m) {
  SceneObject& o = m->object;
  const double T = L.T;
  const Eigen::AlignedBox3d bounds = objectBounds(o);
  const double size = (bounds.max() - bounds.min()).maxCoeff();
  const double height = bounds.max().z() - bounds.min().z();
  // Turns in the air and pushes turn about the object's centre; the origin is this far from it.
  const Eigen::Vector3d centre = bounds.center();
  const double lever = centre.norm();
  auto eased = [&](double lo, double hi, const Eigen::Vector3d& delta_m,
                   const Eigen::Vector3d& delta_rad) {
    m->plan.move(easedDuration(rng.uniform(lo, hi), delta_m.norm(), delta_rad.norm(), lever),
                 delta_m, delta_rad, centre);
  };
  // Close enough for its smaller side to make a 48 px box at 640 px (the detection filter).
  Eigen::Vector3d sides = bounds.sizes();
  std::sort(sides.data(), sides.data() + 3);
  const double max_distance = 525.0 / 48.0 * 0.8 * sides[1];
  if (L.camera != "orbit" && max_distance < std::max(1.0, 0.6 * L.D)) return false;
  if (L.camera == "orbit" && max_distance < L.D - std::min(1.3, L.D - 1.0)) return false;
  const Eigen::Vector2d p = stagePoint(rng, L, 0.5 * size, 1.3 * size, max_distance);
  const double yaw0 = rng.uniform(-kPi, kPi);
  switch (family) {
    case kDrive: {
      // A loop: an ellipse whose tightest bend still has a radius of 0.25 m.
      const double a = rng.uniform(std::max(0.35, 1.0 * size), std::max(0.5, 1.8 * size));
      const double b = rng.uniform(std::max(0.25, std::sqrt(0.25 * a)), std::max(0.3, a));
      const double psi = L.camera == "orbit" ? rng.uniform(0.0, kPi) : rng.uniform(-0.4, 0.4);
      const double dir = rng.bernoulli(0.5) ? 1.0 : -1.0;
      const Eigen::Vector2d c = p;
      auto curve = [=](double u) {
        const double ang = dir * 2 * kPi * u;
        const Eigen::Vector2d e(a * std::cos(ang), b * std::sin(ang));
        return Eigen::Vector2d(c.x() + std::cos(psi) * e.x() - std::sin(psi) * e.y(),
                               c.y() + std::sin(psi) * e.x() + std::cos(psi) * e.y());
      };
      for (double u : {0.0, 0.25, 0.5, 0.75}) {
        if (!inStage(L, curve(u))) return false;
      }
      const double rest0 = rng.uniform(0.0, 2.5);
      std::vector<Eigen::Vector2d> stops;
      const int n_stops = rng.uniformInt(0, 3);
      for (int k = 0; k < n_stops; ++k) {
        const double t0 = rng.uniform(2.0, std::max(2.5, T - rest0 - 4.0));
        stops.emplace_back(t0, t0 + rng.uniform(0.8, 3.0));
      }
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      m->plan.rest(rest0);
      m->plan.drive(T - rest0, curve, rng.uniform(), rng.uniform(0.15, 0.32), 50 * kDeg, stops);
      m->motion = "drive";
      return true;
    }
    case kSpin: {
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      while (m->plan.end() < T - 2.0) {
        m->plan.rest(rng.uniform(0.5, 3.0));
        const double angle = (rng.bernoulli(0.5) ? 1 : -1) * rng.uniform(60, 270) * kDeg;
        const double rate = rng.uniform(18, 30) * kDeg;
        const Eigen::Vector3d pivot = m->plan.endPose() * centre;
        m->plan.rotateAbout(std::fabs(angle) / rate, pivot, Eigen::Vector3d::UnitZ(), angle);
      }
      m->motion = "spin";
      return true;
    }
    case kRock: {
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      const bool rockers = kind == Kind::kHorse;
      std::string motion = rockers ? "rock" : "wobble";
      while (m->plan.end() < T - 4.0) {
        m->plan.rest(rng.uniform(0.5, 3.0));
        const double amp = rng.uniform(rockers ? 5 : 4, rockers ? 12 : 8) * kDeg;
        // Peak speed of the object's top at most 0.45 m/s.
        const double f_max = 0.45 / (2 * kPi * amp * std::max(0.2, height));
        const double f = std::min(rng.uniform(rockers ? 0.4 : 0.6, rockers ? 0.7 : 1.1), f_max);
        const Eigen::Vector3d axis =
            rockers || rng.bernoulli(0.5) ? Eigen::Vector3d::UnitY() : Eigen::Vector3d::UnitX();
        m->plan.oscillate(rng.uniform(4.0, 9.0), axis, amp, f, 1.0,
                          rockers ? kRockerRadius * s : 0.0);
        if (rng.bernoulli(0.5) && m->plan.end() < T - 6.0) {
          // Pushed across the floor between bouts.
          const double len = rng.uniform(0.3, 0.8);
          const Eigen::Vector2d at = m->plan.endPose().translation().head<2>();
          if (auto dir = stageDirection(rng, L, at, len)) {
            m->plan.rest(rng.uniform(0.5, 2.0));
            eased(2.0, 3.5, Eigen::Vector3d(dir->x(), dir->y(), 0) * len,
                  Eigen::Vector3d(0, 0, rng.uniform(-30, 30) * kDeg));
            if (motion.find("push") == std::string::npos) motion += "+push";
          }
        }
      }
      m->motion = motion;
      return true;
    }
    case kSwing: {
      // Hang the object L below a pivot on a stand; the origin becomes the pivot.
      const double rope = rng.uniform(0.35, 0.7);
      const double bottom = rng.uniform(0.2, 0.45);
      const double pivot_z = bottom + height + rope;
      if (pivot_z > L.ceiling - 0.3) return false;
      const Eigen::Vector3d top(bounds.center().x(), bounds.center().y(), bounds.max().z());
      Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
      shift.translation() = -top - Eigen::Vector3d(0, 0, rope);
      for (auto& part : o.parts) part.T_parent_primitive = shift * part.T_parent_primitive;
      o.parts.push_back(makeCapsule(0.006, rope / 2, at(0, 0, -rope / 2), solid(0.7f, 0.7f, 0.7f)));
      const Eigen::Isometry3d start = poseAt(p, pivot_z, yaw0);
      // The stand: two posts along the swing's axis (object x) and a crossbar.
      const double half = 0.5 * (bounds.max().x() - bounds.min().x()) + 0.2;
      const Material metal = solid(0.3f, 0.3f, 0.32f);
      for (int sx : {-1, 1}) {
        const Eigen::Vector3d post = start * Eigen::Vector3d(sx * half, 0, 0);
        m->stand.push_back(
            makeCylinder(0.025, pivot_z / 2, at(post.x(), post.y(), pivot_z / 2), metal));
      }
      m->stand.push_back(makeCapsule(0.02, half, start * at(0, 0, 0, 0, kPi / 2, 0), metal));
      m->plan = MotionPlan(start);
      const double length = rope + 0.5 * height;
      const double f = std::sqrt(9.81 / length) / (2 * kPi);
      while (m->plan.end() < T - 4.0) {
        m->plan.rest(rng.uniform(0.5, 3.0));
        const double amp = std::min(rng.uniform(6, 14) * kDeg, 0.45 / (2 * kPi * f * length));
        m->plan.oscillate(rng.uniform(5.0, 10.0), Eigen::Vector3d::UnitX(), amp, f, 1.5, 0.0);
      }
      m->motion = "swing";
      return true;
    }
    case kCarry:
    case kTumble: {
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      const bool flip_edges = family == kTumble && kind == Kind::kBox;
      while (m->plan.end() < T - 6.0) {
        m->plan.rest(rng.uniform(1.0, 3.5));
        const Eigen::Isometry3d now = m->plan.endPose();
        if (flip_edges) {
          // Tip over a bottom edge towards a direction that stays on the stage.
          const Box3 wb = worldBox(bounds, now);
          const int axis = rng.uniformInt(0, 1);
          const double sign = rng.bernoulli(0.5) ? 1.0 : -1.0;
          Eigen::Vector3d d = Eigen::Vector3d::Zero();
          d[axis] = sign;
          Eigen::Vector3d pivot = 0.5 * (wb.lo + wb.hi);
          pivot[axis] = sign > 0 ? wb.hi[axis] : wb.lo[axis];
          pivot.z() = 0.0;
          if (!inStage(
                  L, pivot.head<2>() + 0.5 * (wb.hi - wb.lo).head<2>().cwiseProduct(d.head<2>()))) {
            continue;
          }
          const double arm = (now.translation() - pivot).norm();
          m->plan.rotateAbout(easedDuration(rng.uniform(1.8, 2.6), 0.0, kPi / 2, arm), pivot,
                              Eigen::Vector3d::UnitZ().cross(d), kPi / 2);
          continue;
        }
        // Pick up: lift and tilt.
        const double lift = rng.uniform(0.25, 0.7);
        const double ta = rng.uniform(0, 2 * kPi);
        const Eigen::Vector3d tilt =
            Eigen::Vector3d(std::cos(ta), std::sin(ta), 0) * rng.uniform(5, 25) * kDeg;
        eased(1.1, 1.6, Eigen::Vector3d(0, 0, lift), tilt);
        // Carry and turn, or turn it over in the air.
        const double len = rng.uniform(0.2, 0.7);
        const Eigen::Vector2d at2 = m->plan.endPose().translation().head<2>();
        const auto dir = stageDirection(rng, L, at2, len);
        Eigen::Vector3d step = Eigen::Vector3d::Zero();
        if (dir) step = Eigen::Vector3d(dir->x(), dir->y(), 0) * len;
        if (family == kTumble) {
          const double fa = rng.uniform(0, 2 * kPi);
          eased(2.0, 3.0, 0.3 * step, Eigen::Vector3d(std::cos(fa), std::sin(fa), 0) * kPi);
        } else {
          eased(1.6, 3.0, step, Eigen::Vector3d(0, 0, rng.uniform(-60, 60) * kDeg));
          if (rng.bernoulli(0.4)) {
            const Eigen::Vector3d w = Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
            eased(1.2, 2.0, Eigen::Vector3d::Zero(), w.normalized() * rng.uniform(20, 50) * kDeg);
          }
        }
        m->plan.rest(rng.uniform(0.0, 1.0));
        // Put down: flat on a face (upright after a carry; after a turn over, on its top).
        const Eigen::Isometry3d held = m->plan.endPose();
        Eigen::Vector3d level = uprightDelta(held.linear());
        if (family == kTumble) {
          // Closest of upright and upside down.
          const Eigen::Matrix3d flipped =
              Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
          const Eigen::Matrix3d R = held.linear() * flipped;
          const Eigen::Vector3d level_flipped = uprightDelta(R);
          if (level_flipped.norm() < level.norm()) level = level_flipped;
        }
        // Where it would land turned level about its centre, then lowered onto the floor.
        const Eigen::Matrix3d R_level =
            Eigen::AngleAxisd(level.norm(),
                              level.norm() > 0 ? level.normalized() : Eigen::Vector3d::UnitZ())
                .toRotationMatrix();
        Eigen::Isometry3d landed = held;
        landed.linear() = R_level * held.linear();
        const Eigen::Vector3d c_world = held * centre;
        landed.translation() = c_world + R_level * (held.translation() - c_world);
        const double drop = lowestZ(o, landed);
        eased(1.1, 1.6, Eigen::Vector3d(0, 0, -drop), level);
      }
      m->motion = family == kTumble ? "tumble" : "carry";
      return true;
    }
    case kPush: {
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      m->plan.rest(rng.uniform(3.0, std::max(3.5, std::min(10.0, T - 8.0))));
      int pushes = 0;
      while (pushes == 0 || (m->plan.end() < T - 4.0 && rng.bernoulli(0.4))) {
        const double len = rng.uniform(0.3, 0.9);
        const Eigen::Vector2d at2 = m->plan.endPose().translation().head<2>();
        const auto dir = stageDirection(rng, L, at2, len);
        if (!dir) return false;
        eased(1.6, 3.0, Eigen::Vector3d(dir->x(), dir->y(), 0) * len,
              Eigen::Vector3d(0, 0, rng.uniform(-40, 40) * kDeg));
        m->plan.rest(rng.uniform(2.0, 6.0));
        ++pushes;
      }
      m->motion = "push";
      return true;
    }
    case kFloat: {
      const double z = rng.uniform(0.7, 1.4);
      m->plan = MotionPlan(poseAt(p, z, yaw0));
      if (kind == Kind::kAirship && rng.bernoulli(0.5)) {
        // A flight around a loop at a constant height.
        const double a = rng.uniform(0.4, 0.9), b = rng.uniform(0.3, a);
        const Eigen::Vector2d c = p;
        const double psi = rng.uniform(0.0, kPi);
        auto curve = [=](double u) {
          const double ang = 2 * kPi * u;
          const Eigen::Vector2d e(a * std::cos(ang), b * std::sin(ang));
          return Eigen::Vector2d(c.x() + std::cos(psi) * e.x() - std::sin(psi) * e.y(),
                                 c.y() + std::sin(psi) * e.x() + std::cos(psi) * e.y());
        };
        for (double u : {0.0, 0.25, 0.5, 0.75}) {
          if (!inStage(L, curve(u))) return false;
        }
        m->plan.rest(rng.uniform(0.0, 2.0));
        m->plan.drive(T - m->plan.end(), curve, rng.uniform(), rng.uniform(0.12, 0.25), 35 * kDeg,
                      {});
        m->motion = "float";
        return true;
      }
      while (m->plan.end() < T - 4.0) {
        const Eigen::Vector3d amp_m(rng.uniform(0.15, 0.45), rng.uniform(0.1, 0.3),
                                    rng.uniform(0.05, 0.2));
        const Eigen::Vector3d amp_rad(rng.uniform(0.05, 0.2), rng.uniform(0.05, 0.2),
                                      rng.uniform(0.1, 0.4));
        const Eigen::Vector3d f(rng.uniform(0.05, 0.15), rng.uniform(0.06, 0.16),
                                rng.uniform(0.08, 0.2));
        const Eigen::Vector3d phase(rng.uniform(0, 2 * kPi), rng.uniform(0, 2 * kPi),
                                    rng.uniform(0, 2 * kPi));
        m->plan.drift(rng.uniform(6.0, 14.0), amp_m, amp_rad, f, phase, 1.5);
        if (rng.bernoulli(0.3)) m->plan.rest(rng.uniform(0.5, 2.0));
      }
      m->motion = "float";
      return true;
    }
    case kPass: {
      if (L.camera == "orbit") return false;  // there is no "outside the view" to come from
      const double d = rng.uniform(std::max(1.0, 0.6 * L.D), std::max(1.0, L.stage_far_d));
      const double out = std::min(0.62 * d + L.sweep_x + 0.6 * size, L.room_hx - 0.2 - 0.6 * size);
      const double side = rng.bernoulli(0.5) ? 1.0 : -1.0;
      const double z = kind == Kind::kAirship ? rng.uniform(0.7, 1.4) : rest_z;
      m->plan = MotionPlan(poseAt({-side * out, d - L.D}, z, side > 0 ? 0.0 : kPi));
      double x = -side * out;
      int legs = 0;
      while (m->plan.end() < T - 5.0 && (legs == 0 || rng.bernoulli(0.6))) {
        m->plan.rest(rng.uniform(0.5, 4.0));
        const double speed = rng.uniform(0.13, 0.24);
        const double dx = -2.0 * x;
        m->plan.move(std::fabs(dx) / speed, Eigen::Vector3d(dx, 0, 0), Eigen::Vector3d::Zero());
        x += dx;
        ++legs;
        if (m->plan.end() < T - 5.0) {
          // Turn around out of view.
          m->plan.rest(rng.uniform(0.5, 2.0));
          eased(2.5, 2.5, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, kPi));
        }
      }
      m->leaves_view = true;
      m->motion = "pass";
      return true;
    }
    case kFamilies:
      break;
  }
  return false;
}

// ---- cameras ------------------------------------------------------------------------------------

void handHeld(CameraRig& rig) {
  rig.path.position_terms.push_back(sine(0.004, 0.003, 0.004, 1.7, 0.3));
  rig.path.position_terms.push_back(sine(0.002, 0.003, 0.002, 2.9, 1.1));
  rig.tremor_rad.push_back(sine(0.004, 0.005, 0.003, 1.3, 0.2));
  rig.tremor_rad.push_back(sine(0.002, 0.002, 0.002, 2.3, 1.7));
}

CameraRig makeCamera(Rng& rng, Layout* L) {
  CameraRig rig;
  const double h = rng.uniform(0.9, 1.6);
  if (L->camera == "orbit") {
    const double R = L->D;
    const double v = rng.uniform(0.15, 0.3);
    const double f = v / (2 * kPi * R);
    const double phase = rng.uniform(0, 2 * kPi);
    rig.path.origin_m = v3(0, 0, h);
    rig.path.position_terms = {sine(R, 0, 0, f, phase + kPi / 2), sine(0, R, 0, f, phase),
                               sine(0, 0, rng.uniform(0.0, 0.15), rng.uniform(0.05, 0.12))};
    rig.target.origin_m = v3(0, 0, rng.uniform(0.2, 0.6));
    rig.target.position_terms = {sine(rng.uniform(0.1, 0.3), rng.uniform(0.1, 0.3), 0.05,
                                      rng.uniform(0.04, 0.09), rng.uniform(0, 2 * kPi))};
  } else if (L->camera == "xyz") {
    rig.path.origin_m = v3(rng.uniform(-0.3, 0.3), -L->D, h);
    rig.path.position_terms = {
        sine(rng.uniform(0.05, 0.15), 0, 0, rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi)),
        sine(0, rng.uniform(0.05, 0.15), 0, rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.03, 0.1), rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi))};
    rig.target.origin_m = v3(0, rng.uniform(0.0, 0.5), rng.uniform(0.2, 0.5));
    const double r = L->D * std::tan(rng.uniform(3, 8) * kDeg);
    rig.target.position_terms = {
        sine(r, 0, 0, rng.uniform(0.08, 0.2), rng.uniform(0, 2 * kPi)),
        sine(0, 0, 0.6 * r, rng.uniform(0.08, 0.2), rng.uniform(0, 2 * kPi))};
    L->sweep_x = 0.15;
  } else {
    L->sweep_x = rng.uniform(0.3, 0.9);
    rig.path.origin_m = v3(0, -L->D, h);
    rig.path.position_terms = {
        sine(L->sweep_x, 0, 0, rng.uniform(0.03, 0.07), rng.uniform(0, 2 * kPi)),
        sine(0, rng.uniform(0.0, 0.3), 0, rng.uniform(0.05, 0.1), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.0, 0.1), rng.uniform(0.08, 0.14), rng.uniform(0, 2 * kPi))};
    rig.target.origin_m = v3(0, rng.uniform(0.0, 0.6), rng.uniform(0.2, 0.6));
    rig.target.position_terms = {
        sine(rng.uniform(0.2, 0.6), 0, 0, rng.uniform(0.04, 0.08), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.05, 0.15), rng.uniform(0.06, 0.1), rng.uniform(0, 2 * kPi))};
  }
  // At most 0.4 m/s and 30 deg/s (the TUM sequences' range): slow the whole rig down.
  for (int k = 0; k < 30; ++k) {
    double v, w;
    peakSpeeds([&](double t) { return rig.pose(t); }, L->T, kFps, &v, &w);
    if (v <= 0.4 && w <= 30 * kDeg) break;
    for (auto* terms : {&rig.path.position_terms, &rig.target.position_terms}) {
      for (auto& term : *terms) term.frequency_hz *= 0.9;
    }
  }
  handHeld(rig);
  return rig;
}

// ---- furniture ----------------------------------------------------------------------------------

/// Pillars standing out of the walls the camera faces (two on the back wall, one on each side
/// wall; one per wall for an orbit), floor to ceiling: their side faces keep the camera's
/// sideways motion observable where the room would otherwise show a floor and a flat wall.
void addPillars(Scene& s, Rng& rng, Layout* L, const Occupant& stage) {
  const Material plaster = pattern(Texture::kNoise, randomColour(rng, 0.55, 0.85),
                                   randomColour(rng, 0.45, 0.7), rng.uniform(0.2, 0.5));
  const double h = 0.5 * L->ceiling + 0.1;
  std::vector<Primitive> pillars;
  auto add = [&](double x, double y, double hx, double hy) {
    std::vector<Primitive> p = {makeBox({hx, hy, h}, at(x, y, h - 0.1), plaster)};
    const Occupant occ = staticOccupant(p, 0.05);
    if (collides(occ, stage) || std::any_of(L->occupants.begin(), L->occupants.end(),
                                            [&](const Occupant& o) { return collides(occ, o); })) {
      return;
    }
    L->occupants.push_back(occ);
    s.statics.push_back(p[0]);
  };
  const bool orbit = L->camera == "orbit";
  for (int k = 0; k < (orbit ? 1 : 2); ++k) {
    const double depth = rng.uniform(0.15, 0.3);
    const double x = (k == 0 ? -1 : 1) * rng.uniform(0.3, std::max(0.35, L->room_hx - 0.6));
    add(orbit ? rng.uniform(-L->room_hx + 0.5, L->room_hx - 0.5) : x, L->room_y_hi - depth,
        rng.uniform(0.15, 0.35), depth);
  }
  for (int side : {-1, 1}) {
    const double depth = rng.uniform(0.15, 0.3);
    const double y =
        orbit ? rng.uniform(L->room_y_lo + 0.5, L->room_y_hi - 0.5)
              : rng.uniform(std::max(L->room_y_lo + 0.5, L->room_y_hi - 2.0), L->room_y_hi - 0.4);
    add(side * (L->room_hx - depth), y, depth, rng.uniform(0.15, 0.35));
  }
  if (orbit) {
    const double depth = rng.uniform(0.15, 0.3);
    add(rng.uniform(-L->room_hx + 0.5, L->room_hx - 0.5), L->room_y_lo + depth,
        rng.uniform(0.15, 0.35), depth);
  }
}

/// Adds 2-5 pieces along the walls where they keep clear of the stage and the camera.
void addFurniture(Scene& s, Rng& rng, Layout* L, const Occupant& stage) {
  const bool orbit = L->camera == "orbit";
  const int n = rng.uniformInt(3, 6);
  for (int i = 0; i < n; ++i) {
    for (int attempt = 0; attempt < 20; ++attempt) {
      Scene piece;
      const int kind = rng.uniformInt(0, 5);
      // Back, left, right (and front for an orbit). The first two pieces of a camera looking
      // one way stand where it looks (the back wall, or a side wall near it): with the floor
      // and the back wall alone, sliding along the wall is not observable in depth.
      int wall = rng.uniformInt(0, orbit ? 3 : 2);
      if (!orbit && i == 0) wall = 0;
      double x, y, yaw;
      if (wall == 0 || wall == 3) {
        const double reach = !orbit && i < 2 ? std::min(1.2, L->room_hx - 0.6) : L->room_hx - 0.6;
        x = rng.uniform(-reach, reach);
        y = wall == 0 ? L->room_y_hi - 0.5 : L->room_y_lo + 0.5;
        yaw = wall == 0 ? 0 : kPi;
      } else {
        x = (wall == 1 ? -1 : 1) * (L->room_hx - 0.5);
        const double lo = !orbit && i < 2 ? L->room_y_hi - 1.5 : L->room_y_lo + 0.6;
        y = rng.uniform(std::min(lo, L->room_y_hi - 0.6), L->room_y_hi - 0.6);
        yaw = wall == 1 ? -kPi / 2 : kPi / 2;
      }
      switch (kind) {
        case 0:
          addTable(piece, x, y, yaw, rng.uniform(0.4, 0.7), rng.uniform(0.3, 0.45));
          if (rng.bernoulli(0.6)) addTableItems(piece, x, y);
          break;
        case 1:
          addShelf(piece, x, y + (wall == 0 ? 0.25 : 0), yaw);
          break;
        case 2:
          addSofa(piece, x, y, yaw + kPi);
          break;
        case 3:
          addLamp(piece, x, y);
          break;
        case 4:
          addChair(piece, x, y, yaw + rng.uniform(-0.5, 0.5));
          break;
        default: {
          // A cabinet.
          const double half_z = rng.uniform(0.3, 0.6);
          piece.statics.push_back(makeBox({rng.uniform(0.25, 0.5), rng.uniform(0.2, 0.35), half_z},
                                          at(x, y, half_z, yaw), randomMaterial(rng)));
          break;
        }
      }
      const Occupant occ = staticOccupant(piece.statics, 0.1);
      if (!insideRoom(*L, occ, false) || collides(occ, stage) ||
          std::any_of(L->occupants.begin(), L->occupants.end(),
                      [&](const Occupant& o) { return collides(occ, o); })) {
        continue;
      }
      L->occupants.push_back(occ);
      for (auto& p : piece.statics) s.statics.push_back(p);
      break;
    }
  }
}

// ---- visibility check -----------------------------------------------------------------------

/// How well the static scene in view pins the camera down: the smallest eigenvalue of the mean
/// of n n^T over the surface normals of `depth` (CV_32F, NaN = nothing, 4.5 m range) where
/// `ids` (CV_16U) is 0 (the static scene, objects left out), in [0, 1/3]. Near 0 when all surfaces
/// in view share a direction they are parallel to (a floor and one wall: sliding along the wall
/// changes no depth).
double normalSpread(const cv::Mat& depth, const cv::Mat& ids, const Intrinsics& K) {
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  int n = 0;
  auto point = [&](int u, int v) {
    const float z = depth.at<float>(v, u);
    return Eigen::Vector3d((u - K.cx) / K.fx * z, (v - K.cy) / K.fy * z, z);
  };
  auto valid = [&](int u, int v) {
    const float z = depth.at<float>(v, u);
    return ids.at<uint16_t>(v, u) == 0 && z == z && z > 0.4f && z < 4.5f;
  };
  for (int v = 0; v + 1 < depth.rows; ++v) {
    for (int u = 0; u + 1 < depth.cols; ++u) {
      if (!valid(u, v) || !valid(u + 1, v) || !valid(u, v + 1)) continue;
      const Eigen::Vector3d p = point(u, v);
      const Eigen::Vector3d a = point(u + 1, v) - p, b = point(u, v + 1) - p;
      // Skip pixels across depth edges.
      if (a.norm() > 0.05 * p.z() || b.norm() > 0.05 * p.z()) continue;
      const Eigen::Vector3d normal = a.cross(b).normalized();
      S += normal * normal.transpose();
      ++n;
    }
  }
  if (n < 20) return 0.0;
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S / n).eigenvalues()(0);
}

/// Fraction of the frames (every 8th) on which each object is detectable: in view with a box of
/// at least kMinBoxFraction of the image width on both sides (the paper's 40 px detection filter
/// at 640 px, with a margin); the camera's nearest surface over them (metres); and the
/// normalSpread of the static scene in view per frame. Rendered at 96x72.
void viewCheck(const Scene& scene, int frames, std::vector<double>* detectable, double* nearest_m,
               std::vector<double>* spread) {
  constexpr double kMinBoxFraction = 48.0 / 640.0;
  RenderOptions ro;
  ro.width = 96;
  ro.height = 72;
  ro.threads = 1;
  const Renderer renderer(ro);
  detectable->assign(scene.objects.size(), 0.0);
  *nearest_m = 1e9;
  spread->clear();
  const int min_side = static_cast<int>(std::ceil(kMinBoxFraction * ro.width));
  const int min_pixels = minVisiblePixels(ro.width, ro.height);
  int checked = 0;
  for (int f = 0; f < frames; f += 8, ++checked) {
    const double t = scene.timeOf(f);
    std::vector<Eigen::Isometry3d> poses;
    for (const auto& o : scene.objects) poses.push_back(o.trajectory.pose(t));
    RenderOutput r;
    renderer.render(scene, scene.camera.pose(t), poses, &r);
    spread->push_back(normalSpread(r.depth, r.instance_ids, renderer.intrinsics()));
    for (size_t k = 0; k < scene.objects.size(); ++k) {
      const cv::Mat mask = r.instance_ids == scene.objects[k].id;
      if (cv::countNonZero(mask) < min_pixels) continue;
      const cv::Rect box = cv::boundingRect(mask);
      if (box.width >= min_side && box.height >= min_side) (*detectable)[k] += 1.0;
    }
    double lo, hi;
    cv::minMaxIdx(r.depth, &lo, &hi, nullptr, nullptr, r.depth == r.depth);
    *nearest_m = std::min(*nearest_m, lo);
  }
  for (auto& v : *detectable) v /= std::max(1, checked);
}

// ---- the generator ------------------------------------------------------------------------------

struct Attempt {
  RandomScene result;
  double score = -1.0;  // the smallest visibility margin over the objects (>= 0: accepted)
};

Attempt generate(uint64_t seed, int attempt, const RandomSceneOptions& options, unsigned families) {
  Rng rng(streamSeed(seed, kSceneStream, static_cast<uint64_t>(attempt)));
  Layout L;
  L.T = options.frames / kFps;
  Attempt out;
  Scene& scene = out.result.scene;
  scene.name = "random";
  scene.default_frames = options.frames;

  // Camera family and distance, then a room that holds the camera and the stage.
  if (!options.camera.empty()) {
    L.camera = options.camera;
  } else {
    const double c = rng.uniform();
    L.camera = c < 0.5 ? "sweep" : (c < 0.72 ? "xyz" : "orbit");
  }
  // The wall the camera faces stays within kFarWallM (the sensor sees 0.4-4.5 m): beyond it a
  // camera would see a floor and little else to track against.
  constexpr double kFarWallM = 4.1;
  L.D = L.camera == "orbit" ? rng.uniform(1.5, 1.9) : rng.uniform(1.6, 3.0);
  if (L.camera == "orbit") {
    L.room_hx = rng.uniform(L.D + 0.6, std::max(L.D + 0.6, kFarWallM - L.D));
    const double hy = rng.uniform(L.D + 0.6, std::max(L.D + 0.6, kFarWallM - L.D));
    L.room_y_lo = -hy;
    L.room_y_hi = hy;
    L.stage_far_d = L.D + std::min(1.3, L.D - 1.0);
  } else {
    L.room_hx = rng.uniform(2.4, 3.6);
    L.room_y_lo = -L.D - rng.uniform(0.8, 1.5);
    const double back = rng.uniform(std::min(kFarWallM, std::max(3.4, L.D + 1.4)), kFarWallM);
    L.room_y_hi = back - L.D;
    L.stage_far_d = std::min(L.D + 1.1, back - 0.45);
  }
  const double hz = rng.uniform(1.35, 1.6);
  L.ceiling = 2 * hz - 0.2;
  const double cy = 0.5 * (L.room_y_lo + L.room_y_hi), hy = 0.5 * (L.room_y_hi - L.room_y_lo);
  addRoom(scene, {L.room_hx, hy, hz}, cy,
          pattern(rng.bernoulli(0.5) ? Texture::kTiles : Texture::kChecker,
                  randomColour(rng, 0.2, 0.6), randomColour(rng, 0.3, 0.8), rng.uniform(0.25, 0.6)),
          pattern(Texture::kNoise, randomColour(rng, 0.55, 0.9), randomColour(rng, 0.45, 0.75),
                  rng.uniform(0.2, 0.5)));
  scene.camera = makeCamera(rng, &L);
  {
    // The camera's space at every check instant.
    Occupant cam;
    cam.margin = 0.35;
    for (double t = 0.0; t <= L.T + 1e-9; t += 1.0 / kCheckHz) {
      const Eigen::Vector3d c = scene.camera.pose(t).translation();
      cam.boxes.push_back({c - Eigen::Vector3d::Constant(0.2), c + Eigen::Vector3d::Constant(0.2)});
    }
    L.occupants.push_back(cam);
  }
  // The stage (where objects act) as furniture sees it.
  Occupant stage;
  if (L.camera == "orbit") {
    const double r = L.D + 0.6;
    stage.boxes.push_back({Eigen::Vector3d(-r, -r, 0), Eigen::Vector3d(r, r, 2.0)});
  } else {
    stage.boxes.push_back({Eigen::Vector3d(-0.6 * L.stage_far_d, -L.D, 0),
                           Eigen::Vector3d(0.6 * L.stage_far_d, L.stage_far_d - L.D - 0.3, 2.0)});
  }
  addPillars(scene, rng, &L, stage);
  addFurniture(scene, rng, &L, stage);
  std::string description = "Room " + std::to_string(2 * L.room_hx).substr(0, 3) + " x " +
                            std::to_string(2 * hy).substr(0, 3) + " m; camera " + L.camera +
                            " at " + std::to_string(L.D).substr(0, 3) + " m";
  // Sometimes a static occluder among the objects: a low cabinet.
  if (rng.bernoulli(0.3)) {
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector2d p = stagePoint(rng, L, 0.3);
      std::vector<Primitive> cab = {
          makeBox({rng.uniform(0.2, 0.45), rng.uniform(0.15, 0.3), rng.uniform(0.2, 0.4)},
                  at(p.x(), p.y(), 0, rng.uniform(-0.5, 0.5)), randomMaterial(rng))};
      cab[0].T_parent_primitive.translation().z() = cab[0].geometry.half_extents_m.z;
      const Occupant occ = staticOccupant(cab, 0.1);
      if (!fits(L, occ)) continue;
      L.occupants.push_back(occ);
      scene.statics.push_back(cab[0]);
      description += "; a cabinet among the objects";
      break;
    }
  }

  // Movers.
  const int movers = options.movers > 0 ? options.movers : [&] {
    const double u = rng.uniform();
    return u < 0.2 ? 1 : (u < 0.55 ? 2 : (u < 0.85 ? 3 : 4));
  }();
  int next_id = 1;
  std::vector<Family> allowed;
  for (int f = 0; f < kFamilies; ++f) {
    if (families & (1u << f)) allowed.push_back(static_cast<Family>(f));
  }
  const double far_d = L.stage_far_d;
  int placed_movers = 0;
  for (int i = 0; i < movers; ++i) {
    bool placed = false;
    for (int tries = 0; tries < 60 && !placed; ++tries) {
      // Drives fit the stage less often than the rest: drawn twice as often.
      std::vector<Family> draw = allowed;
      if (std::find(allowed.begin(), allowed.end(), kDrive) != allowed.end())
        draw.push_back(kDrive);
      const Family family =
          draw[static_cast<size_t>(rng.uniformInt(0, static_cast<int>(draw.size()) - 1))];
      std::vector<const ShapeDef*> shapes;
      double total_weight = 0;
      for (const auto& d : kShapes) {
        // Large enough to be detected at the far side, small enough for the view at the
        // distance it is placed at (stagePoint keeps 1.3 x its size from the camera).
        const double lo = d.size_m * d.s_lo, hi = d.size_m * d.s_hi;
        if ((d.families & bit(family)) && hi >= 0.075 * far_d && lo <= 0.6 * L.D) {
          shapes.push_back(&d);
          total_weight += d.weight;
        }
      }
      if (shapes.empty()) continue;
      double pick = rng.uniform(0.0, total_weight);
      const ShapeDef* chosen = shapes.back();
      for (const ShapeDef* d : shapes) {
        if ((pick -= d->weight) < 0) {
          chosen = d;
          break;
        }
      }
      const ShapeDef& def = *chosen;
      const double s = std::clamp(rng.uniform(def.s_lo, def.s_hi), 0.075 * far_d / def.size_m,
                                  std::max(def.s_lo, 0.6 * L.D / def.size_m));
      Mover m;
      double rest_z = 0;
      m.object = buildShape(def.kind, next_id, s, rng, &rest_z);
      if (!planMotion(family, def.kind, s, rest_z, rng, L, &m)) continue;
      const MotionPlan plan = m.plan;
      Occupant occ = movingOccupant(
          m.object, [&](double t) { return plan.pose(t); }, L.T, 0.08);
      if (!insideRoom(L, occ, m.leaves_view)) continue;
      if (std::any_of(L.occupants.begin(), L.occupants.end(),
                      [&](const Occupant& o) { return collides(occ, o); })) {
        continue;
      }
      std::vector<Primitive> stand = m.stand;
      if (!stand.empty()) {
        const Occupant st = staticOccupant(stand, 0.05);
        if (!fits(L, st)) continue;
        L.occupants.push_back(st);
        for (auto& p : stand) scene.statics.push_back(p);
      }
      L.occupants.push_back(occ);
      m.object.trajectory.keys = plan.sample(L.T + 1.0, kKeyHz);
      m.object.motion = m.motion;
      description +=
          "; " + std::to_string(next_id) + " \"" + m.object.class_name + "\" " + m.motion;
      scene.objects.push_back(m.object);
      ++next_id;
      ++placed_movers;
      placed = true;
    }
  }
  // Still objects the detector reports.
  const int still = options.still >= 0 ? options.still : [&] {
    const double u = rng.uniform();
    return u < 0.3 ? 0 : (u < 0.65 ? 1 : (u < 0.88 ? 2 : 3));
  }();
  for (int i = 0; i < still; ++i) {
    for (int tries = 0; tries < 40; ++tries) {
      const int k = rng.uniformInt(0, 3);
      const Kind kind = k == 0 ? Kind::kTeddy
                               : (k == 1 ? Kind::kChair : (k == 2 ? Kind::kVase : Kind::kSuitcase));
      double rest_z = 0;
      SceneObject o = buildShape(kind, next_id, rng.uniform(0.9, 1.2), rng, &rest_z);
      const Eigen::AlignedBox3d b = objectBounds(o);
      Eigen::Vector3d sides = b.sizes();
      std::sort(sides.data(), sides.data() + 3);
      const Eigen::Vector2d p =
          stagePoint(rng, L, 0.5 * sides[2], 0.0, 525.0 / 48.0 * 0.8 * sides[1]);
      const Eigen::Isometry3d T = poseAt(p, rest_z, rng.uniform(-kPi, kPi));
      const Occupant occ{{worldBox(b, T)}, 0.08};
      if (!fits(L, occ)) continue;
      L.occupants.push_back(occ);
      o.trajectory.origin_m = T.translation();
      o.trajectory.R0 = T.linear();
      o.motion = "still";
      description += "; " + std::to_string(next_id) + " \"" + o.class_name + "\" still";
      scene.objects.push_back(o);
      ++next_id;
      break;
    }
  }
  scene.description = description + ".";

  // Detector imperfections of this seed.
  DetectorSimOptions& d = out.result.detector;
  d.miss_rate = rng.uniform(0.05, 0.2);
  d.false_positive_rate = rng.uniform(0.05, 0.25);
  d.max_boundary_px = rng.uniformInt(2, 4);
  d.max_shift_px = rng.uniformInt(1, 3);
  d.confusion_rate = rng.uniform(0.0, 0.08);
  d.spill_rate = rng.uniform(0.0, 0.1);
  d.partial_rate = rng.uniform(0.0, 0.1);
  d.late_frames = rng.bernoulli(0.25) ? rng.uniformInt(1, 2) : 0;

  // Accept when every object is in view long enough and the camera keeps clear of surfaces.
  std::vector<double> visible;
  double nearest = 0;
  std::vector<double> spread;
  viewCheck(scene, options.frames, &visible, &nearest, &spread);
  double score = placed_movers == movers ? 1.0 : -1.0;
  if (nearest < 0.35) score = -1.0;
  std::sort(spread.begin(), spread.end());
  const double spread_min = spread.empty() ? 0.0 : spread.front();
  const double spread_p10 = spread.empty() ? 0.0 : spread[spread.size() / 10];
  score = std::min({score, 10 * (spread_min - kMinNormalSpread), spread_p10 - kLowNormalSpread});
  for (size_t k = 0; k < scene.objects.size(); ++k) {
    const double need = scene.objects[k].motion == "pass" ? 0.35 : 0.6;
    score = std::min(score, visible[k] - need);
  }
  out.score = score;
  return out;
}

}  // namespace

const std::vector<std::string>& motionFamilyNames() {
  static const std::vector<std::string> kNames(kFamilyNames, kFamilyNames + kFamilies);
  return kNames;
}

const std::vector<std::string>& cameraFamilyNames() {
  static const std::vector<std::string> kNames = {"sweep", "xyz", "orbit"};
  return kNames;
}

RandomScene makeRandomScene(uint64_t seed, const RandomSceneOptions& options) {
  auto joined = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  };
  if (options.frames < 30 || options.frames > 100000) {
    throw InvalidArgument("synth:random: frames " + std::to_string(options.frames) +
                          " is out of range [30, 100000]");
  }
  if (options.movers < 0 || options.movers > 4) {
    throw InvalidArgument("synth:random: movers " + std::to_string(options.movers) +
                          " is out of range [1, 4] (0 = drawn from the seed)");
  }
  if (options.still < -1 || options.still > 3) {
    throw InvalidArgument("synth:random: still " + std::to_string(options.still) +
                          " is out of range [0, 3] (-1 = drawn from the seed)");
  }
  const auto& cameras = cameraFamilyNames();
  if (!options.camera.empty() &&
      std::find(cameras.begin(), cameras.end(), options.camera) == cameras.end()) {
    throw InvalidArgument("synth:random: unknown camera family '" + options.camera +
                          "': valid ones are " + joined(cameras));
  }
  unsigned families = 0;
  for (const auto& name : options.motions) {
    const auto& names = motionFamilyNames();
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) {
      throw InvalidArgument("synth:random: unknown motion family '" + name + "': valid ones are " +
                            joined(names));
    }
    families |= 1u << static_cast<unsigned>(it - names.begin());
  }
  if (families == 0) families = (1u << kFamilies) - 1;
  if (options.camera == "orbit" && families == bit(kPass)) {
    throw InvalidArgument(
        "synth:random: the motion family 'pass' needs a camera that keeps looking one way "
        "(sweep or xyz), not 'orbit'");
  }
  Attempt best;
  for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
    Attempt a = generate(seed, attempt, options, families);
    if (a.score > best.score) best = std::move(a);
    if (best.score >= 0.0) break;
  }
  return std::move(best.result);
}

}  // namespace emf::io::synth
