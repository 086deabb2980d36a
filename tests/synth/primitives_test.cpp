// Primitives: signed distances at known points, closed-form ray intersections against an
// independent sphere tracer on the signed distance, normals against the SDF gradient.
#include "synth/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "synth/rng.h"

namespace emf::synth {
namespace {

/// Closed-form intersection vs. sphere-traced reference, metres.
constexpr double kIntersectionToleranceM = 1e-5;
/// Normal vs. finite-difference SDF gradient.
constexpr double kNormalTolerance = 1e-3;

PrimitiveGeometry geometry(Shape shape, V3 h, double r) {
  PrimitiveGeometry g;
  g.shape = shape;
  g.half_extents_m = h;
  g.radius_m = r;
  return g;
}

/// Reference: march the ray with steps of |sdf| / |d| (never overshooting the surface).
bool traceReference(const PrimitiveGeometry& g, V3 o, V3 d, double* t) {
  const double inv = 1.0 / norm(d);
  double s = 0.0;
  for (int i = 0; i < 100000 && s < 100.0; ++i) {
    const double dist = signedDistance(g, o + s * d);
    if (dist < 1e-9) {
      *t = s;
      return true;
    }
    s += std::max(dist, 1e-7) * inv;
  }
  return false;
}

TEST(SynthPrimitives, SignedDistancesAtKnownPoints) {
  const auto box = geometry(Shape::kBox, {1, 2, 3}, 0);
  EXPECT_DOUBLE_EQ(signedDistance(box, {0, 0, 0}), -1.0);
  EXPECT_DOUBLE_EQ(signedDistance(box, {3, 0, 0}), 2.0);
  EXPECT_DOUBLE_EQ(signedDistance(box, {4, 6, 3}), 5.0);  // corner (1,2,3): |(3,4,0)|
  const auto rounded = geometry(Shape::kRoundedBox, {1, 1, 1}, 0.25);
  EXPECT_DOUBLE_EQ(signedDistance(rounded, {2, 0, 0}), 1.0);
  EXPECT_NEAR(signedDistance(rounded, {2, 2, 0}), std::sqrt(2.0) * 1.25 - 0.25, 1e-12);
  const auto sphere = geometry(Shape::kSphere, {0.5, 0.5, 0.5}, 0.5);
  EXPECT_DOUBLE_EQ(signedDistance(sphere, {0, 2, 0}), 1.5);
  const auto cylinder = geometry(Shape::kCylinder, {0, 0, 1}, 0.5);
  EXPECT_DOUBLE_EQ(signedDistance(cylinder, {2, 0, 0}), 1.5);
  EXPECT_DOUBLE_EQ(signedDistance(cylinder, {0, 0, 3}), 2.0);
  EXPECT_DOUBLE_EQ(signedDistance(cylinder, {0, 0, 0.5}), -0.5);
  const auto capsule = geometry(Shape::kCapsule, {0, 0, 1}, 0.5);
  EXPECT_DOUBLE_EQ(signedDistance(capsule, {0, 0, 3}), 1.5);
  EXPECT_DOUBLE_EQ(signedDistance(capsule, {1, 0, 0.3}), 0.5);
  const auto room = geometry(Shape::kRoom, {2, 2, 2}, 0);
  EXPECT_DOUBLE_EQ(signedDistance(room, {0, 0, 0}), 2.0);
  const auto plane = geometry(Shape::kPlane, {0, 0, 0}, 0);
  EXPECT_DOUBLE_EQ(signedDistance(plane, {5, -3, 0.25}), 0.25);
}

TEST(SynthPrimitives, ClosedFormIntersectionsMatchSphereTracing) {
  const PrimitiveGeometry shapes[] = {
      geometry(Shape::kBox, {0.3, 0.2, 0.5}, 0),
      geometry(Shape::kRoundedBox, {0.3, 0.2, 0.5}, 0.08),
      geometry(Shape::kSphere, {0.4, 0.4, 0.4}, 0.4),
      geometry(Shape::kCylinder, {0, 0, 0.3}, 0.25),
      geometry(Shape::kCapsule, {0, 0, 0.3}, 0.2),
      geometry(Shape::kPlane, {0, 0, 0}, 0),
  };
  Rng rng(7);
  for (const auto& g : shapes) {
    int hits = 0, misses = 0;
    for (int i = 0; i < 400; ++i) {
      // Origins on a sphere of radius 2 (above the plane for kPlane), aimed near the centre.
      V3 o{rng.normal(), rng.normal(), rng.normal()};
      o = 2.0 * normalized(o);
      if (g.shape == Shape::kPlane) o.z = std::fabs(o.z) + 0.1;
      const V3 aim{rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6)};
      const V3 d = rng.uniform(0.5, 2.0) * (aim - o);  // unnormalised on purpose
      double t = 0, t_ref = 0;
      const bool hit = intersectRay(g, o, d, 1e-6, &t);
      const bool hit_ref = traceReference(g, o, d, &t_ref);
      // Rays grazing a silhouette can disagree; the reference must then pass within 1e-4 m.
      if (hit != hit_ref) {
        double closest = std::numeric_limits<double>::infinity();
        for (double s = 0; s < 4.0; s += 1e-4)
          closest = std::min(closest, signedDistance(g, o + s * d));
        EXPECT_LT(closest, 1e-4) << "shape " << static_cast<int>(g.shape) << " ray " << i;
        continue;
      }
      if (!hit) {
        ++misses;
        continue;
      }
      ++hits;
      EXPECT_NEAR(t, t_ref, kIntersectionToleranceM / norm(d))
          << "shape " << static_cast<int>(g.shape) << " ray " << i;
      EXPECT_NEAR(signedDistance(g, o + t * d), 0.0, kIntersectionToleranceM);
    }
    EXPECT_GT(hits, 100) << "shape " << static_cast<int>(g.shape);
    if (g.shape != Shape::kPlane) {
      EXPECT_GT(misses, 10) << "shape " << static_cast<int>(g.shape);
    }
  }
}

TEST(SynthPrimitives, RoomIsSeenFromInside) {
  const auto room = geometry(Shape::kRoom, {2, 3, 1.5}, 0);
  double t = 0;
  ASSERT_TRUE(intersectRay(room, {0.5, 0, 0}, {1, 0, 0}, 1e-6, &t));
  EXPECT_DOUBLE_EQ(t, 1.5);
  ASSERT_TRUE(intersectRay(room, {0, 0, 0}, {0, 0.5, 0.5}, 1e-6, &t));
  EXPECT_DOUBLE_EQ(t, 3.0);  // z = 1.5 at t = 3, y = 1.5 < 3
  const V3 n = surfaceNormal(room, {0, 0, 1.5});
  EXPECT_DOUBLE_EQ(n.z, -1.0);  // points into the room
}

TEST(SynthPrimitives, RaysStartingInsideSolidsMiss) {
  double t = 0;
  EXPECT_FALSE(intersectRay(geometry(Shape::kBox, {1, 1, 1}, 0), {0, 0, 0}, {1, 0, 0}, 1e-6, &t));
  EXPECT_FALSE(
      intersectRay(geometry(Shape::kSphere, {1, 1, 1}, 1), {0, 0, 0}, {1, 0, 0}, 1e-6, &t));
  EXPECT_FALSE(
      intersectRay(geometry(Shape::kCapsule, {0, 0, 1}, 0.5), {0, 0, 1.2}, {1, 0, 0}, 1e-6, &t));
  EXPECT_FALSE(
      intersectRay(geometry(Shape::kRoundedBox, {1, 1, 1}, 0.2), {0, 0, 0}, {1, 0, 0}, 1e-6, &t));
}

TEST(SynthPrimitives, NormalsFollowTheSdfGradient) {
  const PrimitiveGeometry shapes[] = {geometry(Shape::kBox, {0.3, 0.2, 0.5}, 0),
                                      geometry(Shape::kRoundedBox, {0.3, 0.2, 0.5}, 0.08),
                                      geometry(Shape::kSphere, {0.4, 0.4, 0.4}, 0.4),
                                      geometry(Shape::kCylinder, {0, 0, 0.3}, 0.25),
                                      geometry(Shape::kCapsule, {0, 0, 0.3}, 0.2)};
  Rng rng(3);
  for (const auto& g : shapes) {
    for (int i = 0; i < 200; ++i) {
      const V3 o = 2.0 * normalized(V3{rng.normal(), rng.normal(), rng.normal()});
      double t = 0;
      if (!intersectRay(g, o, -1.0 * o, 1e-6, &t)) continue;  // aimed at the centre: hits
      const V3 p = o + t * (-1.0 * o);
      const double e = 1e-6;
      const V3 grad =
          normalized(V3{signedDistance(g, p + V3{e, 0, 0}) - signedDistance(g, p - V3{e, 0, 0}),
                        signedDistance(g, p + V3{0, e, 0}) - signedDistance(g, p - V3{0, e, 0}),
                        signedDistance(g, p + V3{0, 0, e}) - signedDistance(g, p - V3{0, 0, e})});
      const V3 n = surfaceNormal(g, p);
      // On box edges the gradient is ambiguous; skip points within 1e-4 of two faces.
      if (g.shape == Shape::kBox) {
        const V3 q{std::fabs(p.x) - g.half_extents_m.x, std::fabs(p.y) - g.half_extents_m.y,
                   std::fabs(p.z) - g.half_extents_m.z};
        const int near_faces = (q.x > -1e-4) + (q.y > -1e-4) + (q.z > -1e-4);
        if (near_faces > 1) continue;
      }
      EXPECT_NEAR(dot(n, grad), 1.0, kNormalTolerance) << "shape " << static_cast<int>(g.shape);
    }
  }
}

}  // namespace
}  // namespace emf::synth
