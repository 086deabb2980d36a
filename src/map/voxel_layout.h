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
  /// Object volumes: the count-block index grid (same dims as `index`), else nullptr.
  const int32_t* count_index = nullptr;

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

  /// Index into `voxels` of the (Fg, Bg) counts of voxel v, or -1 (no count block).
  int64_t countIndex(const Eigen::Vector3i& v) const {
    if (!count_index) return -1;
    VolumeHostView counts_view = *this;
    counts_view.index = count_index;
    return counts_view.voxelIndex(v);
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

// ---- Foreground/background counts (mirror of the count helpers in voxel_access.clh) --------
constexpr float kCountScale = 256.0f;  // 8.8 fixed point: one observation = 256
constexpr float kPfgUnknown = 0.5f;    // p_fg of a voxel without counts

/// (Fg, Bg) of a count voxel stored bit-cast in a Voxel (two uint16).
inline Eigen::Vector2f counts(const Voxel& raw) {
  return Eigen::Vector2f(static_cast<float>(static_cast<uint16_t>(raw.tsdf_q)),
                         static_cast<float>(static_cast<uint16_t>(raw.weight_q))) /
         kCountScale;
}

/// p_fg from counts; kPfgUnknown without any.
inline float pfgFromCounts(float fg, float bg) {
  const float s = fg + bg;
  return s > 0.0f ? fg / s : kPfgUnknown;
}

/// CPU reference of emf_add_counts.
inline Voxel addCounts(const Voxel& raw, float p_fg_det) {
  uint32_t fg = static_cast<uint16_t>(raw.tsdf_q);
  uint32_t bg = static_cast<uint16_t>(raw.weight_q);
  const uint32_t add_fg =
      static_cast<uint32_t>(std::lrint(std::clamp(p_fg_det, 0.0f, 1.0f) * kCountScale));
  const uint32_t add_bg = static_cast<uint32_t>(kCountScale) - add_fg;
  if (fg + add_fg > 65535u || bg + add_bg > 65535u) {
    fg >>= 1;
    bg >>= 1;
  }
  Voxel out;
  out.tsdf_q = static_cast<int16_t>(static_cast<uint16_t>(fg + add_fg));
  out.weight_q = static_cast<int16_t>(static_cast<uint16_t>(bg + add_bg));
  return out;
}

/// CPU reference of emf_sample_pfg: trilinear Fg and Bg at p (volume frame, metres), divided.
inline float samplePfgReference(const VolumeHostView& vol, const Eigen::Vector3f& p) {
  const Eigen::Vector3f g = p / vol.voxel_size_m - Eigen::Vector3f::Constant(0.5f);
  const Eigen::Vector3f f0 = g.array().floor();
  const Eigen::Vector3i v0 = f0.cast<int>();
  const Eigen::Vector3f f = g - f0;
  float fg = 0.f, bg = 0.f;
  for (int n = 0; n < 8; ++n) {
    const Eigen::Vector3i v = v0 + Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1);
    const int64_t i = vol.countIndex(v);
    if (i < 0) continue;
    const Eigen::Vector2f c = counts(vol.voxels[i]);
    const float wx = (n & 1) ? f.x() : 1.f - f.x();
    const float wy = ((n >> 1) & 1) ? f.y() : 1.f - f.y();
    const float wz = ((n >> 2) & 1) ? f.z() : 1.f - f.z();
    const float w = wx * wy * wz;
    fg += w * c.x();
    bg += w * c.y();
  }
  return pfgFromCounts(fg, bg);
}

}  // namespace emf::map
