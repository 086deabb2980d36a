#include "synth/scene.h"

#include <algorithm>
#include <cmath>

namespace emf::synth {
namespace {

/// A fixed pseudo-random permutation of 0..255 (Perlin-style lattice hashing).
struct Permutation {
  uint8_t p[512];
  Permutation() {
    uint8_t base[256];
    for (int i = 0; i < 256; ++i) base[i] = static_cast<uint8_t>(i);
    uint32_t state = 0x2545f491u;
    for (int i = 255; i > 0; --i) {
      state = state * 1664525u + 1013904223u;
      const int j = static_cast<int>((state >> 8) % static_cast<uint32_t>(i + 1));
      std::swap(base[i], base[j]);
    }
    for (int i = 0; i < 512; ++i) p[i] = base[i & 255];
  }
};
const Permutation kPerm;

float unitHash(int32_t x, int32_t y, int32_t z) {
  const uint8_t* p = kPerm.p;
  return static_cast<float>(p[p[p[x & 255] + (y & 255)] + (z & 255)]) * (1.0f / 255.0f);
}

float fade(float t) { return t * t * (3.0f - 2.0f * t); }

/// Trilinear value noise in [0, 1) with lattice spacing 1.
float valueNoise(double x, double y, double z) {
  const double fx = std::floor(x), fy = std::floor(y), fz = std::floor(z);
  const auto ix = static_cast<int32_t>(fx), iy = static_cast<int32_t>(fy),
             iz = static_cast<int32_t>(fz);
  const float tx = fade(static_cast<float>(x - fx)), ty = fade(static_cast<float>(y - fy)),
              tz = fade(static_cast<float>(z - fz));
  auto lerp = [](float a, float b, float t) { return a + (b - a) * t; };
  const float c00 = lerp(unitHash(ix, iy, iz), unitHash(ix + 1, iy, iz), tx);
  const float c10 = lerp(unitHash(ix, iy + 1, iz), unitHash(ix + 1, iy + 1, iz), tx);
  const float c01 = lerp(unitHash(ix, iy, iz + 1), unitHash(ix + 1, iy, iz + 1), tx);
  const float c11 = lerp(unitHash(ix, iy + 1, iz + 1), unitHash(ix + 1, iy + 1, iz + 1), tx);
  return lerp(lerp(c00, c10, ty), lerp(c01, c11, ty), tz);
}

std::array<float, 3> mix(const std::array<float, 3>& a, const std::array<float, 3>& b, float t) {
  return {a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t};
}

/// Cell index with a tiny offset so faces lying exactly on a cell boundary do not flicker.
int32_t cell(double v, double scale) { return static_cast<int32_t>(std::floor(v / scale + 1e-4)); }

}  // namespace

std::array<float, 3> albedoAt(const Material& m, V3 p) {
  const double s = m.scale_m > 0 ? m.scale_m : 1.0;
  switch (m.texture) {
    case Texture::kSolid:
      return m.albedo_bgr;
    case Texture::kChecker: {
      const int32_t parity = cell(p.x, s) + cell(p.y, s) + cell(p.z, s);
      return (parity & 1) ? m.albedo2_bgr : m.albedo_bgr;
    }
    case Texture::kStripes: {
      const double t = 0.5 + 0.5 * std::sin(6.283185307179586 * p.x / s);
      return mix(m.albedo_bgr, m.albedo2_bgr, static_cast<float>(t));
    }
    case Texture::kNoise:
      return mix(m.albedo_bgr, m.albedo2_bgr, valueNoise(p.x / s, p.y / s, p.z / s));
    case Texture::kTiles: {
      const int32_t cx = cell(p.x, s), cy = cell(p.y, s), cz = cell(p.z, s);
      const float tile = 0.35f * unitHash(cx, cy, cz) + ((cx + cy + cz) & 1 ? 0.45f : 0.0f);
      // Wood-like grain: stripes along x whose phase wanders with y (cheaper than noise).
      const float grain = static_cast<float>(
          0.1 + 0.1 * std::sin(40.0 * p.y / s + 3.0 * std::sin(5.0 * p.x / s + cx * 1.7)));
      return mix(m.albedo_bgr, m.albedo2_bgr, std::min(1.0f, tile + grain));
    }
  }
  return m.albedo_bgr;
}

int minVisiblePixels(int width, int height) {
  return std::max(1, static_cast<int>(std::lround(kMinVisibleFraction * width * height)));
}

std::vector<int> instancePixelCounts(const cv::Mat& instance_ids) {
  std::vector<int> counts;
  if (instance_ids.empty()) return counts;
  CV_Assert(instance_ids.type() == CV_16U);
  for (int v = 0; v < instance_ids.rows; ++v) {
    const auto* row = instance_ids.ptr<uint16_t>(v);
    for (int u = 0; u < instance_ids.cols; ++u) {
      if (row[u] >= counts.size()) counts.resize(row[u] + 1u, 0);
      ++counts[row[u]];
    }
  }
  return counts;
}

namespace {
Primitive make(Shape shape, V3 half_extents_m, double radius_m, const Eigen::Isometry3d& T,
               const Material& material) {
  Primitive p;
  p.geometry.shape = shape;
  p.geometry.half_extents_m = half_extents_m;
  p.geometry.radius_m = radius_m;
  p.T_parent_primitive = T;
  p.material = material;
  return p;
}
}  // namespace

Primitive makeBox(V3 h, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kBox, h, 0.0, T, m);
}
Primitive makeRoundedBox(V3 h, double r, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kRoundedBox, h, r, T, m);
}
Primitive makeSphere(double r, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kSphere, {r, r, r}, r, T, m);
}
Primitive makeCylinder(double r, double hz, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kCylinder, {r, r, hz}, r, T, m);
}
Primitive makeCapsule(double r, double hz, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kCapsule, {r, r, hz}, r, T, m);
}
Primitive makePlane(const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kPlane, {0, 0, 0}, 0.0, T, m);
}
Primitive makeRoom(V3 h, const Eigen::Isometry3d& T, const Material& m) {
  return make(Shape::kRoom, h, 0.0, T, m);
}

Eigen::Isometry3d at(double x, double y, double z, double yaw, double pitch, double roll) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

Eigen::AlignedBox3d objectBounds(const SceneObject& object) {
  Eigen::AlignedBox3d box;
  for (const auto& part : object.parts) {
    V3 h;
    if (!localBounds(part.geometry, &h)) continue;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner((c & 1) ? h.x : -h.x, (c & 2) ? h.y : -h.y,
                                   (c & 4) ? h.z : -h.z);
      box.extend(part.T_parent_primitive * corner);
    }
  }
  return box;
}

}  // namespace emf::synth
