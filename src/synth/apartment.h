// The `apartment` preset: a static flat of four rooms and a hallway, walked through on a long
// closed loop by a hand-held camera (presets.h describes it; apartment.cpp builds it).
#pragma once

#include "synth/scene.h"

namespace emf::synth {

/// Builds the `apartment` preset. World frame: z up, floor z = 0, metres; the flat covers
/// x in [0, 12], y in [0, 9].
Scene apartment();

}  // namespace emf::synth
