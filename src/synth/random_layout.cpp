// The layout of a generated scene while it is built: geometry helpers, occupants, random
// materials and the stage.
#include "synth/random_layout.h"

#include <algorithm>
#include <cmath>

#include "synth/shapes.h"

namespace emf::synth::random_gen {

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

std::array<float, 3> randomColour(Rng& rng, double lo, double hi) {
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

Eigen::Vector2d stagePoint(Rng& rng, const Layout& L, double clearance, double min_distance,
                           double max_distance) {
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

}  // namespace emf::synth::random_gen
