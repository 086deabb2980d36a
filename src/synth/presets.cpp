#include "synth/presets.h"

#include <cmath>

#include "common/error.h"
#include "synth/apartment.h"
#include "synth/shapes.h"

namespace emf::synth {
namespace {

constexpr double kPi = 3.141592653589793;

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

std::vector<std::string> presetNames() {
  return {"room", "cars", "occlusion", "enter", "apartment"};
}

Scene makePreset(const std::string& name) {
  if (name == "room") return room();
  if (name == "cars") return cars();
  if (name == "occlusion") return occlusion();
  if (name == "enter") return enter();
  if (name == "apartment") return apartment();
  std::string valid;
  for (const auto& n : presetNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw IoError("synth: unknown preset '" + name + "': valid presets are " + valid);
}

}  // namespace emf::synth
