#include "map/map_reference.h"

#include <cmath>
#include <cstdlib>
#include <limits>

namespace emf::map {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

bool valid(float v) { return !std::isnan(v); }

constexpr int kRayTileReference = 16;      // EMF_RAY_TILE / kRayTile
constexpr float kMaxMarkDepthM = 1000.0f;  // EMF_MAX_MARK_DEPTH

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
                                         float truncation_m, const Eigen::Vector3i& dims,
                                         int stride) {
  std::vector<uint8_t> needed(static_cast<size_t>(dims.x()) * dims.y() * dims.z(), 0);
  for (int y = 0; y < cam.height; y += stride) {
    for (int x = 0; x < cam.width; x += stride) {
      const float d = depth_m.at<float>(y, x);
      if (!valid(d) || d <= 0.0f || d > kMaxMarkDepthM) continue;
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
                                    bool integrate_all, int phases, int phase,
                                    const std::vector<int32_t>* index_before) {
  std::vector<int> list;
  for (size_t i = 0; i < vol.index.size(); ++i) {
    if (vol.index[i] < 0) continue;
    bool in_phase = true;
    if (phases > 1 && !(index_before && (*index_before)[i] < 0)) {
      const Eigen::Vector3i b = blockCoords(vol.dims_blocks, static_cast<int>(i));
      in_phase = (b.x() + b.y() + b.z()) % phases == phase;
    }
    if ((marked[i] && in_phase) || integrate_all) list.push_back(static_cast<int>(i));
  }
  return list;
}

void integrateReference(VolumeHostData& vol, const std::vector<int>& block_list,
                        const cv::Mat& depth_m, const cv::Mat& weights, const cv::Mat& fg_mask,
                        const CameraF& cam, const PoseRows& T_camera_volume, float max_weight,
                        bool free_space_full_weight, bool behind_dropoff, float weight_scale) {
  const float truncation = vol.truncation_m;
  const float inv_truncation = 1.0f / truncation;
  const float vs = vol.voxel_size_m;
  const float(&r)[3][4] = T_camera_volume.r;
  // emf_round_even: rint without a builtin (same IEEE operations as the kernel).
  auto round_even = [](float x) { return (x + 12582912.0f) - 12582912.0f; };
  const float max_storable = 32767.0f / kWeightScale;
  for (int lin : block_list) {
    const int slot = vol.index[static_cast<size_t>(lin)];
    const int count_slot = vol.count_index.empty() ? -1 : vol.count_index[static_cast<size_t>(lin)];
    const Eigen::Vector3i b = blockCoords(vol.dims_blocks, lin);
    for (int lid = 0; lid < kBlockVoxels; ++lid) {
      const float px_v = (static_cast<float>(b.x() * kBlockSize + (lid & 7)) + 0.5f) * vs;
      const float py_v = (static_cast<float>(b.y() * kBlockSize + ((lid >> 3) & 7)) + 0.5f) * vs;
      const float pz_v = (static_cast<float>(b.z() * kBlockSize + (lid >> 6)) + 0.5f) * vs;
      const float xc = r[0][0] * px_v + r[0][1] * py_v + r[0][2] * pz_v + r[0][3];
      const float yc = r[1][0] * px_v + r[1][1] * py_v + r[1][2] * pz_v + r[1][3];
      const float zc = r[2][0] * px_v + r[2][1] * py_v + r[2][2] * pz_v + r[2][3];
      const float inv_z = 1.0f / zc;
      const float u = cam.fx * (xc * inv_z) + cam.cx + 0.5f;
      const float v = cam.fy * (yc * inv_z) + cam.cy + 0.5f;
      const bool in_view = zc > 0.0f && u >= 0.0f && v >= 0.0f &&
                           u < static_cast<float>(cam.width) && v < static_cast<float>(cam.height);
      if (!in_view) continue;
      const int px = static_cast<int>(u), py = static_cast<int>(v);
      const float d_meas = depth_m.at<float>(py, px);
      const float sdf = d_meas - zc;
      if (!(d_meas > 0.0f && sdf >= -truncation)) continue;
      const float q = weights.empty() ? 1.0f : weights.at<float>(py, px);
      const bool free_space = sdf > truncation;
      float w = (free_space && free_space_full_weight) ? 1.0f : q;
      if (behind_dropoff && sdf < -vs) {
        const float drop = (truncation + sdf) / (truncation - vs);
        w = w * (drop > 0.0f ? drop : 0.0f);
      }
      w *= weight_scale;
      if (w > 0.0f) {
        Voxel& vox = vol.voxels[static_cast<size_t>(slot) * kBlockVoxels + lid];
        const float w_old = static_cast<float>(vox.weight_q) / kWeightScale;
        const float w_sum = w_old + w;
        const float tsdf_obs = sdf * inv_truncation < 1.0f ? sdf * inv_truncation : 1.0f;
        float tsdf_new =
            (w_old * (static_cast<float>(vox.tsdf_q) / kTsdfScale) + w * tsdf_obs) / w_sum;
        tsdf_new = tsdf_new < -1.0f ? -1.0f : (tsdf_new > 1.0f ? 1.0f : tsdf_new);
        float w_new = w_sum < max_weight ? w_sum : max_weight;
        w_new = w_new < max_storable ? w_new : max_storable;
        vox.tsdf_q = static_cast<int16_t>(round_even(tsdf_new * kTsdfScale));
        vox.weight_q = static_cast<int16_t>(round_even(w_new * kWeightScale));
      }
      if (count_slot >= 0 && !fg_mask.empty() && !free_space) {
        const float m = fg_mask.at<float>(py, px);
        if (valid(m)) {
          Voxel& c = vol.voxels[static_cast<size_t>(count_slot) * kBlockVoxels + lid];
          c = addCounts(c, m);
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

float blockExit(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Eigen::Vector3f& inv_d,
                const Eigen::Vector3i& b, float block_m, float t) {
  float te = kInf;
  for (int k = 0; k < 3; ++k) {
    if (d[k] != 0.0f) {
      const float c =
          (static_cast<float>(d[k] > 0.0f ? b[k] + 1 : b[k]) * block_m - o[k]) * inv_d[k];
      if (c > t) te = std::fmin(te, c);
    }
  }
  return te;
}

}  // namespace

TileRanges tileRangesReference(const VolumeHostData& vol, const CameraF& cam, const PoseRows& T_cv,
                               const MapOptions& options) {
  TileRanges tb;
  tb.tiles_x = (cam.width + kRayTileReference - 1) / kRayTileReference;
  const int tiles_y = (cam.height + kRayTileReference - 1) / kRayTileReference;
  tb.z_min.assign(static_cast<size_t>(tb.tiles_x * tiles_y), kInf);
  tb.z_max.assign(static_cast<size_t>(tb.tiles_x * tiles_y), 0.0f);
  const float block_m = static_cast<float>(kBlockSize) * vol.voxel_size_m;
  const float near_z = static_cast<float>(options.raycast_min_depth_m);
  const float far_z = static_cast<float>(options.raycast_max_depth_m);
  for (size_t i = 0; i < vol.index.size(); ++i) {
    if (vol.index[i] < 0) continue;
    const Eigen::Vector3i b = blockCoords(vol.dims_blocks, static_cast<int>(i));
    float z_lo = kInf, z_hi = 0.0f, u_lo = kInf, u_hi = -kInf, v_lo = kInf, v_hi = -kInf;
    bool straddles = false;
    for (int n = 0; n < 8; ++n) {
      const Eigen::Vector3f corner(static_cast<float>(b.x() + (n & 1)) * block_m,
                                   static_cast<float>(b.y() + ((n >> 1) & 1)) * block_m,
                                   static_cast<float>(b.z() + ((n >> 2) & 1)) * block_m);
      const Eigen::Vector3f pc = T_cv.transform(corner);
      z_lo = std::fmin(z_lo, pc.z());
      z_hi = std::fmax(z_hi, pc.z());
      if (pc.z() <= near_z) {
        straddles = true;
      } else {
        const float u = cam.fx * (pc.x() / pc.z()) + cam.cx;
        const float v = cam.fy * (pc.y() / pc.z()) + cam.cy;
        u_lo = std::fmin(u_lo, u);
        u_hi = std::fmax(u_hi, u);
        v_lo = std::fmin(v_lo, v);
        v_hi = std::fmax(v_hi, v);
      }
    }
    if (z_hi <= near_z || z_lo >= far_z) continue;
    int x0 = 0, x1 = cam.width - 1, y0 = 0, y1 = cam.height - 1;
    if (straddles) {
      z_lo = near_z;
    } else {
      if (u_hi < 0.0f || v_hi < 0.0f || u_lo > static_cast<float>(cam.width - 1) ||
          v_lo > static_cast<float>(cam.height - 1)) {
        continue;
      }
      // Here u_hi >= 0 and u_lo <= width - 1: clamping first keeps the conversions in range.
      x0 = static_cast<int>(std::floor(std::fmax(u_lo, 0.0f)));
      x1 = static_cast<int>(std::ceil(std::fmin(u_hi, static_cast<float>(cam.width - 1))));
      y0 = static_cast<int>(std::floor(std::fmax(v_lo, 0.0f)));
      y1 = static_cast<int>(std::ceil(std::fmin(v_hi, static_cast<float>(cam.height - 1))));
    }
    for (int ty = y0 / kRayTileReference; ty <= y1 / kRayTileReference; ++ty) {
      for (int tx = x0 / kRayTileReference; tx <= x1 / kRayTileReference; ++tx) {
        const size_t t = static_cast<size_t>(ty * tb.tiles_x + tx);
        tb.z_min[t] = std::fmin(tb.z_min[t], z_lo);
        tb.z_max[t] = std::fmax(tb.z_max[t], z_hi);
      }
    }
  }
  return tb;
}

namespace {

/// raycast_volume_lanes for one pixel (one lane).
void castPixel(const VolumeHostData& vol, int id, float depth_margin, const TileRanges& tiles,
               const CameraF& cam, const PoseRows& T, const MapOptions& options, int x, int y,
               RaycastImages* out) {
  const VolumeHostView view = vol.view();
  const float voxel_size = vol.voxel_size_m;
  const float truncation = vol.truncation_m;
  const Eigen::Vector3f ray = pixelRay(x, y, cam);
  const Eigen::Vector3f o = T.translation();
  const Eigen::Vector3f d = T.rotate(ray);
  const float current = out->depth.at<float>(y, x);
  const float far_z = static_cast<float>(options.raycast_max_depth_m);
  const size_t tile =
      static_cast<size_t>((y / kRayTileReference) * tiles.tiles_x + x / kRayTileReference);
  float t0 = std::fmax(static_cast<float>(options.raycast_min_depth_m), tiles.z_min[tile]);
  float t1 = std::fmin(far_z, tiles.z_max[tile]);
  if (valid(current)) t1 = std::fmin(t1, current + depth_margin);
  const float block_m = static_cast<float>(kBlockSize) * voxel_size;
  for (int k = 0; k < 3; ++k) {
    if (!clipSlab(o[k], d[k], static_cast<float>(vol.dims_blocks[k]) * block_m, &t0, &t1)) return;
  }
  if (!(t0 < t1)) return;
  const float step_fraction = static_cast<float>(options.raycast_step_fraction);
  const float ray_len = std::sqrt(ray.x() * ray.x() + ray.y() * ray.y() + ray.z() * ray.z());
  const float voxel_t = voxel_size / ray_len;
  const float inv_voxel = 1.0f / voxel_size;
  const float psi_scale = truncation / kTsdfScale;
  const Eigen::Vector3f inv_d(1.0f / d.x(), 1.0f / d.y(), 1.0f / d.z());
  Eigen::Vector3i block(-1, -1, -1);
  int slot = -1;
  bool prev_ok = false;
  float prev_t = 0.0f, prev_psi = 0.0f;
  float t = t0;
  while (t < t1) {
    const Eigen::Vector3f p = o + d * t;
    const float gx = p.x() * inv_voxel, gy = p.y() * inv_voxel, gz = p.z() * inv_voxel;
    if (gx < 0.0f || gy < 0.0f || gz < 0.0f) {
      prev_ok = false;
      t += voxel_t;
      continue;
    }
    const Eigen::Vector3i v(static_cast<int>(gx), static_cast<int>(gy), static_cast<int>(gz));
    const Eigen::Vector3i b = v / kBlockSize;
    if (b != block) {
      block = b;
      slot = inGrid(b, vol.dims_blocks)
                 ? vol.index[static_cast<size_t>(blockLinear(vol.dims_blocks, b))]
                 : -1;
    }
    if (slot < 0) {
      const float te = blockExit(o, d, inv_d, b, block_m, t);
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
    const float psi = static_cast<float>(vox.tsdf_q) * psi_scale;
    if (prev_ok && prev_psi > 0.0f && psi <= 0.0f) {
      float th = prev_t + (t - prev_t) * (prev_psi / (prev_psi - psi));
      Eigen::Vector3f grad(0, 0, 0);
      Eigen::Vector3f ph = o + d * th;
      const float sh = sampleSdf(view, ph, &grad);
      if (!valid(sh)) return;
      const float slope = grad.x() * d.x() + grad.y() * d.y() + grad.z() * d.z();
      if (slope < 0.0f) {
        const float tn = th - sh / slope;
        if (tn > prev_t - voxel_t && tn < t + voxel_t) {
          Eigen::Vector3f gn(0, 0, 0);
          const Eigen::Vector3f pn = o + d * tn;
          if (valid(sampleSdf(view, pn, &gn))) {
            th = tn;
            ph = pn;
            grad = gn;
          }
        }
      }
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
    const TileRanges tb = tileRangesReference(
        *item.volume, cam, PoseRows::from(T_world_camera.inverse() * item.volume->T_world_volume),
        options);
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x)
        castPixel(*item.volume, item.id, item.depth_margin_m, tb, cam, T, options, x, y, &out);
    }
  }
  return out;
}

}  // namespace emf::map
