// The furniture of the generated scenes: pillars on the walls the camera faces and pieces along
// the walls, kept clear of the stage and of everything placed before.
#pragma once

#include "synth/random_layout.h"

namespace emf::synth::random_gen {

/// Pillars standing out of the walls the camera faces (two on the back wall, one on each side
/// wall; one per wall for an orbit), floor to ceiling: their side faces keep the camera's
/// sideways motion observable where the room would otherwise show a floor and a flat wall.
void addPillars(Scene& s, Rng& rng, Layout* L, const Occupant& stage);
/// Adds 2-5 pieces along the walls where they keep clear of the stage and the camera.
void addFurniture(Scene& s, Rng& rng, Layout* L, const Occupant& stage);

}  // namespace emf::synth::random_gen
