// Host mirror of kernels_cl/voxel_access.clh: the voxel-block layout every map kernel uses.
// Keep the two identical (tests/map compare the CPU references against the kernels).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace emf::map {

constexpr int kBlockSize = 8;                                       // voxels per block edge
constexpr int kBlockVoxels = kBlockSize * kBlockSize * kBlockSize;  // 512
constexpr float kTsdfScale = 32767.0f;  // TSDF/truncation in [-1, 1] -> int16
constexpr float kWeightScale = 256.0f;  // weight -> int16 (max 127.99)
constexpr float kMaxStorableWeight = 32767.0f / kWeightScale;

/// One voxel as stored in the pool (OpenCL short2).
struct Voxel {
  int16_t tsdf_q = 0;
  int16_t weight_q = 0;

  float tsdf() const { return static_cast<float>(tsdf_q) / kTsdfScale; }
  float weight() const { return static_cast<float>(weight_q) / kWeightScale; }
  static Voxel make(float tsdf, float weight) {
    Voxel v;
    v.tsdf_q = static_cast<int16_t>(std::lrint(std::clamp(tsdf, -1.0f, 1.0f) * kTsdfScale));
    v.weight_q = static_cast<int16_t>(
        std::lrint(std::clamp(weight, 0.0f, kMaxStorableWeight) * kWeightScale));
    return v;
  }
};
static_assert(sizeof(Voxel) == 4, "Voxel must match OpenCL short2");

/// Read-only host view of one volume: its index grid and the pool's voxel array.
struct VolumeHostView {
  const int32_t* index = nullptr;  // dims.x * dims.y * dims.z entries, -1 = unallocated
  Eigen::Vector3i dims_blocks{0, 0, 0};
  const Voxel* voxels = nullptr;  // the pool's voxels (slot * kBlockVoxels + local)
  float voxel_size_m = 0.01f;
  float truncation_m = 0.1f;

  /// Index into `voxels` of voxel v, or -1 (outside the grid / unallocated block).
  int64_t voxelIndex(const Eigen::Vector3i& v) const {
    if ((v.array() < 0).any()) return -1;
    const Eigen::Vector3i b = v / kBlockSize;
    if ((b.array() >= dims_blocks.array()).any()) return -1;
    const int32_t slot = index[b.x() + dims_blocks.x() * (b.y() + dims_blocks.y() * b.z())];
    if (slot < 0) return -1;
    const Eigen::Vector3i l = v - b * kBlockSize;
    return static_cast<int64_t>(slot) * kBlockVoxels + l.x() +
           kBlockSize * (l.y() + kBlockSize * l.z());
  }
};

/// CPU reference of emf_sample_sdf (voxel_access.clh): trilinear psi (metres) at p (volume
/// frame, metres). Returns false where any of the 8 neighbours is unallocated or unobserved.
inline bool sampleSdfReference(const VolumeHostView& vol, const Eigen::Vector3f& p, float* psi,
                               float* weight, Eigen::Vector3f* gradient) {
  const Eigen::Vector3f g = p / vol.voxel_size_m - Eigen::Vector3f::Constant(0.5f);
  const Eigen::Vector3f f0 = g.array().floor();
  const Eigen::Vector3i v0 = f0.cast<int>();
  const Eigen::Vector3f f = g - f0;
  float c[8];
  float w = 0.f;
  for (int n = 0; n < 8; ++n) {
    const Eigen::Vector3i v = v0 + Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1);
    const int64_t i = vol.voxelIndex(v);
    if (i < 0) return false;
    const Voxel vox = vol.voxels[i];
    if (vox.weight_q <= 0) return false;
    c[n] = vox.tsdf() * vol.truncation_m;
    const float wx = (n & 1) ? f.x() : 1.f - f.x();
    const float wy = ((n >> 1) & 1) ? f.y() : 1.f - f.y();
    const float wz = ((n >> 2) & 1) ? f.z() : 1.f - f.z();
    w += wx * wy * wz * vox.weight();
  }
  auto mix = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = mix(c[0], c[1], f.x()), c10 = mix(c[2], c[3], f.x());
  const float c01 = mix(c[4], c[5], f.x()), c11 = mix(c[6], c[7], f.x());
  const float c0 = mix(c00, c10, f.y()), c1 = mix(c01, c11, f.y());
  *psi = mix(c0, c1, f.z());
  const float fx = f.x(), fy = f.y(), fz = f.z();
  const float dx = (1 - fy) * (1 - fz) * (c[1] - c[0]) + fy * (1 - fz) * (c[3] - c[2]) +
                   (1 - fy) * fz * (c[5] - c[4]) + fy * fz * (c[7] - c[6]);
  const float dy = (1 - fx) * (1 - fz) * (c[2] - c[0]) + fx * (1 - fz) * (c[3] - c[1]) +
                   (1 - fx) * fz * (c[6] - c[4]) + fx * fz * (c[7] - c[5]);
  const float dz = (1 - fx) * (1 - fy) * (c[4] - c[0]) + fx * (1 - fy) * (c[5] - c[1]) +
                   (1 - fx) * fy * (c[6] - c[2]) + fx * fy * (c[7] - c[3]);
  *gradient = Eigen::Vector3f(dx, dy, dz) / vol.voxel_size_m;
  *weight = w;
  return true;
}

}  // namespace emf::map
