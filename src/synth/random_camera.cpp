// The camera families of the generated scenes: sweep, xyz and orbit rigs with hand-held tremor.
#include "synth/random_camera.h"

#include <cmath>

#include "synth/motion_plan.h"
#include "synth/shapes.h"

namespace emf::synth::random_gen {
namespace {

void handHeld(CameraRig& rig) {
  rig.path.position_terms.push_back(sine(0.004, 0.003, 0.004, 1.7, 0.3));
  rig.path.position_terms.push_back(sine(0.002, 0.003, 0.002, 2.9, 1.1));
  rig.tremor_rad.push_back(sine(0.004, 0.005, 0.003, 1.3, 0.2));
  rig.tremor_rad.push_back(sine(0.002, 0.002, 0.002, 2.3, 1.7));
}

// A value to draw (lo < hi) or a fixed one (lo == hi: nothing is drawn).
struct Range {
  double lo, hi;
};
constexpr Range fixed(double v) { return {v, v}; }
double draw(Rng& rng, Range r) { return r.lo == r.hi ? r.lo : rng.uniform(r.lo, r.hi); }

// A sine term drawn phase first, then frequency, then the z, y and x amplitudes: the order
// every seed's rig was generated with (one draw per statement, see rng.h).
Sinusoid drawSine(Rng& rng, Range ax, Range ay, Range az, Range f_hz, Range phase) {
  const double p = draw(rng, phase);
  const double f = draw(rng, f_hz);
  const double z = draw(rng, az);
  const double y = draw(rng, ay);
  const double x = draw(rng, ax);
  return sine(x, y, z, f, p);
}

// (0, y, z) with z drawn before y.
Eigen::Vector3d drawTargetOrigin(Rng& rng, Range y, Range z) {
  const double dz = draw(rng, z);
  return v3(0, draw(rng, y), dz);
}

}  // namespace

CameraRig makeCamera(Rng& rng, Layout* L) {
  CameraRig rig;
  const double h = rng.uniform(0.9, 1.6);
  if (L->camera == "orbit") {
    const double R = L->D;
    const double v = rng.uniform(0.15, 0.3);
    const double f = v / (2 * kPi * R);
    const double phase = rng.uniform(0, 2 * kPi);
    rig.path.origin_m = v3(0, 0, h);
    const Range zero = fixed(0), turn = {0, 2 * kPi};
    rig.path.position_terms = {sine(R, 0, 0, f, phase + kPi / 2), sine(0, R, 0, f, phase),
                               drawSine(rng, zero, zero, {0.0, 0.15}, {0.05, 0.12}, zero)};
    rig.target.origin_m = v3(0, 0, rng.uniform(0.2, 0.6));
    rig.target.position_terms = {
        drawSine(rng, {0.1, 0.3}, {0.1, 0.3}, fixed(0.05), {0.04, 0.09}, turn)};
  } else if (L->camera == "xyz") {
    const Range zero = fixed(0), turn = {0, 2 * kPi};
    rig.path.origin_m = v3(rng.uniform(-0.3, 0.3), -L->D, h);
    rig.path.position_terms = {drawSine(rng, {0.05, 0.15}, zero, zero, {0.1, 0.3}, turn),
                               drawSine(rng, zero, {0.05, 0.15}, zero, {0.1, 0.3}, turn),
                               drawSine(rng, zero, zero, {0.03, 0.1}, {0.1, 0.3}, turn)};
    rig.target.origin_m = drawTargetOrigin(rng, {0.0, 0.5}, {0.2, 0.5});
    const double r = L->D * std::tan(rng.uniform(3, 8) * kDeg);
    rig.target.position_terms = {drawSine(rng, fixed(r), zero, zero, {0.08, 0.2}, turn),
                                 drawSine(rng, zero, zero, fixed(0.6 * r), {0.08, 0.2}, turn)};
    L->sweep_x = 0.15;
  } else {
    const Range zero = fixed(0), turn = {0, 2 * kPi};
    L->sweep_x = rng.uniform(0.3, 0.9);
    rig.path.origin_m = v3(0, -L->D, h);
    rig.path.position_terms = {drawSine(rng, fixed(L->sweep_x), zero, zero, {0.03, 0.07}, turn),
                               drawSine(rng, zero, {0.0, 0.3}, zero, {0.05, 0.1}, turn),
                               drawSine(rng, zero, zero, {0.0, 0.1}, {0.08, 0.14}, turn)};
    rig.target.origin_m = drawTargetOrigin(rng, {0.0, 0.6}, {0.2, 0.6});
    rig.target.position_terms = {drawSine(rng, {0.2, 0.6}, zero, zero, {0.04, 0.08}, turn),
                                 drawSine(rng, zero, zero, {0.05, 0.15}, {0.06, 0.1}, turn)};
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

}  // namespace emf::synth::random_gen
