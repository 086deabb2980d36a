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
    rig.path.position_terms = {sine(R, 0, 0, f, phase + kPi / 2), sine(0, R, 0, f, phase),
                               sine(0, 0, rng.uniform(0.0, 0.15), rng.uniform(0.05, 0.12))};
    rig.target.origin_m = v3(0, 0, rng.uniform(0.2, 0.6));
    rig.target.position_terms = {sine(rng.uniform(0.1, 0.3), rng.uniform(0.1, 0.3), 0.05,
                                      rng.uniform(0.04, 0.09), rng.uniform(0, 2 * kPi))};
  } else if (L->camera == "xyz") {
    rig.path.origin_m = v3(rng.uniform(-0.3, 0.3), -L->D, h);
    rig.path.position_terms = {
        sine(rng.uniform(0.05, 0.15), 0, 0, rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi)),
        sine(0, rng.uniform(0.05, 0.15), 0, rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.03, 0.1), rng.uniform(0.1, 0.3), rng.uniform(0, 2 * kPi))};
    rig.target.origin_m = v3(0, rng.uniform(0.0, 0.5), rng.uniform(0.2, 0.5));
    const double r = L->D * std::tan(rng.uniform(3, 8) * kDeg);
    rig.target.position_terms = {
        sine(r, 0, 0, rng.uniform(0.08, 0.2), rng.uniform(0, 2 * kPi)),
        sine(0, 0, 0.6 * r, rng.uniform(0.08, 0.2), rng.uniform(0, 2 * kPi))};
    L->sweep_x = 0.15;
  } else {
    L->sweep_x = rng.uniform(0.3, 0.9);
    rig.path.origin_m = v3(0, -L->D, h);
    rig.path.position_terms = {
        sine(L->sweep_x, 0, 0, rng.uniform(0.03, 0.07), rng.uniform(0, 2 * kPi)),
        sine(0, rng.uniform(0.0, 0.3), 0, rng.uniform(0.05, 0.1), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.0, 0.1), rng.uniform(0.08, 0.14), rng.uniform(0, 2 * kPi))};
    rig.target.origin_m = v3(0, rng.uniform(0.0, 0.6), rng.uniform(0.2, 0.6));
    rig.target.position_terms = {
        sine(rng.uniform(0.2, 0.6), 0, 0, rng.uniform(0.04, 0.08), rng.uniform(0, 2 * kPi)),
        sine(0, 0, rng.uniform(0.05, 0.15), rng.uniform(0.06, 0.1), rng.uniform(0, 2 * kPi))};
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
