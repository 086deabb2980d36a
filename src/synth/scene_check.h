// The view check of a generated scene: how long each object is detectable, how close the camera
// comes to a surface, and how well the static scene in view pins the camera down.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "synth/renderer.h"
#include "synth/scene.h"

namespace emf::synth::random_gen {

/// How well the static scene in view pins the camera down: the smallest eigenvalue of the mean
/// of n n^T over the surface normals of `depth` (CV_32F, NaN = nothing, 4.5 m range) where
/// `ids` (CV_16U) is 0 (the static scene, objects left out), in [0, 1/3]. Near 0 when all surfaces
/// in view share a direction they are parallel to (a floor and one wall: sliding along the wall
/// changes no depth).
double normalSpread(const cv::Mat& depth, const cv::Mat& ids, const core::Intrinsics& K);

/// Fraction of the frames (every 8th) on which each object is detectable: in view with a box of
/// at least kMinBoxFraction of the image width on both sides (the paper's 40 px detection filter
/// at 640 px, with a margin); the camera's nearest surface over them (metres); and the
/// normalSpread of the static scene in view per frame. Rendered at 96x72.
void viewCheck(const Scene& scene, int frames, std::vector<double>* detectable, double* nearest_m,
               std::vector<double>* spread);

}  // namespace emf::synth::random_gen
