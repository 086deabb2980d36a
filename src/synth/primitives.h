// Analytic signed-distance primitives of the synthetic world and their exact ray intersections.
// Every primitive lives in its own local frame P (centred, axis-aligned); rays are given in P as
// origin o_P + t * d_P with an unnormalised direction, so t is whatever parameter the caller
// chose (the renderer uses camera rays with d_C.z = 1, making t the z-depth in metres).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

namespace emf::synth {

/// Minimal 3-vector for the per-pixel loops (fast in unoptimised sanitizer builds too).
struct V3 {
  double x = 0, y = 0, z = 0;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double norm(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 normalized(V3 a) {
  const double n = norm(a);
  return n > 0 ? (1.0 / n) * a : V3{0, 0, 1};
}

enum class Shape {
  kPlane,       // the half-space z <= 0 (surface z = 0, normal +z); infinite
  kBox,         // |x| <= hx, |y| <= hy, |z| <= hz
  kRoundedBox,  // box of half extents h with edges rounded by radius r (outer extent = h)
  kSphere,      // |p| <= r
  kCylinder,    // x^2 + y^2 <= r^2, |z| <= hz (capped)
  kCapsule,     // points within r of the segment z in [-hz, hz] on the z axis
  kRoom,        // inside-out box: the solid is everything outside |p_i| <= h_i (seen from inside)
};

/// Geometry of one primitive in its local frame. Units: metres.
struct PrimitiveGeometry {
  Shape shape = Shape::kBox;
  V3 half_extents_m{0.5, 0.5, 0.5};  // box, rounded box, room: half extents; cylinder and
                                     // capsule: only .z (half height / half segment length)
  double radius_m = 0.5;             // sphere, cylinder, capsule radius; rounded box edge radius
};

/// Signed distance (metres) from p (frame P) to the primitive's surface, negative inside.
/// Exact for every shape (the room's is the negated box distance).
double signedDistance(const PrimitiveGeometry& g, V3 p);

/// Exact first intersection of the ray o + t d (frame P, d unnormalised) with the primitive's
/// surface for t > t_min, entering the solid from outside (the room: leaving its interior).
/// Returns false when there is none. Rays starting inside a solid (other than the room) miss it.
/// The rounded box is sphere-traced to 1e-7 m inside its bounding box; the rest are closed form.
inline bool intersectRay(const PrimitiveGeometry& g, V3 o, V3 d, double t_min, double* t);

/// The rounded box's intersection (sphere tracing); see intersectRay.
bool intersectRoundedBox(const PrimitiveGeometry& g, V3 o, V3 d, double t_min, double* t);

/// Outward unit normal (frame P) at a surface point p; for the room it points into the room.
V3 surfaceNormal(const PrimitiveGeometry& g, V3 p);

/// Half extents of the local axis-aligned bounding box; false for unbounded shapes (plane,
/// room), which cover the whole image.
bool localBounds(const PrimitiveGeometry& g, V3* half_extents_m);

// ---- closed-form intersections (inline: the renderer calls them per pixel) ------------------

namespace detail {

/// Entry/exit parameters of the ray through the slab box |p_i| <= h_i (t over all reals).
inline bool slabs(V3 h, V3 o, V3 d, double* t_near, double* t_far) {
  double tn = -std::numeric_limits<double>::infinity();
  double tf = std::numeric_limits<double>::infinity();
  auto axis = [&](double hi, double oi, double di) {
    if (di == 0.0) return std::fabs(oi) <= hi;
    const double inv = 1.0 / di;
    const double t1 = (-hi - oi) * inv, t2 = (hi - oi) * inv;
    tn = std::max(tn, std::min(t1, t2));
    tf = std::min(tf, std::max(t1, t2));
    return true;
  };
  if (!axis(h.x, o.x, d.x) || !axis(h.y, o.y, d.y) || !axis(h.z, o.z, d.z)) return false;
  *t_near = tn;
  *t_far = tf;
  return tn <= tf;
}

/// Roots of a t^2 + 2 b t + c = 0 in ascending order (numerically stable form).
inline bool quadratic(double a, double b, double c, double* t0, double* t1) {
  if (a <= 0.0) return false;
  const double disc = b * b - a * c;
  if (disc < 0.0) return false;
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  if (q == 0.0) {
    *t0 = *t1 = 0.0;
    return true;
  }
  const double r0 = q / a, r1 = c / q;
  *t0 = std::min(r0, r1);
  *t1 = std::max(r0, r1);
  return true;
}

inline void keepNearest(double t, double t_min, double* best) {
  if (t > t_min && t < *best) *best = t;
}

/// Sphere of radius r centred at (0, 0, zc), entered from outside.
inline void sphereAt(double r, double zc, V3 o, V3 d, double t_min, double* best) {
  const V3 oc{o.x, o.y, o.z - zc};
  double t0, t1;
  if (!quadratic(dot(d, d), dot(oc, d), dot(oc, oc) - r * r, &t0, &t1)) return;
  if (t0 > t_min) {
    keepNearest(t0, t_min, best);
  } else {
    keepNearest(t1, t_min, best);
  }
}

/// Side of the infinite cylinder x^2 + y^2 = r^2, restricted to |z| <= hz.
inline void cylinderSide(double r, double hz, V3 o, V3 d, double t_min, double* best) {
  double t0, t1;
  if (!quadratic(d.x * d.x + d.y * d.y, o.x * d.x + o.y * d.y, o.x * o.x + o.y * o.y - r * r, &t0,
                 &t1)) {
    return;
  }
  if (std::fabs(o.z + t0 * d.z) <= hz) keepNearest(t0, t_min, best);
  if (std::fabs(o.z + t1 * d.z) <= hz) keepNearest(t1, t_min, best);
}

}  // namespace detail

/// intersectRay for a shape known at compile time (g.shape must be S).
template <Shape S>
inline bool intersectShape(const PrimitiveGeometry& g, V3 o, V3 d, double t_min, double* t) {
  double best = std::numeric_limits<double>::infinity();
  if constexpr (S == Shape::kPlane) {
    if (o.z > 0.0 && d.z < 0.0) detail::keepNearest(-o.z / d.z, t_min, &best);
  } else if constexpr (S == Shape::kBox) {
    double tn, tf;
    if (detail::slabs(g.half_extents_m, o, d, &tn, &tf) && tn > t_min) best = tn;
  } else if constexpr (S == Shape::kRoom) {
    double tn, tf;
    if (detail::slabs(g.half_extents_m, o, d, &tn, &tf) && tn <= t_min && tf > t_min) best = tf;
  } else if constexpr (S == Shape::kRoundedBox) {
    return intersectRoundedBox(g, o, d, t_min, t);
  } else if constexpr (S == Shape::kSphere) {
    if (dot(o, o) < g.radius_m * g.radius_m) return false;
    detail::sphereAt(g.radius_m, 0.0, o, d, t_min, &best);
  } else if constexpr (S == Shape::kCylinder) {
    const double r = g.radius_m, hz = g.half_extents_m.z;
    if (o.x * o.x + o.y * o.y < r * r && std::fabs(o.z) < hz) return false;
    detail::cylinderSide(r, hz, o, d, t_min, &best);
    if (d.z != 0.0) {
      for (double zc : {-hz, hz}) {
        const double tc = (zc - o.z) / d.z;
        const double x = o.x + tc * d.x, y = o.y + tc * d.y;
        if (x * x + y * y <= r * r) detail::keepNearest(tc, t_min, &best);
      }
    }
  } else {
    static_assert(S == Shape::kCapsule, "unhandled shape");
    const double r = g.radius_m, hz = g.half_extents_m.z;
    const double zc = std::clamp(o.z, -hz, hz);
    if (o.x * o.x + o.y * o.y + (o.z - zc) * (o.z - zc) < r * r) return false;
    detail::cylinderSide(r, hz, o, d, t_min, &best);
    detail::sphereAt(r, -hz, o, d, t_min, &best);
    detail::sphereAt(r, hz, o, d, t_min, &best);
  }
  if (!(best < std::numeric_limits<double>::infinity())) return false;
  *t = best;
  return true;
}

inline bool intersectRay(const PrimitiveGeometry& g, V3 o, V3 d, double t_min, double* t) {
  switch (g.shape) {
    case Shape::kPlane:
      return intersectShape<Shape::kPlane>(g, o, d, t_min, t);
    case Shape::kBox:
      return intersectShape<Shape::kBox>(g, o, d, t_min, t);
    case Shape::kRoom:
      return intersectShape<Shape::kRoom>(g, o, d, t_min, t);
    case Shape::kRoundedBox:
      return intersectShape<Shape::kRoundedBox>(g, o, d, t_min, t);
    case Shape::kSphere:
      return intersectShape<Shape::kSphere>(g, o, d, t_min, t);
    case Shape::kCylinder:
      return intersectShape<Shape::kCylinder>(g, o, d, t_min, t);
    case Shape::kCapsule:
      return intersectShape<Shape::kCapsule>(g, o, d, t_min, t);
  }
  return false;
}

}  // namespace emf::synth
