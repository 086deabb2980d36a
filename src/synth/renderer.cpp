#include "synth/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.h"
#include "synth/parallel.h"

namespace emf::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// One primitive prepared for a frame: the camera centre and rotation in its local frame, and
/// the inclusive pixel rectangle its bounding box projects to.
struct Prepared {
  const PrimitiveGeometry* geometry = nullptr;
  const Material* material = nullptr;
  uint16_t id = 0;
  double R[9];  // R_primitive_camera, row-major
  V3 o;         // camera centre in the primitive frame
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
  double min_depth_m = 0.0;  // no point of the primitive is closer (0 for unbounded ones)
};

V3 rotate(const double* R, V3 d) {
  return {R[0] * d.x + R[1] * d.y + R[2] * d.z, R[3] * d.x + R[4] * d.y + R[5] * d.z,
          R[6] * d.x + R[7] * d.y + R[8] * d.z};
}
V3 rotateTransposed(const double* R, V3 d) {
  return {R[0] * d.x + R[3] * d.y + R[6] * d.z, R[1] * d.x + R[4] * d.y + R[7] * d.z,
          R[2] * d.x + R[5] * d.y + R[8] * d.z};
}

Prepared prepare(const Primitive& prim, const Eigen::Isometry3d& T_world_primitive,
                 const Eigen::Isometry3d& T_world_camera, uint16_t id, const core::Intrinsics& K,
                 double near_m) {
  Prepared p;
  p.geometry = &prim.geometry;
  p.material = &prim.material;
  p.id = id;
  const Eigen::Isometry3d T_primitive_camera = T_world_primitive.inverse() * T_world_camera;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) p.R[r * 3 + c] = T_primitive_camera.linear()(r, c);
  }
  const Eigen::Vector3d o = T_primitive_camera.translation();
  p.o = {o.x(), o.y(), o.z()};

  p.u0 = 0;
  p.u1 = K.width - 1;
  p.v0 = 0;
  p.v1 = K.height - 1;
  V3 h;
  if (!localBounds(prim.geometry, &h)) return p;
  const Eigen::Isometry3d T_camera_primitive = T_primitive_camera.inverse();
  Eigen::Vector3d c[8];
  int behind = 0;  // corners closer than near_m
  double min_depth = kInf;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d corner((k & 1) ? h.x : -h.x, (k & 2) ? h.y : -h.y, (k & 4) ? h.z : -h.z);
    c[k] = T_camera_primitive * corner;
    if (c[k].z() < near_m) ++behind;
    min_depth = std::min(min_depth, c[k].z());
  }
  if (behind == 8) {
    // Wholly closer than near_m (behind the camera, say): no hit can have t >= near_m.
    p.u0 = 0;
    p.u1 = -1;
    return p;
  }
  // The box cut by the near plane is the hull of its corners in front and of the points where
  // its edges cross the plane; its projection is the hull of theirs.
  double umin = kInf, umax = -kInf, vmin = kInf, vmax = -kInf;
  auto extend = [&](const Eigen::Vector3d& q) {
    const double u = K.fx * q.x() / q.z() + K.cx, v = K.fy * q.y() / q.z() + K.cy;
    umin = std::min(umin, u);
    umax = std::max(umax, u);
    vmin = std::min(vmin, v);
    vmax = std::max(vmax, v);
  };
  for (int k = 0; k < 8; ++k) {
    if (c[k].z() < near_m) continue;
    extend(c[k]);
    for (int bit : {1, 2, 4}) {
      const Eigen::Vector3d& b = c[k ^ bit];
      if (b.z() >= near_m) continue;
      const double f = (c[k].z() - near_m) / (c[k].z() - b.z());
      Eigen::Vector3d q = c[k] + f * (b - c[k]);
      q.z() = near_m;
      extend(q);
    }
  }
  // A box straddling the near plane keeps min depth 0 (never skipped, scanned last).
  if (behind == 0) p.min_depth_m = min_depth;
  // The pixel centres inside that hull's bounding rectangle (clamped to the image first: points
  // just in front of the camera project far outside it).
  const double W = K.width, H = K.height;
  p.u0 = static_cast<int>(std::floor(std::clamp(umin, 0.0, W)));
  p.u1 = static_cast<int>(std::ceil(std::clamp(umax, -1.0, W - 1)));
  p.v0 = static_cast<int>(std::floor(std::clamp(vmin, 0.0, H)));
  p.v1 = static_cast<int>(std::ceil(std::clamp(vmax, -1.0, H - 1)));
  return p;
}

/// Z-buffer pass of one primitive over rows [vb, ve) of its rectangle (buffers hold rows
/// vb..ve-1).
template <Shape S>
void scan(const Prepared& p, size_t index, int vb, int ve, int W, const std::vector<double>& xs,
          const std::vector<double>& ys, double near_m, std::vector<double>* zbuf,
          std::vector<int>* winner) {
  const int v_begin = std::max(p.v0, vb), v_end = std::min(p.v1 + 1, ve);
  const V3 col0{p.R[0], p.R[3], p.R[6]};
  for (int v = v_begin; v < v_end; ++v) {
    const size_t row = static_cast<size_t>(v - vb) * static_cast<size_t>(W);
    const double y = ys[static_cast<size_t>(v)];
    // d = R (x, y, 1) = x * column 0 + (y * column 1 + column 2).
    const V3 base{p.R[1] * y + p.R[2], p.R[4] * y + p.R[5], p.R[7] * y + p.R[8]};
    for (int u = p.u0; u <= p.u1; ++u) {
      double& z = (*zbuf)[row + static_cast<size_t>(u)];
      if (z <= p.min_depth_m) continue;  // something closer than all of p is already there
      const double x = xs[static_cast<size_t>(u)];
      const V3 d{base.x + x * col0.x, base.y + x * col0.y, base.z + x * col0.z};
      double t;
      if (intersectShape<S>(*p.geometry, p.o, d, near_m, &t) && t < z) {
        z = t;
        (*winner)[row + static_cast<size_t>(u)] = static_cast<int>(index);
      }
    }
  }
}

}  // namespace

core::Intrinsics defaultIntrinsics(int width, int height) {
  core::Intrinsics k;
  k.fx = k.fy = 525.0;
  k.cx = 319.5;
  k.cy = 239.5;
  k.width = 640;
  k.height = 480;
  return (width == 640 && height == 480) ? k : k.scaled(width, height);
}

Renderer::Renderer(const RenderOptions& options) : options_(options) {
  if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384) {
    throw InvalidArgument("synthetic renderer: image size " + std::to_string(options.width) + "x" +
                          std::to_string(options.height) +
                          " is out of range: use 1..16384 pixels per side");
  }
  K_ = options.intrinsics.valid() ? options.intrinsics
                                  : defaultIntrinsics(options.width, options.height);
  K_.width = options.width;
  K_.height = options.height;
}

void Renderer::render(const Scene& scene, const Eigen::Isometry3d& T_world_camera,
                      const std::vector<Eigen::Isometry3d>& T_world_objects,
                      RenderOutput* out) const {
  if (T_world_objects.size() != scene.objects.size()) {
    throw InvalidArgument("synthetic renderer: scene '" + scene.name + "' has " +
                          std::to_string(scene.objects.size()) + " objects but " +
                          std::to_string(T_world_objects.size()) + " poses were given");
  }
  const int W = K_.width, H = K_.height;
  std::vector<Prepared> prims;
  for (const auto& s : scene.statics) {
    prims.push_back(prepare(s, s.T_parent_primitive, T_world_camera, 0, K_, options_.near_m));
  }
  for (size_t k = 0; k < scene.objects.size(); ++k) {
    const auto& obj = scene.objects[k];
    for (const auto& part : obj.parts) {
      prims.push_back(prepare(part, T_world_objects[k] * part.T_parent_primitive, T_world_camera,
                              static_cast<uint16_t>(obj.id), K_, options_.near_m));
    }
  }
  prims.erase(std::remove_if(prims.begin(), prims.end(),
                             [](const Prepared& p) { return p.u0 > p.u1 || p.v0 > p.v1; }),
              prims.end());
  // Near primitives first, so farther ones can skip pixels already covered by something closer
  // than any of their points; unbounded ones (min depth 0) last as they never skip.
  std::stable_sort(prims.begin(), prims.end(), [](const Prepared& a, const Prepared& b) {
    const double da = a.min_depth_m > 0 ? a.min_depth_m : kInf;
    const double db = b.min_depth_m > 0 ? b.min_depth_m : kInf;
    return da < db;
  });

  std::vector<double> xs(static_cast<size_t>(W)), ys(static_cast<size_t>(H));
  for (int u = 0; u < W; ++u) xs[static_cast<size_t>(u)] = (u - K_.cx) / K_.fx;
  for (int v = 0; v < H; ++v) ys[static_cast<size_t>(v)] = (v - K_.cy) / K_.fy;

  // Key light from above (world frame, towards the light), expressed in the camera frame.
  const Eigen::Vector3d l_world = Eigen::Vector3d(0.35, -0.5, 1.0).normalized();
  const Eigen::Vector3d l_cam_e = T_world_camera.linear().transpose() * l_world;
  const V3 l_cam{l_cam_e.x(), l_cam_e.y(), l_cam_e.z()};

  out->depth.create(H, W, CV_32F);
  out->color.create(H, W, CV_8UC3);
  out->instance_ids.create(H, W, CV_16U);
  out->cos_incidence.create(H, W, CV_32F);
  const double near_m = options_.near_m;

  parallelFor(H, resolveThreads(options_.threads), [&](int vb, int ve) {
    const size_t rows = static_cast<size_t>(ve - vb);
    std::vector<double> zbuf(rows * static_cast<size_t>(W), kInf);
    std::vector<int> winner(rows * static_cast<size_t>(W), -1);
    for (size_t i = 0; i < prims.size(); ++i) {
      const Prepared& p = prims[i];
      switch (p.geometry->shape) {
        case Shape::kPlane:
          scan<Shape::kPlane>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kBox:
          scan<Shape::kBox>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kRoom:
          scan<Shape::kRoom>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kRoundedBox:
          scan<Shape::kRoundedBox>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kSphere:
          scan<Shape::kSphere>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kCylinder:
          scan<Shape::kCylinder>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
        case Shape::kCapsule:
          scan<Shape::kCapsule>(p, i, vb, ve, W, xs, ys, near_m, &zbuf, &winner);
          break;
      }
    }
    for (int v = vb; v < ve; ++v) {
      const size_t row = static_cast<size_t>(v - vb) * static_cast<size_t>(W);
      auto* depth = out->depth.ptr<float>(v);
      auto* color = out->color.ptr<cv::Vec3b>(v);
      auto* ids = out->instance_ids.ptr<uint16_t>(v);
      auto* cosi = out->cos_incidence.ptr<float>(v);
      for (int u = 0; u < W; ++u) {
        const int w = winner[row + static_cast<size_t>(u)];
        if (w < 0) {
          depth[u] = std::numeric_limits<float>::quiet_NaN();
          color[u] = cv::Vec3b(0, 0, 0);
          ids[u] = 0;
          cosi[u] = 0.f;
          continue;
        }
        const Prepared& p = prims[static_cast<size_t>(w)];
        const double t = zbuf[row + static_cast<size_t>(u)];
        const V3 d_cam{xs[static_cast<size_t>(u)], ys[static_cast<size_t>(v)], 1.0};
        const V3 d = rotate(p.R, d_cam);
        const V3 hit = p.o + t * d;
        const V3 n_cam = rotateTransposed(p.R, surfaceNormal(*p.geometry, hit));
        const V3 view = -1.0 * normalized(d_cam);  // towards the camera
        const double c_view = dot(n_cam, view);
        const double shade =
            0.3 + 0.55 * std::max(0.0, dot(n_cam, l_cam)) + 0.25 * std::max(0.0, c_view);
        const auto albedo = albedoAt(*p.material, hit);
        cv::Vec3b bgr;
        for (int c = 0; c < 3; ++c) {
          const double value = 255.0 * albedo[static_cast<size_t>(c)] * shade;
          bgr[c] = cv::saturate_cast<uint8_t>(value);
        }
        depth[u] = static_cast<float>(t);
        color[u] = bgr;
        ids[u] = p.id;
        cosi[u] = static_cast<float>(std::min(1.0, std::fabs(c_view)));
      }
    }
  });
}

}  // namespace emf::synth
