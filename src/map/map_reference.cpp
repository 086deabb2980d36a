#include "map/map_reference.h"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace emf::map {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

bool valid(float v) { return !std::isnan(v); }

bool inGrid(const Eigen::Vector3i& c, const Eigen::Vector3i& dims) {
  return c.x() >= 0 && c.y() >= 0 && c.z() >= 0 && c.x() < dims.x() && c.y() < dims.y() &&
         c.z() < dims.z();
}

int sgn(float v) { return v > 0.0f ? 1 : (v < 0.0f ? -1 : 0); }

/// emf_sample_sdf as a value: NaN where unavailable.
float sampleSdf(const VolumeHostView& v, const Eigen::Vector3f& p, Eigen::Vector3f* grad) {
  float psi = 0.f, w = 0.f;
  Eigen::Vector3f g;
  if (!sampleSdfReference(v, p, &psi, &w, &g)) return kNaN;
  *grad = g;
  return psi;
}

}  // namespace

std::vector<uint8_t> markBlocksReference(const cv::Mat& depth_m, const CameraF& cam,
                                         const PoseRows& T_volume_camera, float block_size_m,
                                         float truncation_m, const Eigen::Vector3i& dims) {
  std::vector<uint8_t> needed(static_cast<size_t>(dims.x()) * dims.y() * dims.z(), 0);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const float d = depth_m.at<float>(y, x);
      if (!valid(d) || d <= 0.0f) continue;
      const Eigen::Vector3f ray = pixelRay(x, y, cam);
      const float z0 = std::fmax(d - truncation_m, 0.0f);
      const float z1 = d + truncation_m;
      const Eigen::Vector3f a = T_volume_camera.transform(ray * z0) / block_size_m;
      const Eigen::Vector3f b = T_volume_camera.transform(ray * z1) / block_size_m;
      const Eigen::Vector3f dir = b - a;
      Eigen::Vector3i cell(static_cast<int>(std::floor(a.x())), static_cast<int>(std::floor(a.y())),
                           static_cast<int>(std::floor(a.z())));
      const Eigen::Vector3i end(static_cast<int>(std::floor(b.x())),
                                static_cast<int>(std::floor(b.y())),
                                static_cast<int>(std::floor(b.z())));
      const Eigen::Vector3i step(sgn(dir.x()), sgn(dir.y()), sgn(dir.z()));
      float t_max[3] = {kInf, kInf, kInf};
      float t_delta[3] = {kInf, kInf, kInf};
      for (int k = 0; k < 3; ++k) {
        if (step[k] != 0) {
          t_max[k] = (static_cast<float>(cell[k] + (step[k] > 0 ? 1 : 0)) - a[k]) / dir[k];
          t_delta[k] = static_cast<float>(step[k]) / dir[k];
        }
      }
      const int max_cells = std::abs(end.x() - cell.x()) + std::abs(end.y() - cell.y()) +
                            std::abs(end.z() - cell.z()) + 1;
      for (int n = 0; n < max_cells; ++n) {
        if (inGrid(cell, dims)) needed[static_cast<size_t>(blockLinear(dims, cell))] = 1;
        int k;
        if (t_max[0] <= t_max[1] && t_max[0] <= t_max[2]) {
          k = 0;
        } else if (t_max[1] <= t_max[2]) {
          k = 1;
        } else {
          k = 2;
        }
        if (t_max[k] > 1.0f) break;
        cell[k] += step[k];
        t_max[k] += t_delta[k];
      }
    }
  }
  return needed;
}

std::vector<int> blockListReference(const VolumeHostData& vol, const std::vector<uint8_t>& marked,
                                    bool integrate_all) {
  std::vector<int> list;
  for (size_t i = 0; i < vol.index.size(); ++i) {
    if (vol.index[i] >= 0 && (marked[i] || integrate_all)) list.push_back(static_cast<int>(i));
  }
  return list;
}

void integrateReference(VolumeHostData& vol, const std::vector<int>& block_list,
                        const cv::Mat& depth_m, const cv::Mat& weights, const cv::Mat& fg_mask,
                        const CameraF& cam, const PoseRows& T_camera_volume, float max_weight,
                        bool free_space_full_weight) {
  const float truncation = vol.truncation_m;
  for (int lin : block_list) {
    const int slot = vol.index[static_cast<size_t>(lin)];
    const int count_slot = vol.count_index.empty() ? -1 : vol.count_index[static_cast<size_t>(lin)];
    const Eigen::Vector3i base = blockCoords(vol.dims_blocks, lin) * kBlockSize;
    for (int lz = 0; lz < kBlockSize; ++lz) {
      for (int ly = 0; ly < kBlockSize; ++ly) {
        for (int lx = 0; lx < kBlockSize; ++lx) {
          const Eigen::Vector3i v = base + Eigen::Vector3i(lx, ly, lz);
          const Eigen::Vector3f pc = T_camera_volume.transform(voxelCentre(v, vol.voxel_size_m));
          if (pc.z() <= 0.0f) continue;
          int px, py;
          if (!projectToPixel(pc, cam, &px, &py)) continue;
          const float d_meas = depth_m.at<float>(py, px);
          if (!valid(d_meas) || d_meas <= 0.0f) continue;
          const float sdf = d_meas - pc.z();
          if (sdf < -truncation) continue;
          const float q = weights.empty() ? 1.0f : weights.at<float>(py, px);
          const bool free_space = sdf > truncation;
          const float w = (free_space && free_space_full_weight) ? 1.0f : q;
          const int local = lx + kBlockSize * (ly + kBlockSize * lz);
          if (w > 0.0f) {
            const float tsdf = std::fmin(1.0f, sdf / truncation);
            Voxel& vox = vol.voxels[static_cast<size_t>(slot) * kBlockVoxels + local];
            const float w_old = vox.weight();
            const float w_sum = w_old + w;
            const float tsdf_new = (w_old * vox.tsdf() + w * tsdf) / w_sum;
            vox = Voxel::make(tsdf_new, std::fmin(max_weight, w_sum));
          }
          if (count_slot >= 0 && !fg_mask.empty() && !free_space) {
            const float m = fg_mask.at<float>(py, px);
            if (valid(m)) {
              Voxel& c = vol.voxels[static_cast<size_t>(count_slot) * kBlockVoxels + local];
              c = addCounts(c, m);
            }
          }
        }
      }
    }
  }
}

namespace {

bool clipSlab(float o, float d, float hi, float* t0, float* t1) {
  if (d == 0.0f) return o >= 0.0f && o <= hi;
  const float ta = (0.0f - o) / d;
  const float tb = (hi - o) / d;
  *t0 = std::fmax(*t0, std::fmin(ta, tb));
  *t1 = std::fmin(*t1, std::fmax(ta, tb));
  return true;
}

float blockExit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Eigen::Vector3i& b,
                float block_m) {
  float te = kInf;
  for (int k = 0; k < 3; ++k) {
    if (d[k] > 0.0f) te = std::fmin(te, (static_cast<float>(b[k] + 1) * block_m - o[k]) / d[k]);
    if (d[k] < 0.0f) te = std::fmin(te, (static_cast<float>(b[k]) * block_m - o[k]) / d[k]);
  }
  return te;
}

/// raycast_volume for one pixel.
void castPixel(const VolumeHostData& vol, int id, float depth_margin, const CameraF& cam,
               const PoseRows& T, const MapOptions& options, int x, int y, RaycastImages* out) {
  const VolumeHostView view = vol.view();
  const float voxel_size = vol.voxel_size_m;
  const float truncation = vol.truncation_m;
  const Eigen::Vector3f ray = pixelRay(x, y, cam);
  const Eigen::Vector3f o = T.translation();
  const Eigen::Vector3f d = T.rotate(ray);
  const float current = out->depth.at<float>(y, x);
  const float far_z = static_cast<float>(options.raycast_max_depth_m);
  float t0 = static_cast<float>(options.raycast_min_depth_m);
  float t1 = valid(current) ? std::fmin(far_z, current + depth_margin) : far_z;
  const float block_m = static_cast<float>(kBlockSize) * voxel_size;
  for (int k = 0; k < 3; ++k) {
    if (!clipSlab(o[k], d[k], static_cast<float>(vol.dims_blocks[k]) * block_m, &t0, &t1)) return;
  }
  if (!(t0 < t1)) return;
  const float step_fraction = static_cast<float>(options.raycast_step_fraction);
  const float ray_len = std::sqrt(ray.x() * ray.x() + ray.y() * ray.y() + ray.z() * ray.z());
  const float voxel_t = voxel_size / ray_len;
  Eigen::Vector3i block(-1, -1, -1);
  int slot = -1;
  bool prev_ok = false;
  float prev_t = 0.0f, prev_psi = 0.0f;
  float t = t0;
  while (t < t1) {
    const Eigen::Vector3f p = o + d * t;
    const Eigen::Vector3i v(static_cast<int>(std::floor(p.x() / voxel_size)),
                            static_cast<int>(std::floor(p.y() / voxel_size)),
                            static_cast<int>(std::floor(p.z() / voxel_size)));
    if (v.x() < 0 || v.y() < 0 || v.z() < 0) {
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const Eigen::Vector3i b = v / kBlockSize;
    if (b != block) {
      block = b;
      slot = inGrid(b, vol.dims_blocks)
                 ? vol.index[static_cast<size_t>(blockLinear(vol.dims_blocks, b))]
                 : -1;
    }
    if (slot < 0) {
      const float te = blockExit(o, d, b, block_m);
      t = std::fmax(te, t) + 0.01f * voxel_t;
      prev_ok = false;
      continue;
    }
    const Eigen::Vector3i l = v - b * kBlockSize;
    const Voxel vox = vol.voxels[static_cast<size_t>(slot) * kBlockVoxels + l.x() +
                                 kBlockSize * (l.y() + kBlockSize * l.z())];
    if (vox.weight_q <= 0) {
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const float psi = vox.tsdf() * truncation;
    if (prev_ok && prev_psi > 0.0f && psi <= 0.0f) {
      float ta = prev_t, tb = t, fa = prev_psi, fb = psi;
      Eigen::Vector3f grad(0, 0, 0);
      const float sa = sampleSdf(view, o + d * ta, &grad);
      const float sb = sampleSdf(view, o + d * tb, &grad);
      if (valid(sa) && valid(sb) && sa > 0.0f && sb <= 0.0f) {
        fa = sa;
        fb = sb;
      }
      float th = ta + (tb - ta) * (fa / (fa - fb));
      const float sh = sampleSdf(view, o + d * th, &grad);
      if (valid(sh) && fa != fb) {
        if (sh > 0.0f) {
          ta = th;
          fa = sh;
        } else {
          tb = th;
          fb = sh;
        }
        if (fa > 0.0f && fb <= 0.0f) th = ta + (tb - ta) * (fa / (fa - fb));
      }
      const Eigen::Vector3f ph = o + d * th;
      const float s_hit = sampleSdf(view, ph, &grad);
      if (!valid(s_hit)) return;
      const float grad_len =
          std::sqrt(grad.x() * grad.x() + grad.y() * grad.y() + grad.z() * grad.z());
      if (!(grad_len > 0.0f)) return;
      if (view.count_index && samplePfgReference(view, ph) <= 0.5f) return;
      if (!(th < t1)) return;
      const Eigen::Vector3f n = T.rotateInverse(grad / grad_len);
      out->depth.at<float>(y, x) = th;
      out->normals.at<cv::Vec3f>(y, x) = cv::Vec3f(n.x(), n.y(), n.z());
      out->ids.at<int>(y, x) = id;
      return;
    }
    prev_ok = true;
    prev_psi = psi;
    prev_t = t;
    t += (psi > 0.0f ? std::fmax(voxel_size, step_fraction * psi) : voxel_size) / ray_len;
  }
}

}  // namespace

RaycastImages raycastReference(const std::vector<HostRenderItem>& volumes, const CameraF& cam,
                               const Eigen::Isometry3d& T_world_camera, const MapOptions& options) {
  RaycastImages out;
  out.depth = cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(kNaN));
  out.normals = cv::Mat(cam.height, cam.width, CV_32FC3, cv::Scalar(kNaN, kNaN, kNaN));
  out.ids = cv::Mat(cam.height, cam.width, CV_32SC1, cv::Scalar(-1));
  for (const HostRenderItem& item : volumes) {
    const PoseRows T = PoseRows::from(item.volume->T_world_volume.inverse() * T_world_camera);
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x)
        castPixel(*item.volume, item.id, item.depth_margin_m, cam, T, options, x, y, &out);
    }
  }
  return out;
}

}  // namespace emf::map
