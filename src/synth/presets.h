// The built-in synthetic scenes (`synth:<preset>`). World frame: z up, floor z = 0, metres; time
// in seconds at 30 frames per second. In every preset the camera is hand-held-like: it moves on
// a smooth path (0.2-0.4 m/s; the first four sweep sideways looking at a slowly wandering point,
// apartment walks a loop) with a little tremor; rotation stays under 1 deg per frame.
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
//  apartment  a static flat (12 x 9 m, 2.5 m ceilings: hallway, living room, kitchen, study,
//             bedroom; 0.1 m walls, doorways 0.96 m clear with frames and open door leaves,
//             furniture in every room and along the hallway; apartment.cpp). Unlike the
//             sweeps above, the camera walks one closed loop through all rooms and doorways
//             (36.5 m, a smooth spline sampled every frame): eye height 1.45-1.55 m, looking
//             1.5 m ahead along the path and about 17 deg down, at up to 0.36 m/s (slower in
//             turns: the view turns at most ~27 deg/s), from rest back to rest at the start
//             pose. Every view has surfaces within 4 m on at least 60 % of the image. Nothing
//             moves but the camera. Default 3074 frames (102 s).
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
