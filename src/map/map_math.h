// Host mirror of kernels_cl/map_common.clh: the float geometry of the map kernels, written with
// the same operations in the same order so that the CPU references agree with the kernels to
// rounding (the kernels are compiled with FP_CONTRACT OFF; the host build does not fuse either).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "map/voxel_layout.h"

namespace emf::map {

/// A rigid transform T_a_b in float, stored as the rows of [R | t] exactly as the kernels get
/// it (three float4 arguments).
struct PoseRows {
  float r[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};

  static PoseRows from(const Eigen::Isometry3d& T) {
    PoseRows p;
    const Eigen::Matrix4d m = T.matrix();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 4; ++j) p.r[i][j] = static_cast<float>(m(i, j));
    }
    return p;
  }
  /// Row i as the 4 floats of a cl_float4.
  const float* row(int i) const { return r[i]; }

  Eigen::Vector3f transform(const Eigen::Vector3f& p) const {
    return Eigen::Vector3f(r[0][0] * p.x() + r[0][1] * p.y() + r[0][2] * p.z() + r[0][3],
                           r[1][0] * p.x() + r[1][1] * p.y() + r[1][2] * p.z() + r[1][3],
                           r[2][0] * p.x() + r[2][1] * p.y() + r[2][2] * p.z() + r[2][3]);
  }
  Eigen::Vector3f rotate(const Eigen::Vector3f& d) const {
    return Eigen::Vector3f(r[0][0] * d.x() + r[0][1] * d.y() + r[0][2] * d.z(),
                           r[1][0] * d.x() + r[1][1] * d.y() + r[1][2] * d.z(),
                           r[2][0] * d.x() + r[2][1] * d.y() + r[2][2] * d.z());
  }
  Eigen::Vector3f rotateInverse(const Eigen::Vector3f& d) const {
    return Eigen::Vector3f(r[0][0] * d.x() + r[1][0] * d.y() + r[2][0] * d.z(),
                           r[0][1] * d.x() + r[1][1] * d.y() + r[2][1] * d.z(),
                           r[0][2] * d.x() + r[1][2] * d.y() + r[2][2] * d.z());
  }
  Eigen::Vector3f translation() const { return Eigen::Vector3f(r[0][3], r[1][3], r[2][3]); }
};

/// Pinhole camera in float as the kernels get it.
struct CameraF {
  float fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
};

/// Centre of voxel v in the volume frame, metres (emf_voxel_centre).
inline Eigen::Vector3f voxelCentre(const Eigen::Vector3i& v, float voxel_size_m) {
  return Eigen::Vector3f((static_cast<float>(v.x()) + 0.5f) * voxel_size_m,
                         (static_cast<float>(v.y()) + 0.5f) * voxel_size_m,
                         (static_cast<float>(v.z()) + 0.5f) * voxel_size_m);
}

/// Nearest pixel of a camera-frame point, or false when z <= 0 or outside the image
/// (emf_project; inv_z = 1 / pc.z).
inline bool projectToPixel(const Eigen::Vector3f& pc, float inv_z, const CameraF& cam, int* x,
                           int* y) {
  const float u = cam.fx * (pc.x() * inv_z) + cam.cx + 0.5f;
  const float v = cam.fy * (pc.y() * inv_z) + cam.cy + 0.5f;
  const bool in_view = pc.z() > 0.0f && u >= 0.0f && v >= 0.0f &&
                       u < static_cast<float>(cam.width) && v < static_cast<float>(cam.height);
  if (!in_view) return false;
  *x = static_cast<int>(u);
  *y = static_cast<int>(v);
  return true;
}

/// projectToPixel computing inv_z itself.
inline bool projectToPixel(const Eigen::Vector3f& pc, const CameraF& cam, int* x, int* y) {
  return projectToPixel(pc, 1.0f / pc.z(), cam, x, y);
}

/// Viewing ray of pixel (x, y) scaled to z = 1 (emf_pixel_ray).
inline Eigen::Vector3f pixelRay(int x, int y, const CameraF& cam) {
  return Eigen::Vector3f((static_cast<float>(x) - cam.cx) / cam.fx,
                         (static_cast<float>(y) - cam.cy) / cam.fy, 1.0f);
}

/// Linear index of block b in a grid of `dims` blocks (emf_block_linear).
inline int blockLinear(const Eigen::Vector3i& dims, const Eigen::Vector3i& b) {
  return b.x() + dims.x() * (b.y() + dims.y() * b.z());
}

/// Block coordinates of a linear block index (emf_block_coords).
inline Eigen::Vector3i blockCoords(const Eigen::Vector3i& dims, int lin) {
  const int plane = dims.x() * dims.y();
  const int z = lin / plane;
  const int r = lin - z * plane;
  const int y = r / dims.x();
  return Eigen::Vector3i(r - y * dims.x(), y, z);
}

}  // namespace emf::map
