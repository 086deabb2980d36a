#include "track_test_support.h"

#include <cmath>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace emf::test {
namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
}

HostVolume::HostVolume(const Eigen::Vector3i& dims, float voxel_size, float truncation)
    : dims_blocks(dims), voxel_size_m(voxel_size), truncation_m(truncation) {
  index.assign(static_cast<size_t>(dims.prod()), -1);
}

map::VolumeHostView HostVolume::view() const {
  map::VolumeHostView v;
  v.index = index.data();
  v.dims_blocks = dims_blocks;
  v.voxels = voxels.data();
  v.voxel_size_m = voxel_size_m;
  v.truncation_m = truncation_m;
  return v;
}

int HostVolume::allocate(const Eigen::Vector3i& b) {
  int32_t& slot = index[b.x() + dims_blocks.x() * (b.y() + dims_blocks.y() * b.z())];
  if (slot < 0) {
    slot = allocatedBlocks();
    voxels.resize(voxels.size() + map::kBlockVoxels);
  }
  return slot;
}

HostVolume volumeFromSdf(const SdfFunction& sdf, const Eigen::Vector3i& dims_blocks,
                         float voxel_size, float truncation, float weight) {
  HostVolume vol(dims_blocks, voxel_size, truncation);
  const float block_m = map::kBlockSize * voxel_size;
  const float half_diag = 0.5f * std::sqrt(3.0f) * block_m;
  for (int z = 0; z < dims_blocks.z(); ++z) {
    for (int y = 0; y < dims_blocks.y(); ++y) {
      for (int x = 0; x < dims_blocks.x(); ++x) {
        const Eigen::Vector3i b(x, y, z);
        const Eigen::Vector3f centre =
            (b.cast<float>() + Eigen::Vector3f::Constant(0.5f)) * block_m;
        if (std::abs(sdf(centre)) > truncation + half_diag) continue;
        const int slot = vol.allocate(b);
        for (int l = 0; l < map::kBlockVoxels; ++l) {
          const Eigen::Vector3i lv(l % map::kBlockSize, (l / map::kBlockSize) % map::kBlockSize,
                                   l / (map::kBlockSize * map::kBlockSize));
          const Eigen::Vector3f c =
              ((b * map::kBlockSize + lv).cast<float>() + Eigen::Vector3f::Constant(0.5f)) *
              voxel_size;
          vol.voxels[static_cast<size_t>(slot) * map::kBlockVoxels + l] =
              map::Voxel::make(sdf(c) / truncation, weight);
        }
      }
    }
  }
  return vol;
}

void fuseDepth(HostVolume* vol, const cv::Mat& depth_m, const core::Intrinsics& k,
               const Eigen::Isometry3d& T_volume_camera, float max_weight) {
  const float vs = vol->voxel_size_m, tr = vol->truncation_m;
  const Eigen::Isometry3f T = T_volume_camera.cast<float>();
  const Eigen::Isometry3f T_camera_volume = T.inverse();
  const float block_m = map::kBlockSize * vs;
  // Allocation: blocks within truncation of the surface along each (2nd) pixel's ray.
  for (int v = 0; v < depth_m.rows; v += 2) {
    for (int u = 0; u < depth_m.cols; u += 2) {
      const float d = depth_m.at<float>(v, u);
      if (!(d > 0.0f)) continue;
      const Eigen::Vector3f ray(static_cast<float>((u - k.cx) / k.fx),
                                static_cast<float>((v - k.cy) / k.fy), 1.0f);
      for (float s = d - tr; s <= d + tr; s += 0.5f * vs) {
        const Eigen::Vector3f x = T * (s * ray);
        const Eigen::Vector3i b = (x / block_m).array().floor().cast<int>();
        if ((b.array() < 0).any() || (b.array() >= vol->dims_blocks.array()).any()) continue;
        vol->allocate(b);
      }
    }
  }
  // Integration: projective truncated distance, running average.
  for (size_t bi = 0; bi < vol->index.size(); ++bi) {
    const int slot = vol->index[bi];
    if (slot < 0) continue;
    const int bx = static_cast<int>(bi % vol->dims_blocks.x());
    const int by = static_cast<int>((bi / vol->dims_blocks.x()) % vol->dims_blocks.y());
    const int bz = static_cast<int>(bi / (vol->dims_blocks.x() * vol->dims_blocks.y()));
    for (int l = 0; l < map::kBlockVoxels; ++l) {
      const Eigen::Vector3i vox = Eigen::Vector3i(bx, by, bz) * map::kBlockSize +
                                  Eigen::Vector3i(l % 8, (l / 8) % 8, l / 64);
      const Eigen::Vector3f c =
          T_camera_volume * ((vox.cast<float>().array() + 0.5f) * vs).matrix();
      if (c.z() <= 0.0f) continue;
      const int u = static_cast<int>(std::lround(k.fx * c.x() / c.z() + k.cx));
      const int v = static_cast<int>(std::lround(k.fy * c.y() / c.z() + k.cy));
      if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) continue;
      const float d = depth_m.at<float>(v, u);
      if (!(d > 0.0f)) continue;
      const float sdf = d - c.z();
      if (sdf < -tr) continue;
      map::Voxel& vx = vol->voxels[static_cast<size_t>(slot) * map::kBlockVoxels + l];
      const float tsdf = std::min(1.0f, sdf / tr);
      const float w = vx.weight();
      vx = map::Voxel::make((w * vx.tsdf() + tsdf) / (w + 1.0f), std::min(max_weight, w + 1.0f));
    }
  }
}

DeviceVolume upload(cl::Context& ctx, const HostVolume& vol) {
  DeviceVolume d;
  d.index = ctx.buffer(CL_MEM_READ_ONLY, vol.index.size() * sizeof(int32_t), vol.index.data());
  const map::Voxel dummy;
  d.voxels =
      vol.voxels.empty()
          ? ctx.buffer(CL_MEM_READ_ONLY, sizeof(map::Voxel), &dummy)
          : ctx.buffer(CL_MEM_READ_ONLY, vol.voxels.size() * sizeof(map::Voxel), vol.voxels.data());
  d.view.index = d.index.get();
  d.view.voxels = d.voxels.get();
  d.view.dims_blocks = vol.dims_blocks;
  d.view.voxel_size_m = vol.voxel_size_m;
  d.view.truncation_m = vol.truncation_m;
  return d;
}

float AnalyticScene::sdf(const Eigen::Vector3f& x) const {
  // Plain float arithmetic: this runs for every voxel of the test volumes, also in Debug builds.
  const float px = x.x(), py = x.y(), pz = x.z();
  float s = std::numeric_limits<float>::max();
  for (const Plane& p : planes) {
    s = std::min(s, p.normal.x() * px + p.normal.y() * py + p.normal.z() * pz - p.offset);
  }
  for (const Box& b : boxes) {
    const float qx = std::abs(px - b.center.x()) - b.half_extent.x();
    const float qy = std::abs(py - b.center.y()) - b.half_extent.y();
    const float qz = std::abs(pz - b.center.z()) - b.half_extent.z();
    const float ox = std::max(qx, 0.0f), oy = std::max(qy, 0.0f), oz = std::max(qz, 0.0f);
    const float outside = std::sqrt(ox * ox + oy * oy + oz * oz);
    const float inside = std::min(std::max(qx, std::max(qy, qz)), 0.0f);
    s = std::min(s, outside + inside);
  }
  return s;
}

cv::Mat AnalyticScene::render(const core::Intrinsics& k, const Eigen::Isometry3d& T_volume_camera,
                              float max_depth) const {
  cv::Mat depth(k.height, k.width, CV_32F, cv::Scalar(kNaN));
  const Eigen::Vector3d o = T_volume_camera.translation();
  const Eigen::Matrix3d R = T_volume_camera.linear();
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      // Ray parameter t is the camera-frame depth: dir has z = 1 in the camera frame.
      const Eigen::Vector3d d = R * Eigen::Vector3d((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0);
      double t_hit = std::numeric_limits<double>::infinity();
      for (const Plane& p : planes) {
        const Eigen::Vector3d n = p.normal.cast<double>();
        const double nd = n.dot(d);
        if (nd >= 0.0) continue;
        const double t = (p.offset - n.dot(o)) / nd;
        if (t > 0.0) t_hit = std::min(t_hit, t);
      }
      for (const Box& b : boxes) {
        double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a) {
          const double lo = b.center[a] - b.half_extent[a], hi = b.center[a] + b.half_extent[a];
          if (std::abs(d[a]) < 1e-12) {
            if (o[a] < lo || o[a] > hi) t0 = std::numeric_limits<double>::infinity();
            continue;
          }
          double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (t0 <= t1 && t0 > 0.0) t_hit = std::min(t_hit, t0);
      }
      if (t_hit <= max_depth) depth.at<float>(v, u) = static_cast<float>(t_hit);
    }
  }
  return depth;
}

AnalyticScene roomCornerScene() {
  AnalyticScene s;
  s.planes.push_back({Eigen::Vector3f(1, 0, 0), 0.3f});    // left wall, x = 0.3
  s.planes.push_back({Eigen::Vector3f(0, -1, 0), -2.2f});  // floor, y = 2.2 (y down)
  s.planes.push_back({Eigen::Vector3f(0, 0, -1), -2.3f});  // back wall, z = 2.3
  s.boxes.push_back({Eigen::Vector3f(1.0f, 1.95f, 1.7f), Eigen::Vector3f(0.25f, 0.25f, 0.2f)});
  s.boxes.push_back({Eigen::Vector3f(1.6f, 1.2f, 2.2f), Eigen::Vector3f(0.2f, 0.15f, 0.1f)});
  s.boxes.push_back({Eigen::Vector3f(0.4f, 1.5f, 1.2f), Eigen::Vector3f(0.1f, 0.3f, 0.2f)});
  return s;
}

Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

Eigen::Isometry3d roomCornerCamera() {
  return lookAt(Eigen::Vector3d(2.0, 1.2, 0.3), Eigen::Vector3d(0.9, 1.8, 1.9));
}

core::Intrinsics smallCamera() {
  core::Intrinsics k;
  k.fx = k.fy = 262.5;
  k.cx = 159.5;
  k.cy = 119.5;
  k.width = 320;
  k.height = 240;
  return k;
}

core::Intrinsics kinectCamera() {
  core::Intrinsics k;
  k.fx = k.fy = 525.0;
  k.cx = 319.5;
  k.cy = 239.5;
  k.width = 640;
  k.height = 480;
  return k;
}

Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    // z, y, x: one draw per statement (as test::drawXyz; this file also builds into benches).
    const double z = n(rng);
    const double y = n(rng);
    v = Eigen::Vector3d(n(rng), y, z);
  } while (v.norm() < 1e-6);
  return v.normalized();
}

cv::Mat readDepthPng(const std::string& path, double depth_scale) {
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH);
  if (raw.empty() || raw.type() != CV_16U) throw std::runtime_error("cannot read uint16 " + path);
  cv::Mat depth;
  raw.convertTo(depth, CV_32F, 1.0 / depth_scale);
  depth.setTo(kNaN, raw == 0);
  return depth;
}

Eigen::Isometry3d readPoseTxt(const std::string& path) {
  std::ifstream in(path);
  double tx, ty, tz, qx, qy, qz, qw;
  if (!(in >> tx >> ty >> tz >> qx >> qy >> qz >> qw)) {
    throw std::runtime_error("cannot read pose from " + path);
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(tx, ty, tz);
  return T;
}

}  // namespace emf::test
