#pragma once
// Points of a detection's mask, shared by the object matching, creation and re-identification.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

namespace emf::pipeline {

/// A mask pixel belongs to the instance above this foreground probability p_fg.
constexpr float kMaskInside = 0.5f;

/// Camera-frame points (m) of the mask's pixels (CV_32F p_fg > kMaskInside) with a valid
/// vertex (`vertex`: CV_32FC4, w = 0 where the depth is missing).
std::vector<Eigen::Vector3d> maskedPoints(const cv::Mat& vertex, const cv::Mat& mask);

/// Per-axis value at fraction f (0-1) of the points' sorted coordinates; `points` not empty.
Eigen::Vector3d percentile(std::vector<Eigen::Vector3d> points, double f);

}  // namespace emf::pipeline
