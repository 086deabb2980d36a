// The movers of the generated scenes: building a shape of the library and planning its motion
// family on the stage.
#include "synth/random_movers.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "synth/shapes.h"

namespace emf::synth::random_gen {
namespace {

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

}  // namespace

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

Eigen::Isometry3d poseAt(const Eigen::Vector2d& p, double z, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.x(), p.y(), z);
  return T;
}

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
      const double speed_mps = rng.uniform(0.15, 0.32);  // one draw per statement (rng.h)
      const double phase0 = rng.uniform();
      m->plan.drive(T - rest0, curve, phase0, speed_mps, 50 * kDeg, stops);
      m->motion = "drive";
      return true;
    }
    case kSpin: {
      m->plan = MotionPlan(poseAt(p, rest_z, yaw0));
      while (m->plan.end() < T - 2.0) {
        m->plan.rest(rng.uniform(0.5, 3.0));
        const double sign = rng.bernoulli(0.5) ? 1 : -1;
        const double angle = sign * rng.uniform(60, 270) * kDeg;
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
            const double w_z = rng.normal();
            const double w_y = rng.normal();
            const double w_x = rng.normal();
            const Eigen::Vector3d w(w_x, w_y, w_z);
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
        const double speed_mps = rng.uniform(0.12, 0.25);
        const double phase0 = rng.uniform();
        m->plan.drive(T - m->plan.end(), curve, phase0, speed_mps, 35 * kDeg, {});
        m->motion = "float";
        return true;
      }
      while (m->plan.end() < T - 4.0) {
        // One draw per statement (rng.h), z before y before x: the order these scenes were made
        // with.
        const double amp_m_z = rng.uniform(0.05, 0.2);
        const double amp_m_y = rng.uniform(0.1, 0.3);
        const double amp_m_x = rng.uniform(0.15, 0.45);
        const Eigen::Vector3d amp_m(amp_m_x, amp_m_y, amp_m_z);
        const double amp_rad_z = rng.uniform(0.1, 0.4);
        const double amp_rad_y = rng.uniform(0.05, 0.2);
        const double amp_rad_x = rng.uniform(0.05, 0.2);
        const Eigen::Vector3d amp_rad(amp_rad_x, amp_rad_y, amp_rad_z);
        const double f_z = rng.uniform(0.08, 0.2);
        const double f_y = rng.uniform(0.06, 0.16);
        const double f_x = rng.uniform(0.05, 0.15);
        const Eigen::Vector3d f(f_x, f_y, f_z);
        const double phase_z = rng.uniform(0, 2 * kPi);
        const double phase_y = rng.uniform(0, 2 * kPi);
        const double phase_x = rng.uniform(0, 2 * kPi);
        const Eigen::Vector3d phase(phase_x, phase_y, phase_z);
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

}  // namespace emf::synth::random_gen
