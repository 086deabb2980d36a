// The `apartment` preset: a static flat of four rooms and a hallway (walls, door frames, open
// door leaves, furniture in every room) and a hand-held camera walking one closed loop through
// all of it. Built for long sequences whose map outgrows one volume: the loop is about 36.5 m
// long and ends where it started.
//
// World frame: z up, floor z = 0, metres, radians. The flat covers x in [0, 12], y in [0, 9]:
//
//   y=9 +------+----------------------+--------------------+
//       |      |                      |                    |
//       |      D    bedroom           D    study           |
//       | hall |                      |                    |
//   4.6 |      +----------------------+--D-----------------+
//       |      |                      |                    |
//       |      D    living room       D    kitchen         |
//   y=0 +--F---+----------------------+--------------------+
//      x=0    1.8                    7.0                  12
//
// (D: doorways, F: the flat's closed front door.) The camera walks counter-clockwise: living
// room -> kitchen (round the island) -> study (round a pillar) -> bedroom (past the foot of the
// bed) -> hallway (southwards) -> living room. Furniture builders place their piece in a frame
// whose origin is on the floor under its footprint's centre, with its front facing local -y.
#include "synth/apartment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "synth/rng.h"
#include "synth/shapes.h"

namespace emf::synth {
namespace {

constexpr double kPi = 3.141592653589793;
constexpr double kDeg = kPi / 180.0;

// ---- the shell --------------------------------------------------------------------------------

constexpr double kWallHalf = 0.05;           // walls are 0.1 m thick
constexpr double kWallHeight = 2.5;          // floor to ceiling
constexpr double kOpeningHalf = 0.53;        // doorway cut into a wall: 1.06 m wide ...
constexpr double kOpeningHeight = 2.15;      // ... and 2.15 m high
constexpr double kJamb = 0.05;               // door frame: clear passage 0.96 m x 2.10 m
constexpr double kLeafOpenRad = 100 * kDeg;  // open door leaves stand 100 deg from shut

// Yaws that turn a piece's front (local -y) towards a compass direction (x east, y north).
constexpr double kFacingSouth = 0.0;
constexpr double kFacingNorth = kPi;
constexpr double kFacingEast = kPi / 2;
constexpr double kFacingWest = -kPi / 2;

Eigen::Isometry3d place(double x, double y, double yaw) { return at(x, y, 0, yaw); }

void box(Scene& s, const Eigen::Isometry3d& T, V3 centre, V3 half, const Material& m) {
  s.statics.push_back(makeBox(half, T * at(centre.x, centre.y, centre.z), m));
}

// ---- materials (linear BGR) ---------------------------------------------------------------------

Material paint(float b, float g, float r) {
  return pattern(Texture::kNoise, {b, g, r}, {0.82f * b, 0.85f * g, 0.88f * r}, 0.35);
}
Material oak() {
  return pattern(Texture::kStripes, {0.30f, 0.48f, 0.66f}, {0.22f, 0.38f, 0.55f}, 0.06);
}
Material walnut() {
  return pattern(Texture::kStripes, {0.12f, 0.2f, 0.32f}, {0.18f, 0.28f, 0.42f}, 0.05);
}
Material whiteLacquer() {
  return pattern(Texture::kNoise, {0.86f, 0.87f, 0.86f}, {0.74f, 0.76f, 0.76f}, 0.2);
}
Material frameWhite() { return solid(0.9f, 0.9f, 0.88f); }
Material metal() { return solid(0.35f, 0.36f, 0.38f); }
Material dark() { return solid(0.1f, 0.1f, 0.11f); }
Material fabric(float b, float g, float r) {
  return pattern(Texture::kNoise, {b, g, r}, {0.7f * b, 0.7f * g, 0.7f * r}, 0.08);
}
Material cardboard() {
  return pattern(Texture::kNoise, {0.35f, 0.55f, 0.72f}, {0.28f, 0.45f, 0.6f}, 0.1);
}
Material concrete() {
  return pattern(Texture::kNoise, {0.62f, 0.63f, 0.62f}, {0.45f, 0.47f, 0.47f}, 0.12);
}

// ---- walls and doors --------------------------------------------------------------------------

/// A doorway in a wall, at_m from the wall's start along it.
struct Door {
  double at_m = 0.0;
  /// 0: an open doorway without a leaf; +1 / -1: a leaf standing open on the wall's left / right
  /// side (seen from the wall's start towards its end).
  int leaf = 0;
  /// The jamb the leaf hangs on: +1 towards the wall's end, -1 towards its start.
  int hinge = 1;
  /// The leaf is shut in the opening (the flat's front door; `leaf` must be non-zero), with its
  /// handles on both faces at the jamb opposite the hinge.
  bool closed = false;
};

/// Door frame (jambs and head lining the opening, architraves on both faces) and leaf of a
/// doorway centred at u along the wall frame W (x along the wall, y to its left, z up).
void addDoorway(Scene& s, const Eigen::Isometry3d& W, const Door& d) {
  const Material frame = frameWhite();
  const double u = d.at_m, depth = kWallHalf + 0.02;  // the lining stands 2 cm proud
  for (int side : {-1, 1}) {
    box(s, W, {u + side * (kOpeningHalf - kJamb / 2), 0, kOpeningHeight / 2},
        {kJamb / 2, depth, kOpeningHeight / 2}, frame);
  }
  box(s, W, {u, 0, kOpeningHeight - 0.025}, {kOpeningHalf, depth, 0.025}, frame);
  for (int face : {-1, 1}) {
    const double y = face * (kWallHalf + 0.01);
    for (int side : {-1, 1}) {
      box(s, W, {u + side * (kOpeningHalf + 0.035), y, (kOpeningHeight + 0.07) / 2},
          {0.035, 0.01, (kOpeningHeight + 0.07) / 2}, frame);
    }
    box(s, W, {u, y, kOpeningHeight + 0.035}, {kOpeningHalf + 0.07, 0.01, 0.035}, frame);
  }
  if (d.leaf == 0) return;
  const Material leaf = pattern(Texture::kStripes, {0.78f, 0.8f, 0.8f}, {0.7f, 0.72f, 0.72f}, 0.3);
  const double clear_half = kOpeningHalf - kJamb, height_half = (kOpeningHeight - 0.07) / 2;
  if (d.closed) {
    box(s, W, {u, 0, height_half + 0.01}, {clear_half, 0.025, height_half}, leaf);
    for (int face : {-1, 1}) {
      s.statics.push_back(
          makeSphere(0.03, W * at(u - d.hinge * (clear_half - 0.08), face * 0.06, 1.0), metal()));
    }
    return;
  }
  // Open: the leaf turns about the hinge (the jamb's inner edge on the leaf's side) away from
  // the opening, kLeafOpenRad from shut (shut, it would point from the hinge to -hinge).
  const double hinge_u = u + d.hinge * clear_half;
  const Eigen::Vector2d dir(-d.hinge * std::cos(kLeafOpenRad), d.leaf * std::sin(kLeafOpenRad));
  const double width = 2 * clear_half - 0.01;
  const Eigen::Vector2d c = Eigen::Vector2d(hinge_u, d.leaf * kWallHalf) + 0.5 * width * dir;
  const double yaw = std::atan2(dir.y(), dir.x());
  s.statics.push_back(
      makeBox({width / 2, 0.02, height_half}, W * at(c.x(), c.y(), height_half + 0.01, yaw), leaf));
  const Eigen::Vector2d knob = Eigen::Vector2d(hinge_u, d.leaf * kWallHalf) + 0.85 * width * dir;
  for (int face : {-1, 1}) {
    const Eigen::Vector2d k = knob + face * 0.055 * Eigen::Vector2d(-dir.y(), dir.x());
    s.statics.push_back(makeSphere(0.03, W * at(k.x(), k.y(), 1.0), metal()));
  }
}

/// A straight wall on the centre line (x0, y0) -> (x1, y1), floor to ceiling, kWallHalf thick
/// on either side and extended by kWallHalf at both ends to close the corners. Each side is its
/// own box so the rooms left and right of it (seen from start to end) have their own paint.
void addWall(Scene& s, double x0, double y0, double x1, double y1, std::vector<Door> doors,
             const Material& left, const Material& right) {
  const double length = std::hypot(x1 - x0, y1 - y0);
  const Eigen::Isometry3d W = at(x0, y0, 0, std::atan2(y1 - y0, x1 - x0));
  std::sort(doors.begin(), doors.end(),
            [](const Door& a, const Door& b) { return a.at_m < b.at_m; });
  auto span = [&](double u0, double u1, double z0, double z1) {
    for (int side : {-1, 1}) {
      box(s, W, {(u0 + u1) / 2, side * kWallHalf / 2, (z0 + z1) / 2},
          {(u1 - u0) / 2, kWallHalf / 2, (z1 - z0) / 2}, side > 0 ? left : right);
    }
  };
  double u = -kWallHalf;
  for (const Door& d : doors) {
    span(u, d.at_m - kOpeningHalf, 0, kWallHeight);
    span(d.at_m - kOpeningHalf, d.at_m + kOpeningHalf, kOpeningHeight, kWallHeight);  // lintel
    addDoorway(s, W, d);
    u = d.at_m + kOpeningHalf;
  }
  span(u, length + kWallHalf, 0, kWallHeight);
}

/// A window on a wall face: frame, mullion, glass and sill. F: origin on the wall face under
/// the window's centre, local -y into the room.
void addWindow(Scene& s, const Eigen::Isometry3d& F, double width, double height, double sill_z) {
  const Material glass = pattern(Texture::kNoise, {0.55f, 0.42f, 0.3f}, {0.75f, 0.62f, 0.5f}, 0.25);
  const Material frame = frameWhite();
  const double zc = sill_z + height / 2;
  box(s, F, {0, -0.004, zc}, {width / 2, 0.004, height / 2}, glass);
  for (int side : {-1, 1}) {
    box(s, F, {side * (width / 2 - 0.03), -0.03, zc}, {0.03, 0.03, height / 2}, frame);
    box(s, F, {0, -0.03, zc + side * (height / 2 - 0.03)}, {width / 2, 0.03, 0.03}, frame);
  }
  box(s, F, {0, -0.025, zc}, {0.025, 0.025, height / 2}, frame);
  box(s, F, {0, -0.09, sill_z - 0.02}, {width / 2 + 0.06, 0.09, 0.02}, frame);
}

/// A framed picture on a wall face (F as for addWindow) centred at height zc.
void addPicture(Scene& s, const Eigen::Isometry3d& F, double width, double height, double zc,
                const Material& m) {
  box(s, F, {0, -0.012, zc}, {width / 2, 0.012, height / 2}, walnut());
  box(s, F, {0, -0.026, zc}, {width / 2 - 0.04, 0.003, height / 2 - 0.04}, m);
}

// ---- furniture (origin on the floor under the footprint's centre, front towards local -y) -------

/// A cabinet w x d x h on a recessed plinth with rows x cols doors or drawers and their handles;
/// with a worktop, a 4 cm slab overhanging the front by 3 cm on top.
void addCabinet(Scene& s, const Eigen::Isometry3d& T, double w, double d, double h, int rows,
                int cols, const Material& body, const Material& front, bool worktop = false) {
  const double plinth = 0.08;
  box(s, T, {0, 0.04, plinth / 2}, {w / 2 - 0.02, d / 2 - 0.04, plinth / 2}, dark());
  box(s, T, {0, 0, (plinth + h) / 2}, {w / 2, d / 2, (h - plinth) / 2}, body);
  const double cw = w / cols, ch = (h - plinth) / rows;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double x = -w / 2 + (c + 0.5) * cw, z = plinth + (r + 0.5) * ch;
      box(s, T, {x, -d / 2 - 0.009, z}, {cw / 2 - 0.006, 0.009, ch / 2 - 0.006}, front);
      box(s, T, {x, -d / 2 - 0.03, z + ch / 2 - std::min(0.06, ch / 4)}, {0.06, 0.012, 0.01},
          metal());
    }
  }
  if (worktop) box(s, T, {0, -0.015, h + 0.02}, {w / 2, d / 2 + 0.015, 0.02}, walnut());
}

/// An open bookshelf w x d x h: sides, top, back and `shelves` boards, each board carrying blocks
/// of books (striped spines) of varying height and depth; `seed` varies the books.
void addBookshelf(Scene& s, const Eigen::Isometry3d& T, double w, double d, double h, int shelves,
                  uint64_t seed) {
  const Material wood = oak();
  const double t = 0.018;
  for (int side : {-1, 1})
    box(s, T, {side * (w / 2 - t / 2), 0, h / 2}, {t / 2, d / 2, h / 2}, wood);
  box(s, T, {0, d / 2 - 0.005, h / 2}, {w / 2, 0.005, h / 2}, wood);
  const double pitch = (h - 0.08) / shelves;
  const std::array<std::array<float, 3>, 5> colours = {{{0.2f, 0.2f, 0.7f},
                                                        {0.6f, 0.35f, 0.15f},
                                                        {0.2f, 0.55f, 0.3f},
                                                        {0.75f, 0.75f, 0.7f},
                                                        {0.1f, 0.45f, 0.75f}}};
  for (int k = 0; k <= shelves; ++k) {
    const double z = 0.06 + k * pitch;
    box(s, T, {0, 0, z}, {w / 2 - t, d / 2 - 0.01, t / 2}, wood);
    if (k == shelves) break;
    // Blocks of books from left to right with gaps; heights up to 85 % of the shelf pitch.
    double x = -w / 2 + t + 0.02;
    for (int b = 0; x < w / 2 - t - 0.12; ++b) {
      const uint64_t r = mix64(seed * 1000 + static_cast<uint64_t>(k * 50 + b));
      const double u0 = static_cast<double>(r & 0xffff) / 65535.0;
      const double u1 = static_cast<double>((r >> 16) & 0xffff) / 65535.0;
      const double u2 = static_cast<double>((r >> 32) & 0xffff) / 65535.0;
      const double bw = std::min(0.1 + 0.25 * u0, w / 2 - t - x);
      const double bh = (0.5 + 0.35 * u1) * pitch;
      const double bd = (0.6 + 0.3 * u2) * (d - 0.02);
      const auto& c0 = colours[(r >> 48) % colours.size()];
      const auto& c1 = colours[(r >> 52) % colours.size()];
      // Pushed against the back panel, so their spines stand back from the boards' front edge.
      box(s, T, {x + bw / 2, d / 2 - 0.01 - bd / 2, z + t / 2 + bh / 2}, {bw / 2, bd / 2, bh / 2},
          pattern(Texture::kStripes, c0, c1, 0.035 + 0.02 * u2));
      x += bw + 0.03 + 0.12 * u1;
    }
  }
}

/// A four-poster double bed 1.6 x 2.1 m (2.1 m high, curtains gathered at the posts),
/// headboard on local +y.
void addBed(Scene& s, const Eigen::Isometry3d& T) {
  const Material cover =
      pattern(Texture::kChecker, {0.55f, 0.35f, 0.3f}, {0.75f, 0.6f, 0.55f}, 0.2);
  box(s, T, {0, 0, 0.2}, {0.8, 1.03, 0.15}, walnut());
  s.statics.push_back(makeRoundedBox({0.78, 1.0, 0.12}, 0.05, T * at(0, 0, 0.46), whiteLacquer()));
  box(s, T, {0, -0.35, 0.59}, {0.8, 0.67, 0.02}, cover);
  for (int side : {-1, 1}) {
    s.statics.push_back(makeRoundedBox({0.32, 0.18, 0.07}, 0.05, T * at(side * 0.38, 0.72, 0.63),
                                       fabric(0.8f, 0.8f, 0.85f)));
  }
  box(s, T, {0, 1.03, 0.55}, {0.85, 0.03, 0.55}, walnut());
  const Material curtain = fabric(0.75f, 0.8f, 0.85f);
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      box(s, T, {sx * 0.82, sy * 1.03, 1.05}, {0.04, 0.04, 1.05}, walnut());
      box(s, T, {sx * 0.84, sy * 0.8, 1.35}, {0.02, 0.2, 0.7}, curtain);
    }
    box(s, T, {sx * 0.82, 0, 2.07}, {0.03, 1.03, 0.03}, walnut());
    box(s, T, {0, sx * 1.03, 2.07}, {0.82, 0.03, 0.03}, walnut());
  }
}

void addFridge(Scene& s, const Eigen::Isometry3d& T) {
  const Material shell = solid(0.82f, 0.83f, 0.84f);
  box(s, T, {0, 0, 0.95}, {0.33, 0.32, 0.95}, shell);
  box(s, T, {0, -0.335, 1.45}, {0.32, 0.015, 0.44}, shell);
  box(s, T, {0, -0.335, 0.5}, {0.32, 0.015, 0.48}, shell);
  for (double z : {1.25, 0.75}) {
    s.statics.push_back(makeCylinder(0.012, 0.18, T * at(0.26, -0.37, z), metal()));
  }
}

/// An armchair 0.9 x 0.85 m (rounded boxes), backrest on local +y.
void addArmchair(Scene& s, const Eigen::Isometry3d& T, const Material& m) {
  s.statics.push_back(makeRoundedBox({0.45, 0.42, 0.2}, 0.07, T * at(0, 0, 0.2), m));
  s.statics.push_back(makeRoundedBox({0.45, 0.1, 0.35}, 0.07, T * at(0, 0.32, 0.55), m));
  for (int side : {-1, 1}) {
    s.statics.push_back(makeRoundedBox({0.09, 0.42, 0.13}, 0.05, T * at(side * 0.36, 0, 0.5), m));
  }
}

/// A potted plant: pot, stem and two leaf balls (about 1.1 m high).
void addPlant(Scene& s, double x, double y) {
  const Material leaves = pattern(Texture::kNoise, {0.15f, 0.45f, 0.2f}, {0.1f, 0.3f, 0.12f}, 0.06);
  s.statics.push_back(
      makeCylinder(0.17, 0.18, at(x, y, 0.18),
                   pattern(Texture::kStripes, {0.2f, 0.35f, 0.65f}, {0.25f, 0.45f, 0.75f}, 0.04)));
  s.statics.push_back(makeCylinder(0.02, 0.25, at(x, y, 0.55), walnut()));
  s.statics.push_back(makeSphere(0.28, at(x, y, 0.85), leaves));
  s.statics.push_back(makeSphere(0.18, at(x + 0.12, y - 0.08, 1.1), leaves));
}

/// A bar stool: foot disc, pole and round seat (0.69 m).
void addStool(Scene& s, double x, double y) {
  s.statics.push_back(makeCylinder(0.16, 0.01, at(x, y, 0.01), metal()));
  s.statics.push_back(makeCylinder(0.025, 0.32, at(x, y, 0.34), metal()));
  s.statics.push_back(makeCylinder(0.17, 0.03, at(x, y, 0.66), fabric(0.2f, 0.25f, 0.6f)));
}

/// A square pillar, floor to ceiling.
void addPillar(Scene& s, double x, double y, double half) {
  box(s, at(x, y, 0), {0, 0, kWallHeight / 2}, {half, half, kWallHeight / 2}, concrete());
}

/// A stack of cardboard boxes: (x, y, size) of each in the frame T, stacked in list order.
void addBoxes(Scene& s, const Eigen::Isometry3d& T,
              const std::vector<std::pair<Eigen::Vector2d, V3>>& boxes) {
  std::vector<std::pair<Eigen::Vector2d, double>> tops;  // centre and top of each placed box
  for (const auto& [c, half] : boxes) {
    double z = 0;
    for (const auto& [tc, top] : tops) {
      if ((tc - c).norm() < 0.2) z = std::max(z, top);
    }
    box(s, T, {c.x(), c.y(), z + half.z}, half, cardboard());
    tops.push_back({c, z + 2 * half.z});
  }
}

/// A coat rack: foot, pole, four hooks and two coats hanging from it (1.8 m).
void addCoatRack(Scene& s, double x, double y) {
  s.statics.push_back(makeCylinder(0.2, 0.015, at(x, y, 0.015), dark()));
  s.statics.push_back(makeCylinder(0.02, 0.88, at(x, y, 0.9), walnut()));
  for (int k = 0; k < 4; ++k) {
    const double a = k * kPi / 2 + 0.4;
    s.statics.push_back(makeCapsule(
        0.012, 0.08, at(x + 0.07 * std::cos(a), y + 0.07 * std::sin(a), 1.72, a, kPi / 3, 0),
        walnut()));
  }
  s.statics.push_back(
      makeCapsule(0.13, 0.35, at(x + 0.12, y + 0.02, 1.2), fabric(0.25f, 0.2f, 0.55f)));
  s.statics.push_back(
      makeCapsule(0.11, 0.3, at(x - 0.05, y - 0.12, 1.25), fabric(0.45f, 0.4f, 0.2f)));
}

/// A desk w x d (0.75 m) with a drawer unit on the right, a monitor, a keyboard and a vase.
void addDesk(Scene& s, const Eigen::Isometry3d& T, double w, double d) {
  const Material top = oak();
  box(s, T, {0, 0, 0.735}, {w / 2, d / 2, 0.015}, top);
  box(s, T, {-w / 2 + 0.02, 0, 0.36}, {0.02, d / 2 - 0.02, 0.36}, top);
  addCabinet(s, T * at(w / 2 - 0.22, 0.02, 0), 0.42, d - 0.06, 0.72, 3, 1, whiteLacquer(), oak());
  box(s, T, {0, d / 2 - 0.15, 0.76}, {0.08, 0.06, 0.01}, dark());
  box(s, T, {0, d / 2 - 0.15, 0.84}, {0.02, 0.02, 0.08}, dark());
  box(s, T, {0, d / 2 - 0.17, 1.05}, {0.3, 0.015, 0.19},
      pattern(Texture::kChecker, {0.5f, 0.3f, 0.15f}, {0.2f, 0.15f, 0.1f}, 0.08));
  box(s, T, {0, -d / 2 + 0.15, 0.76}, {0.22, 0.07, 0.01}, solid(0.3f, 0.3f, 0.3f));
  s.statics.push_back(makeCylinder(0.06, 0.12, T * at(-w / 2 + 0.15, d / 2 - 0.12, 0.87),
                                   solid(0.2f, 0.6f, 0.85f)));
}

/// A TV (1.2 m wide) on a stand, standing at height z in the frame T.
void addTv(Scene& s, const Eigen::Isometry3d& T, double z) {
  box(s, T, {0, 0.05, z + 0.01}, {0.18, 0.09, 0.01}, dark());
  box(s, T, {0, 0.05, z + 0.07}, {0.03, 0.02, 0.06}, dark());
  box(s, T, {0, 0.02, z + 0.45}, {0.6, 0.025, 0.34}, dark());
  box(s, T, {0, -0.006, z + 0.45}, {0.57, 0.003, 0.31},
      pattern(Texture::kNoise, {0.45f, 0.3f, 0.2f}, {0.15f, 0.1f, 0.05f}, 0.15));
}

/// A radiator on a wall face (F as for addWindow), fins as stripes, with two pipes.
void addRadiator(Scene& s, const Eigen::Isometry3d& F, double width) {
  const Material fins = pattern(Texture::kStripes, {0.9f, 0.9f, 0.9f}, {0.6f, 0.6f, 0.6f}, 0.05);
  box(s, F, {0, -0.08, 0.45}, {width / 2, 0.045, 0.3}, fins);
  for (int side : {-1, 1}) {
    s.statics.push_back(
        makeCylinder(0.015, 0.08, F * at(side * (width / 2 - 0.05), -0.08, 0.08), metal()));
  }
}

/// A rack hung from the ceiling over a kitchen island at (x, y): rods, a shelf at 1.8 m with
/// jars and a plant on it, and three pans hanging below it down to 1.26 m.
void addHangingRack(Scene& s, double x, double y) {
  for (int side : {-1, 1}) {
    s.statics.push_back(makeCylinder(0.012, 0.35, at(x + side * 0.55, y, 2.15), metal()));
  }
  box(s, at(x, y, 0), {0, 0, 1.8}, {0.62, 0.16, 0.015}, walnut());
  for (int k = 0; k < 4; ++k) {
    s.statics.push_back(
        makeCylinder(0.05, 0.07 + 0.015 * k, at(x - 0.45 + 0.16 * k, y, 1.885 + 0.015 * k),
                     pattern(Texture::kStripes, {0.2f, 0.6f, 0.8f}, {0.8f, 0.8f, 0.8f}, 0.03)));
  }
  s.statics.push_back(
      makeSphere(0.13, at(x + 0.35, y, 1.95),
                 pattern(Texture::kNoise, {0.15f, 0.45f, 0.2f}, {0.1f, 0.3f, 0.12f}, 0.05)));
  for (int k = 0; k < 3; ++k) {
    const double px = x - 0.35 + 0.35 * k, r = 0.1 + 0.03 * k;
    s.statics.push_back(makeCylinder(0.006, 0.1, at(px, y, 1.685), metal()));
    s.statics.push_back(makeCylinder(r, 0.005, at(px, y, 1.58 - r, 0, kPi / 2, 0), dark()));
  }
}

/// A rug: a 1 cm slab on the floor.
void addRug(Scene& s, double x, double y, double hx, double hy, const Material& m) {
  box(s, at(x, y, 0), {0, 0, 0.005}, {hx, hy, 0.005}, m);
}

// ---- the flat ---------------------------------------------------------------------------------

void buildShell(Scene& s) {
  s.statics.push_back(makePlane(
      at(0, 0, 0), pattern(Texture::kTiles, {0.24f, 0.42f, 0.58f}, {0.4f, 0.58f, 0.74f}, 0.45)));
  // Ceiling: the plane turned upside down (solid above z = kWallHeight).
  s.statics.push_back(
      makePlane(at(0, 0, kWallHeight, 0, 0, kPi),
                pattern(Texture::kNoise, {0.9f, 0.9f, 0.9f}, {0.75f, 0.76f, 0.78f}, 0.6)));
  // Kitchen and hallway floors: tiles over the wooden floor.
  const Material tiles =
      pattern(Texture::kChecker, {0.75f, 0.75f, 0.72f}, {0.45f, 0.48f, 0.5f}, 0.3);
  box(s, at(9.5, 2.3, 0), {0, 0, 0.003}, {2.45, 2.25, 0.003}, tiles);
  box(s, at(0.9, 4.5, 0), {0, 0, 0.003}, {0.85, 4.45, 0.003},
      pattern(Texture::kChecker, {0.35f, 0.4f, 0.5f}, {0.6f, 0.65f, 0.7f}, 0.25));

  const Material hall = paint(0.72f, 0.82f, 0.88f), living = paint(0.74f, 0.86f, 0.78f),
                 kitchen = paint(0.88f, 0.86f, 0.8f), study = paint(0.86f, 0.78f, 0.74f),
                 bedroom = paint(0.8f, 0.76f, 0.86f), outside = paint(0.6f, 0.6f, 0.6f);
  // Outer walls, counter-clockwise (the flat on their left). The front door is shut.
  Door front;
  front.at_m = 0.9;
  front.leaf = 1;
  front.hinge = -1;
  front.closed = true;
  addWall(s, 0, 0, 1.8, 0, {front}, hall, outside);
  addWall(s, 1.8, 0, 7.0, 0, {}, living, outside);
  addWall(s, 7.0, 0, 12, 0, {}, kitchen, outside);
  addWall(s, 12, 0, 12, 4.6, {}, kitchen, outside);
  addWall(s, 12, 4.6, 12, 9, {}, study, outside);
  addWall(s, 12, 9, 7.0, 9, {}, study, outside);
  addWall(s, 7.0, 9, 1.8, 9, {}, bedroom, outside);
  addWall(s, 1.8, 9, 0, 9, {}, hall, outside);
  addWall(s, 0, 9, 0, 0, {}, hall, outside);
  // Hallway | living room and bedroom (south to north: hallway on the left). Both leaves stand
  // open into the rooms, against the jamb the walk does not turn towards.
  addWall(s, 1.8, 0, 1.8, 4.6, {{1.6, -1, -1, false}}, hall, living);
  addWall(s, 1.8, 4.6, 1.8, 9, {{7.3 - 4.6, -1, 1, false}}, hall, bedroom);
  // Living room and kitchen | bedroom and study (west to east: the north rooms on the left).
  addWall(s, 1.8, 4.6, 7.0, 4.6, {}, bedroom, living);
  addWall(s, 7.0, 4.6, 12, 4.6, {{8.3 - 7.0, 1, -1, false}}, study, kitchen);
  // Living room | kitchen (an open doorway) and bedroom | study (south to north: west rooms on
  // the left).
  addWall(s, 7.0, 0, 7.0, 4.6, {{2.3, 0, 1, false}}, living, kitchen);
  addWall(s, 7.0, 4.6, 7.0, 9, {{7.3 - 4.6, 1, 1, false}}, bedroom, study);
}

void furnishHallway(Scene& s) {
  // West wall: a shoe cabinet by the front door, a coat rack, a console with a mirror and a
  // bowl; north end: a tall wardrobe; east wall: a radiator, a column where the hallway meets
  // the middle wall, a wall shelf with boxes and pictures.
  addCabinet(s, place(0.25, 0.85, kFacingEast), 1.1, 0.4, 1.0, 2, 2, whiteLacquer(), oak(), true);
  addCoatRack(s, 0.3, 2.3);
  addCabinet(s, place(0.25, 4.4, kFacingEast), 1.3, 0.4, 0.85, 2, 3, walnut(), oak(), true);
  s.statics.push_back(makeCylinder(0.12, 0.05, at(0.25, 4.0, 0.93), solid(0.6f, 0.3f, 0.2f)));
  s.statics.push_back(makeCylinder(0.05, 0.15, at(0.25, 4.85, 1.03), solid(0.2f, 0.5f, 0.8f)));
  addPicture(s, place(0.05, 4.4, kFacingEast), 0.9, 0.7, 1.5,
             pattern(Texture::kNoise, {0.7f, 0.6f, 0.5f}, {0.4f, 0.3f, 0.25f}, 0.1));
  addCabinet(s, place(0.9, 8.7, kFacingSouth), 1.4, 0.5, 2.2, 1, 3, whiteLacquer(), walnut());
  addRadiator(s, place(1.75, 3.1, kFacingWest), 0.9);
  addPillar(s, 1.65, 4.6, 0.15);
  box(s, place(1.75, 5.8, kFacingWest), {0, -0.12, 1.1}, {0.5, 0.12, 0.015}, walnut());
  addBoxes(s, place(1.75, 5.8, kFacingWest) * at(0, 0, 1.115),
           {{{-0.3, -0.12}, {0.12, 0.1, 0.1}},
            {{0.05, -0.13}, {0.15, 0.1, 0.08}},
            {{0.32, -0.11}, {0.1, 0.09, 0.14}}});
  addPicture(s, place(1.75, 3.1, kFacingWest), 0.6, 0.4, 1.45,
             pattern(Texture::kChecker, {0.2f, 0.3f, 0.8f}, {0.8f, 0.7f, 0.3f}, 0.1));
  addPicture(s, place(1.75, 6.5, kFacingWest), 0.4, 0.5, 1.55,
             pattern(Texture::kStripes, {0.2f, 0.6f, 0.3f}, {0.7f, 0.8f, 0.9f}, 0.08));
}

void furnishLiving(Scene& s) {
  // Sofa against the south wall facing north, a coffee table with things on it on a rug, a TV
  // on a low cabinet against the north wall, a bookshelf on the west wall, an open shelf
  // standing free by the sofa's east end (it closes the view from the hallway door, which
  // would otherwise reach 5 m to the east wall), an armchair in the north-east corner, a floor
  // lamp, a side table, a plant and a window.
  addSofa(s, 4.5, 0.5, kFacingNorth);
  addRug(s, 4.5, 1.6, 1.4, 0.9,
         pattern(Texture::kStripes, {0.3f, 0.25f, 0.6f}, {0.6f, 0.55f, 0.8f}, 0.25));
  addTable(s, 4.5, 1.55, 0, 0.5, 0.28);
  addTableItems(s, 4.5, 1.55);
  addCabinet(s, place(4.5, 4.32, kFacingSouth), 1.8, 0.45, 0.5, 1, 3, walnut(), oak(), true);
  addTv(s, place(4.5, 4.32, kFacingSouth), 0.54);
  addBookshelf(s, place(2.03, 3.6, kFacingEast), 1.3, 0.35, 2.0, 5, 1);
  addArmchair(s, place(6.3, 3.75, -kPi / 4), fabric(0.3f, 0.55f, 0.75f));
  addBookshelf(s, place(5.6, 1.45, kFacingWest), 1.2, 0.35, 1.9, 5, 6);
  addLamp(s, 6.55, 0.45);
  addCabinet(s, place(5.75, 0.35, kFacingNorth), 0.45, 0.45, 0.55, 2, 1, oak(), walnut(), true);
  addPlant(s, 2.35, 0.45);
  addWindow(s, place(3.0, 0.05, kFacingNorth), 1.2, 1.3, 0.9);
  addPicture(s, place(6.95, 3.85, kFacingWest), 0.6, 0.5, 1.55,
             pattern(Texture::kChecker, {0.15f, 0.3f, 0.85f}, {0.8f, 0.65f, 0.2f}, 0.1));
  addPicture(s, place(3.6, 4.55, kFacingSouth), 0.6, 0.45, 1.6,
             pattern(Texture::kNoise, {0.2f, 0.5f, 0.7f}, {0.6f, 0.8f, 0.9f}, 0.08));
}

void furnishKitchen(Scene& s) {
  // Counters with wall cabinets along the south and east walls, a fridge in the north-east
  // corner, a pantry by the study door, an island with a shelf tower on its east end, two stools
  // and a rack hanging over it, things on the worktops. The island, tower and rack stand in the
  // view from the living-room door, which would otherwise reach 5 m to the east wall.
  const Material fronts =
      pattern(Texture::kNoise, {0.3f, 0.55f, 0.45f}, {0.25f, 0.45f, 0.35f}, 0.2);
  addCabinet(s, place(9.925, 0.35, kFacingNorth), 4.05, 0.6, 0.9, 1, 6, whiteLacquer(), fronts,
             true);
  addCabinet(s, place(9.925, 0.225, kFacingNorth) * at(0, 0, 1.45), 4.05, 0.35, 0.7, 1, 6,
             whiteLacquer(), fronts);
  addCabinet(s, place(11.65, 1.75, kFacingWest), 2.2, 0.6, 0.9, 2, 3, whiteLacquer(), fronts, true);
  addCabinet(s, place(11.775, 1.75, kFacingWest) * at(0, 0, 1.45), 2.2, 0.35, 0.7, 1, 3,
             whiteLacquer(), fronts);
  addFridge(s, place(11.62, 4.15, kFacingWest));
  addCabinet(s, place(7.3, 4.05, kFacingEast), 0.9, 0.5, 2.1, 2, 1, whiteLacquer(), fronts);
  addCabinet(s, place(9.5, 2.3, kFacingSouth), 1.4, 0.8, 0.9, 2, 3, oak(), fronts, true);
  addBookshelf(s, place(10.05, 2.3, kFacingWest) * at(0, 0, 0.94), 0.8, 0.28, 1.2, 3, 5);
  addStool(s, 9.1, 2.92);
  addStool(s, 9.9, 2.92);
  addHangingRack(s, 9.5, 2.3);
  // On the worktops (0.94 m): a kettle, jars, a microwave, a bowl with fruit, a tap.
  s.statics.push_back(makeCylinder(0.09, 0.12, at(8.4, 0.35, 1.06), metal()));
  for (int k = 0; k < 3; ++k) {
    s.statics.push_back(
        makeCylinder(0.05, 0.08 + 0.02 * k, at(8.8 + 0.13 * k, 0.25, 1.02 + 0.02 * k),
                     pattern(Texture::kStripes, {0.8f, 0.8f, 0.8f}, {0.3f, 0.5f, 0.8f}, 0.03)));
  }
  box(s, place(10.9, 0.33, 0), {0, 0, 1.1}, {0.25, 0.18, 0.16}, dark());
  s.statics.push_back(makeCylinder(0.015, 0.12, at(9.8, 0.15, 1.06), metal()));
  s.statics.push_back(makeCapsule(0.012, 0.1, at(9.8, 0.24, 1.18, 0, 0, -kPi / 2), metal()));
  s.statics.push_back(makeSphere(0.15, at(9.2, 2.2, 0.96), solid(0.2f, 0.5f, 0.8f)));
  s.statics.push_back(makeSphere(0.05, at(9.25, 2.25, 1.1), solid(0.1f, 0.3f, 0.9f)));
  s.statics.push_back(makeCylinder(0.1, 0.015, at(11.6, 2.4, 0.955), solid(0.75f, 0.75f, 0.7f)));
}

void furnishStudy(Scene& s) {
  // A desk with a chair against the east wall, two bookshelves along the north wall, a filing
  // cabinet by the door, in the middle (the walk goes round them) a concrete pillar, an open
  // shelf and a reading lamp, which stand in the view from the kitchen door; a plant, boxes in
  // the south-east corner, a window.
  addDesk(s, place(11.6, 7.1, kFacingWest), 1.6, 0.7);
  addChair(s, 11.45, 7.0, kFacingWest + kPi);
  addBookshelf(s, place(8.7, 8.775, kFacingSouth), 1.4, 0.35, 2.0, 5, 2);
  addBookshelf(s, place(10.3, 8.775, kFacingSouth), 1.4, 0.35, 1.8, 4, 3);
  addCabinet(s, place(9.7, 4.9, kFacingNorth), 0.8, 0.5, 1.3, 3, 2, metal(),
             solid(0.5f, 0.5f, 0.52f));
  addPillar(s, 9.5, 7.05, 0.2);
  addBookshelf(s, place(8.85, 7.05, kFacingSouth), 0.9, 0.35, 1.6, 4, 4);
  addLamp(s, 8.5, 6.5);
  addPlant(s, 7.45, 6.3);
  addBoxes(s, place(11.45, 5.2, 0),
           {{{0, 0}, {0.25, 0.22, 0.2}},
            {{0.05, 0.02}, {0.2, 0.18, 0.15}},
            {{-0.1, 0.0}, {0.12, 0.1, 0.1}}});
  addWindow(s, place(11.95, 5.6, kFacingWest), 0.9, 1.2, 0.95);
  addPicture(s, place(7.05, 5.8, kFacingEast), 0.7, 0.5, 1.6,
             pattern(Texture::kStripes, {0.7f, 0.3f, 0.2f}, {0.9f, 0.8f, 0.6f}, 0.1));
}

void furnishBedroom(Scene& s) {
  // A four-poster bed against the north wall between two night stands (its posts, rails and
  // curtains stand in the view from the study door), a wardrobe on the south wall, a dresser
  // with a mirror on the east wall, a desk by the hallway wall, a rug, a laundry basket.
  addBed(s, place(4.4, 7.9, kFacingSouth));
  for (double x : {3.32, 5.48}) {
    addCabinet(s, place(x, 8.72, kFacingSouth), 0.45, 0.45, 0.55, 2, 1, walnut(), oak(), true);
  }
  s.statics.push_back(makeCylinder(0.1, 0.01, at(3.32, 8.72, 0.6), metal()));
  s.statics.push_back(makeSphere(0.12, at(3.32, 8.72, 0.78), solid(0.6f, 0.85f, 0.95f)));
  addCabinet(s, place(4.2, 4.95, kFacingNorth), 2.0, 0.6, 2.2, 1, 4, whiteLacquer(), oak());
  addCabinet(s, place(6.72, 5.75, kFacingWest), 1.1, 0.45, 0.9, 3, 2, oak(), whiteLacquer(), true);
  box(s, place(6.95, 5.75, kFacingWest), {0, -0.01, 1.55}, {0.35, 0.01, 0.45},
      pattern(Texture::kNoise, {0.7f, 0.65f, 0.6f}, {0.5f, 0.45f, 0.4f}, 0.12));
  addDesk(s, place(2.2, 5.5, kFacingEast), 1.2, 0.6);
  addRug(s, 4.4, 6.2, 1.2, 0.6,
         pattern(Texture::kChecker, {0.3f, 0.5f, 0.6f}, {0.5f, 0.7f, 0.8f}, 0.2));
  s.statics.push_back(
      makeCylinder(0.2, 0.25, at(6.3, 8.55, 0.25),
                   pattern(Texture::kChecker, {0.5f, 0.7f, 0.75f}, {0.3f, 0.45f, 0.5f}, 0.05)));
  addWindow(s, place(6.1, 8.95, kFacingSouth), 0.9, 1.2, 0.95);
  addPicture(s, place(2.8, 8.95, kFacingSouth), 0.6, 0.8, 1.5,
             pattern(Texture::kNoise, {0.3f, 0.4f, 0.8f}, {0.7f, 0.8f, 0.9f}, 0.1));
}

// ---- the walk ---------------------------------------------------------------------------------

/// A closed centripetal Catmull-Rom spline through waypoints in the floor plane, evaluated by
/// arc length (metres from the first waypoint; wraps around the loop).
class LoopPath {
 public:
  explicit LoopPath(std::vector<Eigen::Vector2d> waypoints) : p_(std::move(waypoints)) {
    const size_t n = p_.size();
    cumulative_.reserve(n * kSamples + 1);
    cumulative_.push_back(0.0);
    Eigen::Vector2d last = p_[0];
    for (size_t i = 0; i < n; ++i) {
      for (int k = 1; k <= kSamples; ++k) {
        const Eigen::Vector2d q = segment(i, static_cast<double>(k) / kSamples);
        cumulative_.push_back(cumulative_.back() + (q - last).norm());
        last = q;
      }
    }
  }

  double length() const { return cumulative_.back(); }

  Eigen::Vector2d at(double s) const {
    s = std::fmod(s, length());
    if (s < 0) s += length();
    const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
    const size_t k = static_cast<size_t>(it - cumulative_.begin()) - 1;
    const double span = cumulative_[k + 1] - cumulative_[k];
    const double u =
        (static_cast<double>(k) + (span > 0 ? (s - cumulative_[k]) / span : 0.0)) / kSamples;
    const size_t i = std::min(static_cast<size_t>(u), p_.size() - 1);
    return segment(i, u - static_cast<double>(i));
  }

 private:
  static constexpr int kSamples = 200;  // arc-length samples per segment

  /// Point at u in [0, 1] of the segment from waypoint i to i + 1 (Barry-Goldman pyramid,
  /// knots spaced by the square root of the chord lengths: no cusps or loops).
  Eigen::Vector2d segment(size_t i, double u) const {
    const size_t n = p_.size();
    const Eigen::Vector2d &p0 = p_[(i + n - 1) % n], &p1 = p_[i], &p2 = p_[(i + 1) % n],
                          &p3 = p_[(i + 2) % n];
    const double t0 = 0, t1 = t0 + std::sqrt((p1 - p0).norm()),
                 t2 = t1 + std::sqrt((p2 - p1).norm()), t3 = t2 + std::sqrt((p3 - p2).norm());
    const double t = t1 + u * (t2 - t1);
    const Eigen::Vector2d a1 = ((t1 - t) * p0 + (t - t0) * p1) / (t1 - t0);
    const Eigen::Vector2d a2 = ((t2 - t) * p1 + (t - t1) * p2) / (t2 - t1);
    const Eigen::Vector2d a3 = ((t3 - t) * p2 + (t - t2) * p3) / (t3 - t2);
    const Eigen::Vector2d b1 = ((t2 - t) * a1 + (t - t0) * a2) / (t2 - t0);
    const Eigen::Vector2d b2 = ((t3 - t) * a2 + (t - t1) * a3) / (t3 - t1);
    return ((t2 - t) * b1 + (t - t1) * b2) / (t2 - t1);
  }

  std::vector<Eigen::Vector2d> p_;
  std::vector<double> cumulative_;  // arc length at u = k / kSamples along the whole loop
};

// The walk's pace: straight on at kWalkSpeed, slower wherever the view would turn faster than
// kTurnRate (it stays under 30 deg/s with the tremor on top), accelerating at most kAccel, from
// rest at the start to rest at the end.
constexpr double kWalkSpeed = 0.36;      // m/s
constexpr double kTurnRate = 22 * kDeg;  // rad/s
constexpr double kAccel = 0.25;          // m/s^2
constexpr double kSmoothing = 0.4;       // m: half-window of the speed profile's filters
constexpr double kEyeHeight = 1.5;       // m, +-kEyeSwing over the loop
constexpr double kEyeSwing = 0.04;
constexpr double kLookAhead = 1.5;  // m along the path: the point the camera looks at ...
constexpr double kLookDrop = 0.45;  // ... lowered by this much (about 17 deg down)

/// The camera's walk: waypoints of the loop, counter-clockwise from the middle of the living
/// room; doorways are passed through their centre, square to the wall (a waypoint on each side).
std::vector<Eigen::Vector2d> loopWaypoints() {
  return {
      {4.6, 3.15},  {5.4, 3.05},  {6.3, 2.35},  {7.0, 2.3},    // living room -> kitchen
      {7.6, 2.25},  {8.35, 1.5},  {10.2, 1.3},  {10.8, 1.85},  // south of the island
      {10.8, 2.9},  {10.2, 3.5},  {9.3, 3.6},   {8.45, 3.95},  // round it, north side
      {8.3, 4.6},   {8.35, 5.25}, {9.3, 5.95},  {10.4, 6.2},   // -> study, round the pillar
      {10.7, 7.1},  {10.3, 7.95}, {9.0, 8.0},   {7.9, 7.45},   //
      {7.0, 7.3},   {6.35, 7.25}, {5.6, 6.45},  {4.4, 6.1},    // -> bedroom, past the bed
      {3.2, 6.35},  {2.5, 7.1},   {1.8, 7.3},   {1.25, 7.2},   // -> hallway
      {0.95, 6.55}, {0.9, 4.5},   {0.95, 2.35}, {1.25, 1.7},   // southwards
      {1.8, 1.6},   {2.45, 1.7},  {3.05, 2.5},  {3.8, 3.05},   // -> living room
  };
}

/// Sums amplitude * sin(2 pi f t + phase) of the terms, each faded in and out by its envelope.
Eigen::Vector3d sumSines(const std::vector<Sinusoid>& terms, double t) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (const auto& term : terms) {
    v += term.envelope(t) * term.amplitude *
         std::sin(2 * kPi * term.frequency_hz * t + term.phase_rad);
  }
  return v;
}

/// Samples the walk into the rig's keys (one per frame) and sets the scene's frame count.
void walkTheLoop(Scene& s) {
  const LoopPath path(loopWaypoints());
  const double S = path.length();
  auto centre = [&](double d) -> Eigen::Vector3d {
    const Eigen::Vector2d p = path.at(d);
    return Eigen::Vector3d(p.x(), p.y(), kEyeHeight + kEyeSwing * std::sin(2 * kPi * 4 * d / S));
  };
  auto target = [&](double d) -> Eigen::Vector3d {
    return centre(d + kLookAhead) - Eigen::Vector3d(0, 0, kLookDrop);
  };

  // Speed limit per centimetre of path from the view's turn rate per metre (yaw and pitch of the
  // viewing direction; the look-at rig has no roll).
  const int n = static_cast<int>(std::ceil(S / 0.01));
  const double ds = S / n;
  std::vector<double> yaw(n + 1), pitch(n + 1), v(n + 1);
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector3d f = (target(i * ds) - centre(i * ds)).normalized();
    yaw[i] = std::atan2(f.y(), f.x());
    pitch[i] = std::asin(f.z());
  }
  for (int i = 0; i <= n; ++i) {
    const int a = i == 0 ? n - 1 : i - 1, b = i == n ? 1 : i + 1;  // the loop is closed
    const double dyaw = std::remainder(yaw[b] - yaw[a], 2 * kPi);
    const double rate = std::hypot(dyaw, pitch[b] - pitch[a]) / (2 * ds);  // rad/m
    v[i] = std::min(kWalkSpeed, kTurnRate / std::max(rate, 1e-9));
  }
  // Smooth without exceeding the limit: a moving minimum, the acceleration limit (rest at both
  // ends), then a moving average of that (never above the minimum over its window).
  const int w = static_cast<int>(std::lround(kSmoothing / ds));
  std::vector<double> lo(n + 1);
  for (int i = 0; i <= n; ++i) {
    lo[i] = *std::min_element(v.begin() + std::max(0, i - w), v.begin() + std::min(n, i + w) + 1);
  }
  lo[0] = lo[n] = 0.0;
  for (int i = 1; i <= n; ++i)
    lo[i] = std::min(lo[i], std::sqrt(lo[i - 1] * lo[i - 1] + 2 * kAccel * ds));
  for (int i = n - 1; i >= 0; --i)
    lo[i] = std::min(lo[i], std::sqrt(lo[i + 1] * lo[i + 1] + 2 * kAccel * ds));
  std::vector<double> sum(n + 2, 0.0);
  for (int i = 0; i <= n; ++i) sum[i + 1] = sum[i] + lo[i];
  for (int i = 0; i <= n; ++i) {
    const int a = std::max(0, i - w), b = std::min(n, i + w);
    v[i] = std::min({(sum[b + 1] - sum[a]) / (b - a + 1), std::sqrt(2 * kAccel * i * ds),
                     std::sqrt(2 * kAccel * (n - i) * ds)});
  }
  // Time at each grid point (trapezoidal in speed), then the arc length at each frame.
  std::vector<double> t(n + 1, 0.0);
  for (int i = 0; i < n; ++i) t[i + 1] = t[i] + 2 * ds / std::max(v[i] + v[i + 1], 1e-9);
  const double T = t[n];
  const int last = static_cast<int>(std::ceil(T * s.fps));

  // Hand-held wobble and tremor, faded in over the first and out over the last 2 s so the last
  // pose is the first.
  std::vector<Sinusoid> wobble = {sine(0.004, 0.003, 0.004, 1.7, 0.3),
                                  sine(0.001, 0.0015, 0.001, 2.9, 1.1)};
  s.camera.tremor_rad = {sine(0.004, 0.005, 0.003, 1.3, 0.2), sine(0.002, 0.002, 0.002, 2.3, 1.7)};
  for (auto* terms : {&wobble, &s.camera.tremor_rad}) {
    for (auto& term : *terms) {
      term.on_s = 0.0;
      term.off_s = T;
      term.ramp_s = 2.0;
    }
  }
  s.camera.path.keys.clear();
  s.camera.target.keys.clear();
  for (int k = 0; k <= last; ++k) {
    const double tk = s.timeOf(k);
    double d = S;
    if (tk < T) {
      const int i = static_cast<int>(std::upper_bound(t.begin(), t.end(), tk) - t.begin()) - 1;
      d = (i + (tk - t[i]) / (t[i + 1] - t[i])) * ds;
    }
    PoseKey c, g;
    c.t_s = g.t_s = tk;
    c.position_m = centre(d) + sumSines(wobble, tk);
    g.position_m = target(d);
    s.camera.path.keys.push_back(c);
    s.camera.target.keys.push_back(g);
  }
  s.default_frames = last + 1;
}

}  // namespace

Scene apartment() {
  Scene s;
  s.name = "apartment";
  s.description =
      "A static flat (12 x 9 m, 2.5 m ceilings): a hallway along its west side, a living room, a "
      "kitchen, a study and a bedroom, walls with doorways (0.96 m clear, door frames, open door "
      "leaves), furniture in every room and along the hallway. Nothing moves but the camera, "
      "which is carried at eye height (1.45-1.55 m) on one closed loop through all rooms and "
      "doorways (about 36.5 m: living room, kitchen round the island, study round a pillar, "
      "bedroom, hallway, back to the start), looking ahead and slightly down, walking at up to "
      "0.36 m/s and slowing in turns. It starts and ends at rest at the same pose.";
  buildShell(s);
  furnishHallway(s);
  furnishLiving(s);
  furnishKitchen(s);
  furnishStudy(s);
  furnishBedroom(s);
  walkTheLoop(s);
  return s;
}

}  // namespace emf::synth
