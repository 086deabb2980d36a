// The furniture of the generated scenes: pillars and pieces along the walls.
#include "synth/random_furniture.h"

#include <algorithm>
#include <array>

#include "synth/shapes.h"

namespace emf::synth::random_gen {

void addPillars(Scene& s, Rng& rng, Layout* L, const Occupant& stage) {
  // One draw per statement (rng.h): this order is the one every seed's scene was made with.
  const double grain_m = rng.uniform(0.2, 0.5);
  const std::array<float, 3> second = randomColour(rng, 0.45, 0.7);
  const std::array<float, 3> first = randomColour(rng, 0.55, 0.85);
  const Material plaster = pattern(Texture::kNoise, first, second, grain_m);
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
    const double hx = rng.uniform(0.15, 0.35);
    add(orbit ? rng.uniform(-L->room_hx + 0.5, L->room_hx - 0.5) : x, L->room_y_hi - depth, hx,
        depth);
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
    const double hx = rng.uniform(0.15, 0.35);
    const double x = rng.uniform(-L->room_hx + 0.5, L->room_hx - 0.5);
    add(x, L->room_y_lo + depth, hx, depth);
  }
}

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
        case 0: {
          const double half_y = rng.uniform(0.3, 0.45);
          const double half_x = rng.uniform(0.4, 0.7);
          addTable(piece, x, y, yaw, half_x, half_y);
        }
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
          const Material material = randomMaterial(rng);
          piece.statics.push_back(makeBox({rng.uniform(0.25, 0.5), rng.uniform(0.2, 0.35), half_z},
                                          at(x, y, half_z, yaw), material));
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

}  // namespace emf::synth::random_gen
