// The camera families of the generated scenes (sweep, xyz, orbit): a camera rig drawn for a
// layout.
#pragma once

#include "synth/random_layout.h"
#include "synth/trajectory.h"

namespace emf::synth::random_gen {

/// The camera rig of the family L->camera at distance L->D, slowed down to at most 0.4 m/s and
/// 30 deg/s over L->T, with hand-held tremor; sets L->sweep_x.
CameraRig makeCamera(Rng& rng, Layout* L);

}  // namespace emf::synth::random_gen
