#include "synth/primitives.h"

#include <algorithm>
#include <limits>

namespace emf::synth {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Sphere tracing stops this close to the surface (metres).
constexpr double kTraceEpsilonM = 1e-7;
constexpr int kTraceMaxSteps = 256;

double maxComponent(V3 a) { return std::max(a.x, std::max(a.y, a.z)); }
V3 absV(V3 a) { return {std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}; }
V3 maxV(V3 a, double s) { return {std::max(a.x, s), std::max(a.y, s), std::max(a.z, s)}; }

double boxDistance(V3 h, V3 p) {
  const V3 q = absV(p) - h;
  return norm(maxV(q, 0.0)) + std::min(maxComponent(q), 0.0);
}

}  // namespace

double signedDistance(const PrimitiveGeometry& g, V3 p) {
  switch (g.shape) {
    case Shape::kPlane:
      return p.z;
    case Shape::kBox:
      return boxDistance(g.half_extents_m, p);
    case Shape::kRoundedBox: {
      const double r = g.radius_m;
      const V3 inner = g.half_extents_m - V3{r, r, r};
      return boxDistance(inner, p) - r;
    }
    case Shape::kSphere:
      return norm(p) - g.radius_m;
    case Shape::kCylinder: {
      const double dr = std::hypot(p.x, p.y) - g.radius_m;
      const double dz = std::fabs(p.z) - g.half_extents_m.z;
      return std::min(std::max(dr, dz), 0.0) + std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
    }
    case Shape::kCapsule: {
      const double zc = std::clamp(p.z, -g.half_extents_m.z, g.half_extents_m.z);
      return norm(V3{p.x, p.y, p.z - zc}) - g.radius_m;
    }
    case Shape::kRoom:
      return -boxDistance(g.half_extents_m, p);
  }
  return kInf;
}

bool intersectRoundedBox(const PrimitiveGeometry& g, V3 o, V3 d, double t_min, double* t) {
  double tn, tf;
  if (!detail::slabs(g.half_extents_m, o, d, &tn, &tf) || tf <= t_min) return false;
  double s = tn;
  if (tn <= t_min) {  // the ray starts inside the bounding box
    s = t_min;
    if (signedDistance(g, o + s * d) < 0.0) return false;  // ... and inside the solid
  }
  const double inv_len = 1.0 / norm(d);
  for (int i = 0; i < kTraceMaxSteps && s <= tf; ++i) {
    const double dist = signedDistance(g, o + s * d);
    if (dist < kTraceEpsilonM) {
      *t = s;
      return true;
    }
    s += dist * inv_len;
  }
  return false;
}

V3 surfaceNormal(const PrimitiveGeometry& g, V3 p) {
  auto dominantAxis = [](V3 q, V3 sgn) {
    if (q.x >= q.y && q.x >= q.z) return V3{sgn.x, 0, 0};
    if (q.y >= q.z) return V3{0, sgn.y, 0};
    return V3{0, 0, sgn.z};
  };
  const V3 sgn{p.x < 0 ? -1.0 : 1.0, p.y < 0 ? -1.0 : 1.0, p.z < 0 ? -1.0 : 1.0};
  switch (g.shape) {
    case Shape::kPlane:
      return {0, 0, 1};
    case Shape::kBox:
      return dominantAxis(absV(p) - g.half_extents_m, sgn);
    case Shape::kRoom:
      return dominantAxis(absV(p) - g.half_extents_m, -1.0 * sgn);
    case Shape::kRoundedBox: {
      const double r = g.radius_m;
      const V3 q = absV(p) - (g.half_extents_m - V3{r, r, r});
      if (maxComponent(q) <= 0.0) return dominantAxis(q, sgn);
      const V3 m = maxV(q, 0.0);
      return normalized(V3{sgn.x * m.x, sgn.y * m.y, sgn.z * m.z});
    }
    case Shape::kSphere:
      return normalized(p);
    case Shape::kCylinder: {
      const double rho = std::hypot(p.x, p.y);
      const double dr = rho - g.radius_m;
      const double dz = std::fabs(p.z) - g.half_extents_m.z;
      if (dz > dr || rho == 0.0) return {0, 0, sgn.z};
      return {p.x / rho, p.y / rho, 0};
    }
    case Shape::kCapsule: {
      const double zc = std::clamp(p.z, -g.half_extents_m.z, g.half_extents_m.z);
      return normalized(V3{p.x, p.y, p.z - zc});
    }
  }
  return {0, 0, 1};
}

bool localBounds(const PrimitiveGeometry& g, V3* h) {
  switch (g.shape) {
    case Shape::kPlane:
    case Shape::kRoom:
      return false;
    case Shape::kBox:
    case Shape::kRoundedBox:
      *h = g.half_extents_m;
      return true;
    case Shape::kSphere:
      *h = {g.radius_m, g.radius_m, g.radius_m};
      return true;
    case Shape::kCylinder:
      *h = {g.radius_m, g.radius_m, g.half_extents_m.z};
      return true;
    case Shape::kCapsule:
      *h = {g.radius_m, g.radius_m, g.half_extents_m.z + g.radius_m};
      return true;
  }
  return false;
}

}  // namespace emf::synth
