// The built-in synthetic scenes (`synth:<preset>`). World frame: z up, floor z = 0, metres; time
// in seconds at 30 frames per second. In every preset the camera is hand-held-like: it sweeps
// sideways on a smooth path (0.2-0.4 m/s) looking at a slowly wandering point, with a little
// tremor; rotation stays well under 1 deg per frame.
//
//  room       static room with furniture (table with a ball, vase and bottle, chairs, shelf,
//             sofa, lamp, picture). Nothing moves but the camera. Default 300 frames.
//  cars       two toy cars (class "car", ids 1 and 2) drive on the floor in front of a table:
//             car 1 counter-clockwise on a 1.7 x 1.1 m ellipse (period 14.3 s), car 2 clockwise
//             on a 0.9 x 0.44 m ellipse (period 9.1 s), both from frame 0 on, with a slight
//             bounce. Default 450 frames.
//  occlusion  a room with three objects: 1 "teddy bear" flies around at head height from frame
//             0 on (sinusoidal 6-DoF motion); 2 "suitcase" slides in from the left between 2 s
//             and 5 s, stays in front of the chair (occluding most of it) until 9 s, then slides
//             out to the right by 12 s; 3 "chair" stands still until 13 s and then accelerates
//             into a sideways swinging, turning motion. Default 600 frames.
//  enter      a "couch" (id 1, about 2 m wide) enters from the right image border between
//             1.5 s and 6.5 s, turning slightly, stops near the image centre, shifts again
//             between 8 s and 9.5 s, then stays. Default 300 frames.
//
// The seed does not change the geometry or the motion (so ground truth is comparable across
// seeds); it drives the depth noise, colour noise and the simulated detector.
#pragma once

#include <string>
#include <vector>

#include "synth/scene.h"

namespace emf::synth {

/// Names of the built-in presets, in documentation order.
std::vector<std::string> presetNames();

/// Builds a preset scene. Throws IoError naming the preset and listing the valid ones.
Scene makePreset(const std::string& name);

}  // namespace emf::synth
