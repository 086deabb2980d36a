#include "synth/random_scene.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "common/error.h"
#include "synth/motion_plan.h"
#include "synth/random_camera.h"
#include "synth/random_furniture.h"
#include "synth/random_layout.h"
#include "synth/random_movers.h"
#include "synth/rng.h"
#include "synth/scene_check.h"
#include "synth/shapes.h"

namespace emf::synth {

using namespace random_gen;

namespace {

constexpr uint64_t kSceneStream = 0x72616e646f6dull;  // "random"
constexpr double kKeyHz = 60.0;                       // trajectory keys per second
constexpr int kMaxAttempts = 40;
// The static scene in view must pin the camera down (normalSpread) on every frame checked
// (kMinNormalSpread) and on 90 % of them with some margin (kLowNormalSpread). The presets'
// smallest and 10th percentile: cars 0.007 / 0.013, occlusion 0.012 / 0.018, enter 0.003 /
// 0.004, room 0.023 / 0.044.
constexpr double kMinNormalSpread = 0.004;
constexpr double kLowNormalSpread = 0.01;

// ---- the generator ------------------------------------------------------------------------------

struct Attempt {
  RandomScene result;
  double score = -1.0;  // the smallest visibility margin over the objects (>= 0: accepted)
};

constexpr int kMinPlanFrames = 300;

Attempt generate(uint64_t seed, int attempt, const RandomSceneOptions& options, unsigned families) {
  Rng rng(streamSeed(seed, kSceneStream, static_cast<uint64_t>(attempt)));
  Layout L;
  // Motions are planned over at least kMinPlanFrames: a shorter sequence shows their start
  // (a drive needs time for its ramps and stops after the rests before it).
  L.T = std::max(options.frames, kMinPlanFrames) / kFps;
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
  // One draw per statement (rng.h), in the order every seed's room was made with.
  const double wall_grain_m = rng.uniform(0.2, 0.5);
  const std::array<float, 3> wall_b = randomColour(rng, 0.45, 0.75);
  const std::array<float, 3> wall_a = randomColour(rng, 0.55, 0.9);
  const double floor_tile_m = rng.uniform(0.25, 0.6);
  const std::array<float, 3> floor_b = randomColour(rng, 0.3, 0.8);
  const std::array<float, 3> floor_a = randomColour(rng, 0.2, 0.6);
  const Texture floor_texture = rng.bernoulli(0.5) ? Texture::kTiles : Texture::kChecker;
  addRoom(scene, {L.room_hx, hy, hz}, cy, pattern(floor_texture, floor_a, floor_b, floor_tile_m),
          pattern(Texture::kNoise, wall_a, wall_b, wall_grain_m));
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
      const Material material = randomMaterial(rng);  // one draw per statement (rng.h)
      const double yaw = rng.uniform(-0.5, 0.5);
      std::vector<Primitive> cab = {
          makeBox({rng.uniform(0.2, 0.45), rng.uniform(0.15, 0.3), rng.uniform(0.2, 0.4)},
                  at(p.x(), p.y(), 0, yaw), material)};
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
  if (options.still < -1 || options.still > 4) {
    throw InvalidArgument("synth:random: still " + std::to_string(options.still) +
                          " is out of range [0, 4] (-1 = drawn from the seed)");
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

}  // namespace emf::synth
