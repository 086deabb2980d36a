#include "io/synth/presets.h"

#include <cmath>

#include "common/error.h"

namespace emf::io::synth {
namespace {

constexpr double kPi = 3.141592653589793;

Material solid(float b, float g, float r) { return {{b, g, r}, {b, g, r}, Texture::kSolid, 1.0}; }
Material pattern(Texture t, std::array<float, 3> a, std::array<float, 3> b, double scale_m) {
  return {a, b, t, scale_m};
}

Sinusoid sine(double ax, double ay, double az, double f_hz, double phase = 0.0) {
  return {Eigen::Vector3d(ax, ay, az), f_hz, phase};
}

Eigen::Vector3d v3(double x, double y, double z) { return {x, y, z}; }

// ---- static furniture (world frame) ---------------------------------------------------------

void addRoom(Scene& s, V3 half_extents_m, double centre_y) {
  const Material floor =
      pattern(Texture::kTiles, {0.22f, 0.38f, 0.55f}, {0.42f, 0.60f, 0.78f}, 0.4);
  const Material walls =
      pattern(Texture::kNoise, {0.80f, 0.85f, 0.88f}, {0.55f, 0.66f, 0.74f}, 0.3);
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

// ---- cameras --------------------------------------------------------------------------------

void handHeld(CameraRig& rig) {
  // Small, faster position wobble and rotational tremor (tenths of a degree).
  rig.path.position_terms.push_back(sine(0.004, 0.003, 0.004, 1.7, 0.3));
  rig.path.position_terms.push_back(sine(0.002, 0.003, 0.002, 2.9, 1.1));
  rig.tremor_rad.push_back(sine(0.004, 0.005, 0.003, 1.3, 0.2));
  rig.tremor_rad.push_back(sine(0.002, 0.002, 0.002, 2.3, 1.7));
}

// ---- presets --------------------------------------------------------------------------------

Scene room() {
  Scene s;
  s.name = "room";
  s.description =
      "A static room (5.2 x 4.8 x 2.8 m) with a table (a ball, a vase and a bottle on it), two "
      "chairs, a shelf, a sofa, a floor lamp, a picture and a door. Nothing moves but the "
      "camera, which sweeps sideways in front of the table (about 0.3 m/s) looking at a slowly "
      "wandering point.";
  s.default_frames = 300;
  addRoom(s, {2.6, 2.4, 1.5}, 0.3);
  addTable(s, 0, 0.7, 0, 0.6, 0.4);
  addTableItems(s, 0, 0.7);
  addChair(s, -0.9, 0.5, 0.5);
  addChair(s, 0.2, 1.4, kPi);
  addShelf(s, -1.9, 2.45, 0);
  addSofa(s, 1.4, 2.1, 0);
  addLamp(s, 2.1, 0.2);
  s.camera.path.origin_m = v3(0, -1.6, 1.45);
  s.camera.path.position_terms = {sine(1.0, 0, 0, 0.05), sine(0, 0.3, 0, 0.1, 1.0),
                                  sine(0, 0, 0.1, 0.13)};
  s.camera.target.origin_m = v3(0, 0.8, 0.7);
  s.camera.target.position_terms = {sine(0.6, 0, 0, 0.07, 0.5), sine(0, 0, 0.15, 0.09)};
  handHeld(s.camera);
  return s;
}

Scene cars() {
  Scene s;
  s.name = "cars";
  s.description =
      "Two toy cars (class \"car\", about 34 cm long) drive on the floor in front of a table "
      "from the first frame on: object 1 (red) counter-clockwise on a 1.7 x 1.1 m ellipse "
      "(period 14.3 s, up to 0.37 m/s), object 2 (blue) clockwise on a 0.9 x 0.44 m ellipse "
      "(period 9.1 s, up to 0.31 m/s), both pointing where they drive and bouncing slightly. "
      "The camera sweeps sideways about 2.4 m away, looking down at the cars.";
  s.default_frames = 450;
  addRoom(s, {2.6, 2.4, 1.5}, 0.3);
  addTable(s, 0.2, 2.0, 0, 0.6, 0.35);
  addTableItems(s, 0.2, 2.0);
  addShelf(s, -1.9, 2.45, 0);
  addChair(s, 1.5, 1.6, 2.5);
  const Eigen::Vector3d centre(0, 0.7, 0);
  SceneObject c1 = car(1, pattern(Texture::kStripes, {0.1f, 0.1f, 0.8f}, {0.9f, 0.9f, 0.9f}, 0.08),
                       solid(0.15f, 0.15f, 0.5f));
  c1.trajectory.origin_m = centre;
  c1.trajectory.position_terms = {sine(0.85, 0, 0, 0.07, kPi / 2), sine(0, 0.55, 0, 0.07),
                                  sine(0, 0, 0.003, 2.7)};
  c1.trajectory.rotation_terms = {sine(0.02, 0, 0, 1.9), sine(0, 0.015, 0, 2.3, 1.0)};
  c1.trajectory.face_velocity = true;
  SceneObject c2 =
      car(2, pattern(Texture::kChecker, {0.8f, 0.45f, 0.1f}, {0.95f, 0.85f, 0.6f}, 0.05),
          solid(0.5f, 0.3f, 0.1f));
  c2.trajectory.origin_m = centre;
  c2.trajectory.position_terms = {sine(0.45, 0, 0, 0.11, kPi / 2), sine(0, -0.22, 0, 0.11),
                                  sine(0, 0, 0.003, 3.1, 0.5)};
  c2.trajectory.rotation_terms = {sine(0.02, 0, 0, 2.1, 0.4), sine(0, 0.015, 0, 2.6)};
  c2.trajectory.face_velocity = true;
  s.objects = {c1, c2};
  s.camera.path.origin_m = v3(0, -1.4, 1.25);
  s.camera.path.position_terms = {sine(0.7, 0, 0, 0.045), sine(0, 0.25, 0, 0.09, 0.7),
                                  sine(0, 0, 0.08, 0.12, 2.0)};
  s.camera.target.origin_m = v3(0, 0.7, 0.05);
  s.camera.target.position_terms = {sine(0.25, 0, 0, 0.06, 0.4), sine(0, 0.15, 0, 0.05)};
  handHeld(s.camera);
  return s;
}

Scene occlusion() {
  Scene s;
  s.name = "occlusion";
  s.description =
      "A room with three objects. Object 1 (\"teddy bear\") flies around at head height from "
      "the first frame on (sinusoidal translation up to ~0.35 m/s and turning). Object 2 "
      "(\"suitcase\", 0.6 x 0.24 x 0.9 m) stands out of view on the left, slides in between "
      "2 s and 5 s (frames 60-150), stays in front of the chair, hiding most of it, until 9 s "
      "(frame 270), then slides out to the right by 12 s (frame 360). Object 3 (\"chair\") "
      "stands still until 13 s (frame 390), then accelerates over 1 s into a sideways swinging, "
      "turning motion. The camera sweeps sideways about 2.4 m in front of the chair.";
  s.default_frames = 600;
  addRoom(s, {2.6, 2.4, 1.5}, 0.4);
  addTable(s, -1.6, 1.9, 0.3, 0.5, 0.35);
  addShelf(s, 1.6, 2.6, 0);
  addLamp(s, 2.0, 0.6);

  SceneObject bear = teddy(1);
  bear.trajectory.origin_m = v3(0.3, 1.1, 1.45);
  bear.trajectory.position_terms = {sine(0.7, 0, 0, 0.06), sine(0, 0.3, 0, 0.09, 1.0),
                                    sine(0, 0, 0.2, 0.13, 0.3)};
  bear.trajectory.rotation_terms = {sine(0, 0, 0.8, 0.05), sine(0.3, 0, 0, 0.11, 1.0),
                                    sine(0, 0.25, 0, 0.17)};
  SceneObject bag = suitcase(2);
  bag.trajectory.origin_m = v3(-1.5, -0.1, 0);
  bag.trajectory.moves = {{2.0, 5.0, v3(1.5, 0, 0), v3(0, 0, 0.25)},
                          {9.0, 12.0, v3(1.5, 0, 0), v3(0, 0, -0.25)}};
  SceneObject chair = chairObject(3);
  chair.trajectory.origin_m = v3(0, 0.5, 0);
  chair.trajectory.position_terms = {sine(0.5, 0, 0, 0.1), sine(0, 0.2, 0, 0.07)};
  chair.trajectory.rotation_terms = {sine(0, 0, 0.5, 0.08)};
  chair.trajectory.still_until_s = 13.0;
  chair.trajectory.ramp_s = 1.0;
  s.objects = {bear, bag, chair};

  s.camera.path.origin_m = v3(0, -1.8, 1.15);
  s.camera.path.position_terms = {sine(0.7, 0, 0, 0.05), sine(0, 0.2, 0, 0.08, 1.0),
                                  sine(0, 0, 0.06, 0.11)};
  s.camera.target.origin_m = v3(0, 0.5, 0.7);
  s.camera.target.position_terms = {sine(0.3, 0, 0, 0.045, 0.3), sine(0, 0, 0.1, 0.07)};
  handHeld(s.camera);
  return s;
}

Scene enter() {
  Scene s;
  s.name = "enter";
  s.description =
      "A room with a table, a shelf, a chair and a lamp. Object 1 (\"couch\", 2.0 x 0.9 x 0.9 m) "
      "starts out of view on the right, enters through the right image border between 1.5 s "
      "and 6.5 s (frames 45-195) while turning by 20 degrees, stops near the image centre, "
      "shifts by 0.4 m between 8 s and 9.5 s (frames 240-285), then stays. The camera sweeps "
      "gently about 2.3 m in front of it.";
  s.default_frames = 300;
  addRoom(s, {4.0, 2.6, 1.5}, 0.4);
  addTable(s, -1.7, 1.3, 0.2, 0.5, 0.35);
  addTableItems(s, -1.7, 1.3);
  addShelf(s, -2.6, 2.75, 0);
  addChair(s, -0.9, 2.2, 0);
  addLamp(s, 1.2, 2.5);
  SceneObject c = couch(1);
  c.trajectory.origin_m = v3(3.0, 0.6, 0);
  c.trajectory.moves = {{1.5, 6.5, v3(-3.0, 0, 0), v3(0, 0, 0.35)},
                        {8.0, 9.5, v3(0.3, 0.25, 0), v3(0, 0, -0.2)}};
  s.objects = {c};
  s.camera.path.origin_m = v3(0, -1.7, 1.3);
  s.camera.path.position_terms = {sine(0.35, 0, 0, 0.06, kPi), sine(0, 0.3, 0, 0.1),
                                  sine(0, 0, 0.08, 0.13, 0.5)};
  s.camera.target.origin_m = v3(0, 0.6, 0.5);
  s.camera.target.position_terms = {sine(0.2, 0, 0, 0.05, 0.2), sine(0, 0, 0.1, 0.08)};
  handHeld(s.camera);
  return s;
}

}  // namespace

std::vector<std::string> presetNames() { return {"room", "cars", "occlusion", "enter"}; }

Scene makePreset(const std::string& name) {
  if (name == "room") return room();
  if (name == "cars") return cars();
  if (name == "occlusion") return occlusion();
  if (name == "enter") return enter();
  std::string valid;
  for (const auto& n : presetNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw IoError("synth: unknown preset '" + name + "': valid presets are " + valid);
}

}  // namespace emf::io::synth
