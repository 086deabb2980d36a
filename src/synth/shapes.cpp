#include "synth/shapes.h"

#include <algorithm>
#include <cmath>

namespace emf::synth {
namespace {

constexpr double kPi = 3.141592653589793;

}  // namespace

Material solid(float b, float g, float r) { return {{b, g, r}, {b, g, r}, Texture::kSolid, 1.0}; }
Material pattern(Texture t, std::array<float, 3> a, std::array<float, 3> b, double scale_m) {
  return {a, b, t, scale_m};
}

// ---- static furniture (world frame) ---------------------------------------------------------

void addRoom(Scene& s, V3 half_extents_m, double centre_y) {
  addRoom(s, half_extents_m, centre_y,
          pattern(Texture::kTiles, {0.22f, 0.38f, 0.55f}, {0.42f, 0.60f, 0.78f}, 0.4),
          pattern(Texture::kNoise, {0.80f, 0.85f, 0.88f}, {0.55f, 0.66f, 0.74f}, 0.3));
}

void addRoom(Scene& s, V3 half_extents_m, double centre_y, const Material& floor,
             const Material& walls) {
  s.statics.push_back(makePlane(at(0, 0, 0), floor));
  // The room box reaches below the floor plane so the floor is the plane, not the box bottom.
  s.statics.push_back(makeRoom(half_extents_m, at(0, centre_y, half_extents_m.z - 0.2), walls));
  // A picture and a door on the walls give the background colour and depth structure.
  const double back_y = centre_y + half_extents_m.y;
  s.statics.push_back(
      makeBox({0.5, 0.015, 0.35}, at(0.3, back_y - 0.015, 1.5),
              pattern(Texture::kChecker, {0.15f, 0.3f, 0.85f}, {0.8f, 0.65f, 0.2f}, 0.1)));
  s.statics.push_back(
      makeBox({0.02, 0.45, 1.0}, at(-half_extents_m.x + 0.02, centre_y + 0.4, 1.0),
              pattern(Texture::kStripes, {0.35f, 0.45f, 0.5f}, {0.25f, 0.32f, 0.38f}, 0.03)));
}

void addTable(Scene& s, double x, double y, double yaw, double half_x, double half_y) {
  const Eigen::Isometry3d T = at(x, y, 0, yaw);
  const Material wood =
      pattern(Texture::kStripes, {0.18f, 0.33f, 0.52f}, {0.28f, 0.45f, 0.66f}, 0.05);
  const Material metal = solid(0.25f, 0.25f, 0.27f);
  s.statics.push_back(makeBox({half_x, half_y, 0.02}, T * at(0, 0, 0.74), wood));
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      s.statics.push_back(makeBox({0.025, 0.025, 0.36},
                                  T * at(sx * (half_x - 0.06), sy * (half_y - 0.06), 0.36), metal));
    }
  }
}

void addShelf(Scene& s, double x, double y, double yaw) {
  const Eigen::Isometry3d T = at(x, y, 0, yaw);
  s.statics.push_back(
      makeBox({0.4, 0.18, 0.9}, T * at(0, 0, 0.9),
              pattern(Texture::kStripes, {0.2f, 0.25f, 0.6f}, {0.6f, 0.5f, 0.2f}, 0.07)));
}

std::vector<Primitive> chairParts(const Material& seat, const Material& legs) {
  std::vector<Primitive> p;
  p.push_back(makeBox({0.22, 0.22, 0.025}, at(0, 0, 0.45), seat));
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1})
      p.push_back(makeCylinder(0.02, 0.215, at(sx * 0.19, sy * 0.19, 0.215), legs));
  }
  p.push_back(makeBox({0.22, 0.02, 0.25}, at(0, 0.2, 0.72), seat));
  return p;
}

void addChair(Scene& s, double x, double y, double yaw) {
  const Eigen::Isometry3d T = at(x, y, 0, yaw);
  for (auto& part :
       chairParts(pattern(Texture::kChecker, {0.3f, 0.55f, 0.3f}, {0.2f, 0.4f, 0.2f}, 0.08),
                  solid(0.2f, 0.2f, 0.2f))) {
    part.T_parent_primitive = T * part.T_parent_primitive;
    s.statics.push_back(part);
  }
}

void addSofa(Scene& s, double x, double y, double yaw) {
  const Eigen::Isometry3d T = at(x, y, 0, yaw);
  const Material fabric = pattern(Texture::kNoise, {0.45f, 0.3f, 0.55f}, {0.3f, 0.2f, 0.4f}, 0.1);
  s.statics.push_back(makeRoundedBox({0.9, 0.4, 0.2}, 0.08, T * at(0, 0, 0.2), fabric));
  s.statics.push_back(makeRoundedBox({0.9, 0.1, 0.35}, 0.08, T * at(0, 0.32, 0.55), fabric));
  for (int sx : {-1, 1}) {
    s.statics.push_back(makeRoundedBox({0.1, 0.4, 0.12}, 0.05, T * at(sx * 0.82, 0, 0.5), fabric));
  }
}

void addLamp(Scene& s, double x, double y) {
  s.statics.push_back(makeCylinder(0.15, 0.015, at(x, y, 0.015), solid(0.2f, 0.2f, 0.2f)));
  s.statics.push_back(makeCylinder(0.015, 0.7, at(x, y, 0.72), solid(0.6f, 0.6f, 0.6f)));
  s.statics.push_back(makeSphere(0.18, at(x, y, 1.5), solid(0.75f, 0.9f, 0.95f)));
}

void addTableItems(Scene& s, double x, double y) {
  const double top = 0.76;
  s.statics.push_back(
      makeSphere(0.1, at(x + 0.3, y - 0.1, top + 0.1),
                 pattern(Texture::kChecker, {0.1f, 0.1f, 0.8f}, {0.9f, 0.9f, 0.9f}, 0.05)));
  s.statics.push_back(
      makeCylinder(0.06, 0.12, at(x - 0.3, y + 0.1, top + 0.12),
                   pattern(Texture::kStripes, {0.7f, 0.4f, 0.1f}, {0.9f, 0.8f, 0.5f}, 0.04)));
  s.statics.push_back(
      makeCapsule(0.035, 0.08, at(x, y + 0.15, top + 0.115), solid(0.2f, 0.6f, 0.25f)));
}

// ---- objects (object frame: x forward, z up, origin on the floor unless noted) ---------------

SceneObject car(int id, const Material& body, const Material& cabin) {
  SceneObject o;
  o.id = id;
  o.class_name = "car";
  const Material tyre = solid(0.08f, 0.08f, 0.08f);
  o.parts.push_back(makeRoundedBox({0.17, 0.08, 0.045}, 0.03, at(0, 0, 0.08), body));
  o.parts.push_back(makeRoundedBox({0.08, 0.07, 0.04}, 0.025, at(-0.02, 0, 0.16), cabin));
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      // Cylinder axis (local z) along the car's y axis.
      o.parts.push_back(
          makeCylinder(0.035, 0.015, at(sx * 0.11, sy * 0.085, 0.035, 0, 0, kPi / 2), tyre));
    }
  }
  return o;
}

SceneObject teddy(int id) {
  // Origin at the body centre; facing -y.
  SceneObject o;
  o.id = id;
  o.class_name = "teddy bear";
  const Material fur = pattern(Texture::kNoise, {0.2f, 0.4f, 0.62f}, {0.1f, 0.25f, 0.42f}, 0.04);
  const Material dark = solid(0.1f, 0.15f, 0.25f);
  o.parts.push_back(makeSphere(0.14, at(0, 0, 0), fur));
  o.parts.push_back(makeSphere(0.1, at(0, 0, 0.21), fur));
  for (int sx : {-1, 1}) {
    o.parts.push_back(makeSphere(0.04, at(sx * 0.07, 0, 0.29), dark));
    o.parts.push_back(makeCapsule(0.04, 0.06, at(sx * 0.15, -0.02, 0.03, 0, sx * 0.6, 0), fur));
    o.parts.push_back(makeCapsule(0.045, 0.05, at(sx * 0.08, -0.06, -0.13, 0, 0, kPi / 2), fur));
  }
  o.parts.push_back(makeSphere(0.045, at(0, -0.085, 0.19), solid(0.5f, 0.7f, 0.85f)));
  return o;
}

SceneObject suitcase(int id) {
  SceneObject o;
  o.id = id;
  o.class_name = "suitcase";
  o.parts.push_back(
      makeRoundedBox({0.3, 0.12, 0.4}, 0.04, at(0, 0, 0.4),
                     pattern(Texture::kChecker, {0.55f, 0.25f, 0.1f}, {0.75f, 0.45f, 0.2f}, 0.12)));
  const Material black = solid(0.1f, 0.1f, 0.1f);
  o.parts.push_back(makeCapsule(0.015, 0.1, at(0, 0, 0.88, 0, kPi / 2, 0), black));
  for (int sx : {-1, 1}) o.parts.push_back(makeCylinder(0.012, 0.04, at(sx * 0.1, 0, 0.84), black));
  return o;
}

SceneObject chairObject(int id) {
  SceneObject o;
  o.id = id;
  o.class_name = "chair";
  o.parts = chairParts(pattern(Texture::kStripes, {0.15f, 0.2f, 0.75f}, {0.3f, 0.5f, 0.9f}, 0.06),
                       solid(0.15f, 0.15f, 0.15f));
  return o;
}

SceneObject couch(int id) {
  SceneObject o;
  o.id = id;
  o.class_name = "couch";
  const Material fabric =
      pattern(Texture::kNoise, {0.3f, 0.55f, 0.25f}, {0.2f, 0.35f, 0.12f}, 0.08);
  const Material cushion =
      pattern(Texture::kChecker, {0.35f, 0.6f, 0.3f}, {0.25f, 0.45f, 0.2f}, 0.15);
  o.parts.push_back(makeRoundedBox({0.9, 0.4, 0.2}, 0.06, at(0, 0, 0.2), fabric));
  o.parts.push_back(makeRoundedBox({0.7, 0.3, 0.06}, 0.04, at(0, -0.05, 0.45), cushion));
  o.parts.push_back(makeRoundedBox({0.9, 0.1, 0.3}, 0.06, at(0, 0.3, 0.6), fabric));
  for (int sx : {-1, 1}) {
    o.parts.push_back(makeRoundedBox({0.1, 0.4, 0.15}, 0.05, at(sx * 0.8, 0, 0.5), fabric));
  }
  return o;
}

SceneObject mug(int id, double s, const Material& body) {
  SceneObject o;
  o.id = id;
  o.class_name = "cup";
  o.parts.push_back(makeCylinder(0.06 * s, 0.06 * s, at(0, 0, 0.06 * s), body));
  // Handle: a short capsule parallel to the body and two stubs joining it.
  o.parts.push_back(makeCapsule(0.012 * s, 0.025 * s, at(0.085 * s, 0, 0.065 * s), body));
  for (int sz : {-1, 1}) {
    o.parts.push_back(makeCapsule(0.011 * s, 0.012 * s,
                                  at(0.07 * s, 0, (0.065 + sz * 0.03) * s, 0, kPi / 2, 0), body));
  }
  return o;
}

SceneObject bottle(int id, double s, const Material& body, const Material& cap) {
  SceneObject o;
  o.id = id;
  o.class_name = "bottle";
  // A spray bottle: a flattened body, a neck, and a head with its nozzle and trigger on +x.
  o.parts.push_back(
      makeRoundedBox({0.045 * s, 0.028 * s, 0.1 * s}, 0.02 * s, at(0, 0, 0.1 * s), body));
  o.parts.push_back(makeCylinder(0.016 * s, 0.025 * s, at(0, 0, 0.225 * s), cap));
  o.parts.push_back(
      makeRoundedBox({0.04 * s, 0.02 * s, 0.022 * s}, 0.008 * s, at(0.02 * s, 0, 0.27 * s), cap));
  o.parts.push_back(makeBox({0.008 * s, 0.012 * s, 0.03 * s}, at(0.045 * s, 0, 0.22 * s), cap));
  return o;
}

SceneObject book(int id, double s, const Material& cover) {
  SceneObject o;
  o.id = id;
  o.class_name = "book";
  o.parts.push_back(makeBox({0.11 * s, 0.08 * s, 0.0175 * s}, at(0, 0, 0.0175 * s), cover));
  // The block of pages shows on three sides, a little lighter than the cover.
  o.parts.push_back(makeBox({0.108 * s, 0.082 * s, 0.014 * s}, at(0.004 * s, 0, 0.0175 * s),
                            solid(0.85f, 0.88f, 0.9f)));
  return o;
}

SceneObject laptop(int id, double s, const Material& shell, const Material& screen) {
  SceneObject o;
  o.id = id;
  o.class_name = "laptop";
  o.parts.push_back(makeBox({0.17 * s, 0.12 * s, 0.01 * s}, at(0, 0, 0.01 * s), shell));
  // The lid hinges on the base's back edge (+y) and leans back by 20 degrees.
  const double lean = 0.35;
  const double h = 0.115 * s;
  o.parts.push_back(makeBox(
      {0.17 * s, 0.006 * s, h},
      at(0, 0.12 * s + h * std::sin(lean), 0.02 * s + h * std::cos(lean), 0, 0, -lean), screen));
  return o;
}

SceneObject backpack(int id, double s, const Material& fabric, const Material& pocket) {
  SceneObject o;
  o.id = id;
  o.class_name = "backpack";
  o.parts.push_back(
      makeRoundedBox({0.15 * s, 0.09 * s, 0.2 * s}, 0.05 * s, at(0, 0, 0.2 * s), fabric));
  o.parts.push_back(
      makeRoundedBox({0.11 * s, 0.04 * s, 0.09 * s}, 0.03 * s, at(0, -0.11 * s, 0.13 * s), pocket));
  o.parts.push_back(makeCapsule(0.012 * s, 0.05 * s, at(0, 0, 0.415 * s, 0, kPi / 2, 0), pocket));
  for (int sx : {-1, 1}) {
    o.parts.push_back(
        makeCapsule(0.015 * s, 0.13 * s, at(sx * 0.08 * s, 0.1 * s, 0.2 * s), pocket));
  }
  return o;
}

SceneObject vase(int id, double s, const Material& body) {
  SceneObject o;
  o.id = id;
  o.class_name = "vase";
  // A jug: a cylinder with a rim, a handle on -x and a spout on +x.
  const double r = 0.1 * s, hz = 0.2 * s;
  o.parts.push_back(makeCylinder(r, hz, at(0, 0, hz), body));
  o.parts.push_back(
      makeCylinder(r * 1.12, 0.015 * s, at(0, 0, 2 * hz - 0.015 * s), solid(0.85f, 0.85f, 0.8f)));
  o.parts.push_back(makeCapsule(0.018 * s, 0.1 * s, at(-0.165 * s, 0, 0.23 * s), body));
  for (double z : {0.13, 0.33}) {
    o.parts.push_back(
        makeCapsule(0.016 * s, 0.03 * s, at(-0.13 * s, 0, z * s, 0, kPi / 2, 0), body));
  }
  o.parts.push_back(makeCapsule(0.022 * s, 0.1 * s, at(0.16 * s, 0, 0.22 * s, 0, 0.7, 0), body));
  return o;
}

SceneObject rockingHorse(int id, double s, const Material& body, const Material& rockers) {
  SceneObject o;
  o.id = id;
  o.class_name = "horse";
  const double R = kRockerRadius * s;
  // Heights below are above the floor; the origin is R above it.
  auto above = [&](double x, double y, double z, double yaw = 0, double pitch = 0,
                   double roll = 0) { return at(x * s, y * s, z * s - R, yaw, pitch, roll); };
  for (int sy : {-1, 1}) {
    // Each rocker: two capsules approximating an arc of radius R through x = +-0.36 s.
    for (int sx : {-1, 1}) {
      o.parts.push_back(makeCapsule(0.022 * s, 0.19 * s,
                                    above(sx * 0.19, sy * 0.15, 0.04, 0, sx * (kPi / 2 - 0.2), 0),
                                    rockers));
    }
    // Legs from the rockers up to the body, splayed a little.
    for (int sx : {-1, 1}) {
      o.parts.push_back(makeCapsule(
          0.025 * s, 0.16 * s, above(sx * 0.2, sy * 0.12, 0.24, 0, -sx * 0.25, sy * 0.15), body));
    }
  }
  o.parts.push_back(makeCapsule(0.11 * s, 0.17 * s, above(0, 0, 0.45, 0, kPi / 2, 0), body));
  o.parts.push_back(makeCapsule(0.05 * s, 0.1 * s, above(0.27, 0, 0.58, 0, 0.6, 0), body));
  o.parts.push_back(makeRoundedBox({0.1 * s, 0.045 * s, 0.05 * s}, 0.03 * s,
                                   above(0.36, 0, 0.69, 0, 0.5, 0), body));
  o.parts.push_back(makeBox({0.02 * s, 0.12 * s, 0.015 * s}, above(0.22, 0, 0.58), rockers));
  return o;
}

SceneObject airship(int id, double s, const Material& envelope, const Material& fins) {
  SceneObject o;
  o.id = id;
  o.class_name = "airplane";
  o.parts.push_back(makeCapsule(0.16 * s, 0.24 * s, at(0, 0, 0, 0, kPi / 2, 0), envelope));
  for (int k = 0; k < 4; ++k) {
    const double roll = k * kPi / 2;
    o.parts.push_back(makeBox({0.07 * s, 0.006 * s, 0.06 * s},
                              at(-0.34 * s, 0, 0, 0, 0, roll) * at(0, 0, 0.17 * s), fins));
  }
  o.parts.push_back(
      makeRoundedBox({0.08 * s, 0.035 * s, 0.03 * s}, 0.015 * s, at(0.02 * s, 0, -0.19 * s), fins));
  return o;
}

SceneObject skateboard(int id, double s, const Material& deck) {
  SceneObject o;
  o.id = id;
  o.class_name = "skateboard";
  o.parts.push_back(
      makeRoundedBox({0.4 * s, 0.105 * s, 0.012 * s}, 0.01 * s, at(0, 0, 0.085 * s), deck));
  const Material wheel = solid(0.8f, 0.85f, 0.85f);
  for (int sx : {-1, 1}) {
    o.parts.push_back(makeBox({0.02 * s, 0.07 * s, 0.012 * s}, at(sx * 0.27 * s, 0, 0.062 * s),
                              solid(0.5f, 0.5f, 0.5f)));
    for (int sy : {-1, 1}) {
      o.parts.push_back(makeCylinder(0.027 * s, 0.016 * s,
                                     at(sx * 0.27 * s, sy * 0.085 * s, 0.027 * s, 0, 0, kPi / 2),
                                     wheel));
    }
  }
  return o;
}

SceneObject surfboard(int id, double s, const Material& board) {
  SceneObject o;
  o.id = id;
  o.class_name = "surfboard";
  o.parts.push_back(
      makeRoundedBox({0.23 * s, 0.03 * s, 0.72 * s}, 0.028 * s, at(0, 0, 0.78 * s), board));
  o.parts.push_back(
      makeBox({0.2 * s, 0.16 * s, 0.03 * s}, at(0, 0, 0.03 * s), solid(0.2f, 0.2f, 0.22f)));
  return o;
}

SceneObject box(int id, V3 half_extents_m, const Material& cardboard) {
  SceneObject o;
  o.id = id;
  o.class_name = "suitcase";
  o.parts.push_back(makeRoundedBox(half_extents_m, std::min(0.01, 0.3 * half_extents_m.z),
                                   at(0, 0, half_extents_m.z), cardboard));
  // A strip of tape across the top.
  o.parts.push_back(makeBox({half_extents_m.x * 0.98, 0.03, 0.004}, at(0, 0, 2 * half_extents_m.z),
                            solid(0.55f, 0.7f, 0.8f)));
  return o;
}

}  // namespace emf::synth
