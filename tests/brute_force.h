// Reference ray/triangle queries for the traversal tests: every triangle, in
// double precision, with Möller-Trumbore (an algorithm independent of the
// kernels' watertight test).
#pragma once

#include "device/tracer.h"
#include "scene/scene.h"

#include <cmath>
#include <limits>

namespace wt::test {

struct BruteHit {
  double t = std::numeric_limits<double>::infinity();
  std::uint32_t triangle = RayHit::kNoHit;
  double minBarycentric = 1.0;  ///< distance to the nearest edge, in barycentric units
};

inline glm::dvec3 vertex(const Scene& s, std::uint32_t i) {
  return glm::dvec3(s.positions[i].x, s.positions[i].y, s.positions[i].z);
}

/// Ray-plane distance and barycentrics of the crossing point, with no inside
/// test; false when the ray is parallel to the triangle's plane.
inline bool triangleParams(const Scene& s, std::uint32_t tri, const Ray& ray, double& t, double& b0,
                           double& b1, double& b2) {
  const WtTriangle& tr = s.triangles[tri];
  glm::dvec3 p0 = vertex(s, tr.v0), p1 = vertex(s, tr.v1), p2 = vertex(s, tr.v2);
  glm::dvec3 o(ray.origin), d(ray.direction);
  glm::dvec3 e1 = p1 - p0, e2 = p2 - p0;
  glm::dvec3 pv = glm::cross(d, e2);
  double det = glm::dot(e1, pv);
  if (det == 0.0) return false;
  double inv = 1.0 / det;
  glm::dvec3 tv = o - p0;
  b1 = glm::dot(tv, pv) * inv;
  glm::dvec3 qv = glm::cross(tv, e1);
  b2 = glm::dot(d, qv) * inv;
  b0 = 1.0 - b1 - b2;
  t = glm::dot(e2, qv) * inv;
  return true;
}

inline BruteHit bruteClosest(const Scene& s, const Ray& ray) {
  BruteHit best;
  for (std::uint32_t i = 0; i < s.triangles.size(); ++i) {
    double t, b0, b1, b2;
    if (!triangleParams(s, i, ray, t, b0, b1, b2)) continue;
    if (b0 < 0.0 || b1 < 0.0 || b2 < 0.0 || !(t > ray.tmin && t < ray.tmax)) continue;
    if (t < best.t) {
      best.t = t;
      best.triangle = i;
      best.minBarycentric = std::min({b0, b1, b2});
    }
  }
  return best;
}

/// True when the kernel's answer agrees with the reference, or differs only
/// where the reference itself is ambiguous at float precision: a tie in t
/// between two triangles, or a ray within kEdge (barycentric) of an edge.
inline bool agrees(const Scene& s, const Ray& ray, const RayHit& got, const BruteHit& want) {
  const double kTie = 1e-5, kEdge = 1e-5;
  auto close = [&](double a, double b) { return std::abs(a - b) <= kTie * std::max(1.0, std::abs(b)); };
  if (got.triangle == want.triangle)
    return got.triangle == RayHit::kNoHit || close(got.t, want.t);
  // the reference hit grazes an edge: missing it is a float-precision call
  if (want.triangle != RayHit::kNoHit && want.minBarycentric < kEdge) return true;
  if (got.triangle == RayHit::kNoHit) return false;
  double t, b0, b1, b2;
  if (!triangleParams(s, got.triangle, ray, t, b0, b1, b2)) return false;
  double minB = std::min({b0, b1, b2});
  if (minB <= -kEdge) return false;  // the kernel's triangle does not contain the hit
  if (want.triangle != RayHit::kNoHit && close(t, want.t)) return true;  // a tie in t
  // a hit within kEdge of an edge that the reference narrowly missed
  return minB < kEdge && (want.triangle == RayHit::kNoHit || t <= want.t * (1 + kTie));
}

}  // namespace wt::test
