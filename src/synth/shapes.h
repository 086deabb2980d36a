// The synthetic world's building blocks: static furniture (added to a scene's statics, world
// frame) and the shape library of detectable objects (object frame O: x forward, z up; the
// origin on the floor under the object unless a builder says otherwise). Units: metres,
// radians; colours linear BGR in [0, 1]. The presets and the generated scenes (random_scene.h)
// share them.
#pragma once

#include <string>

#include "synth/scene.h"

namespace emf::synth {

/// A sinusoid term (per-axis amplitude, frequency, phase).
inline Sinusoid sine(double ax, double ay, double az, double f_hz, double phase = 0.0) {
  return {Eigen::Vector3d(ax, ay, az), f_hz, phase};
}
inline Eigen::Vector3d v3(double x, double y, double z) { return {x, y, z}; }

Material solid(float b, float g, float r);
Material pattern(Texture t, std::array<float, 3> a, std::array<float, 3> b, double scale_m);

// ---- static furniture (world frame) ---------------------------------------------------------

/// Floor plane, the room box (half extents, centred at (0, centre_y)), a picture on the back
/// wall and a door on the left wall.
void addRoom(Scene& s, V3 half_extents_m, double centre_y);
/// The same with the caller's materials (generated scenes vary them).
void addRoom(Scene& s, V3 half_extents_m, double centre_y, const Material& floor,
             const Material& walls);
void addTable(Scene& s, double x, double y, double yaw, double half_x, double half_y);
void addShelf(Scene& s, double x, double y, double yaw);
/// A static chair (the shape of chairObject, never detected).
void addChair(Scene& s, double x, double y, double yaw);
void addSofa(Scene& s, double x, double y, double yaw);
void addLamp(Scene& s, double x, double y);
/// A ball, a vase and a bottle on a table top (0.76 m) centred at (x, y).
void addTableItems(Scene& s, double x, double y);

// ---- objects --------------------------------------------------------------------------------

/// Toy car, 0.34 x 0.2 x 0.2 m, class "car".
SceneObject car(int id, const Material& body, const Material& cabin);
/// Teddy bear, about 0.3 x 0.25 x 0.45 m; origin at the body centre (0.14 m above its lowest
/// point, the feet at z = -0.175), facing -y. Class "teddy bear".
SceneObject teddy(int id);
/// Suitcase, 0.6 x 0.24 x 0.92 m, class "suitcase".
SceneObject suitcase(int id);
/// Chair, 0.44 x 0.44 x 0.97 m (seat at 0.45 m, backrest on +y), class "chair".
SceneObject chairObject(int id);
/// Couch, 2.0 x 0.9 x 0.9 m, class "couch".
SceneObject couch(int id);

// The generated scenes' shape library. Each builder takes a size scale s (1 = the size given)
// and the object's materials; origins are on the floor under the object's centre unless noted.

/// Mug: cylinder of radius 0.06 s and height 0.12 s with a handle on +x. Class "cup".
SceneObject mug(int id, double s, const Material& body);
/// Spray bottle: a flattened body 0.09 s x 0.056 s x 0.2 s, a neck and a head with nozzle and
/// trigger on +x; 0.3 s high. Class "bottle".
SceneObject bottle(int id, double s, const Material& body, const Material& cap);
/// Book: 0.22 s x 0.16 s x 0.035 s, a cover and a lighter block of pages. Class "book".
SceneObject book(int id, double s, const Material& cover);
/// Laptop, open: base 0.34 s x 0.24 s x 0.02 s, screen tilted back by 20 deg. Class "laptop".
SceneObject laptop(int id, double s, const Material& shell, const Material& screen);
/// Backpack, 0.3 s x 0.26 s x 0.43 s: a body, a front pocket (-y), a handle and two straps.
/// Class "backpack".
SceneObject backpack(int id, double s, const Material& fabric, const Material& pocket);
/// Jug: a cylinder of radius 0.1 s and height 0.4 s with a rim, a handle on -x and a spout on
/// +x (no rotational symmetry: its turn about its axis is observable). Class "vase".
SceneObject vase(int id, double s, const Material& body);
/// Rocking horse, 0.8 s long, 0.75 s high: body, neck, head and legs on two rockers. The
/// rockers are arcs of radius kRockerRadius s (approximated by capsules along their chord);
/// the origin is the rockers' centre of curvature, kRockerRadius s above the floor, so rocking
/// by theta about y rolls it by kRockerRadius s theta along x. Class "horse".
SceneObject rockingHorse(int id, double s, const Material& body, const Material& rockers);
constexpr double kRockerRadius = 0.9;
/// Airship: an envelope 0.8 s long and 0.32 s across with fins and a gondola; origin at the
/// envelope's centre. Class "airplane".
SceneObject airship(int id, double s, const Material& envelope, const Material& fins);
/// Skateboard: a deck 0.8 s x 0.21 s on four wheels, 0.1 s high. Class "skateboard".
SceneObject skateboard(int id, double s, const Material& deck);
/// Surfboard standing on its tail: 0.46 s wide, 1.5 s high, 0.06 s thick, on a small foot.
/// Class "surfboard".
SceneObject surfboard(int id, double s, const Material& board);
/// Cardboard box of the given half extents (metres) on the floor. Class "suitcase".
SceneObject box(int id, V3 half_extents_m, const Material& cardboard);

}  // namespace emf::synth
