// Curves (kernels/geometry/curve.cl) through the kernels' traversal: against
// a long-double reference of the curves' surface (the boundary of the union
// of the segments' hulls) on random rays, with radii from 1e-3 to 1, wires
// 1e4 times longer than thick and a thin curve 1e4 away; any hit against
// closest hit in every traversal; rays spawned from a hit, outwards and
// inwards; rays aimed at joints of a bent tube; B-spline subdivision and
// degenerate input on the host.
#include "device/scene_buffers.h"
#include "device/tracer.h"
#include "device_fixture.h"
#include "primitive_checks.h"
#include "geometry/primitives.h"
#include "scene/generators.h"
#include "core/spawn.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace wt {
namespace {

using Real = long double;

/// A gathered segment in long double: joints (x, y, z, r).
struct RSeg {
  Real a[4], b[4];
};

std::vector<RSeg> referenceSegments(const PrimitiveRows& rows) {
  std::vector<RSeg> segs((rows.data.size() - rows.dataFirst[WT_PRIM_CURVE]) / 2);
  for (std::uint32_t i = 0; i < segs.size(); ++i) {
    const CurveSegment s = curveSegment(rows, i);
    for (int k = 0; k < 4; ++k) segs[i].a[k] = s.p0[k], segs[i].b[k] = s.p1[k];
  }
  return segs;
}

Real dot3(const Real* x, const Real* y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; }

/// Signed distance from p to the segment's hull (negative inside), and the
/// outward normal of its nearest point.
Real hullDistance(const RSeg& s, const Real p[3], Real n[3] = nullptr) {
  Real e[3], h[3], cr[3];
  for (int k = 0; k < 3; ++k) e[k] = s.b[k] - s.a[k], h[k] = p[k] - s.a[k];
  const Real dr = s.b[3] - s.a[3], l2 = dot3(e, e), g = l2 - dr * dr;
  Real t = dr > 0 ? 1 : 0;
  if (g > 0) {
    cr[0] = h[1] * e[2] - h[2] * e[1], cr[1] = h[2] * e[0] - h[0] * e[2], cr[2] = h[0] * e[1] - h[1] * e[0];
    const Real sg = std::sqrt(g);
    t = std::clamp((dot3(h, e) * sg + dr * std::sqrt(dot3(cr, cr))) / (l2 * sg), Real(0), Real(1));
  }
  Real v[3];
  for (int k = 0; k < 3; ++k) v[k] = h[k] - t * e[k];
  const Real len = std::sqrt(dot3(v, v));
  if (n)
    for (int k = 0; k < 3; ++k) n[k] = len > 0 ? v[k] / len : 0;
  return len - (s.a[3] + t * dr);
}

/// The hull's entry and exit along the ray's line (t in units of the
/// ray's direction), from its spheres and its cone between the circles of
/// contact (the expanded quadratic, with the origin moved next to the segment).
bool hullRoots(const RSeg& s, const Ray& ray, Real* tin, Real* tout) {
  Real o[3], d[3], m[3];
  for (int k = 0; k < 3; ++k) o[k] = ray.origin[k], d[k] = ray.direction[k], m[k] = (s.a[k] + s.b[k]) / 2;
  const Real dd = dot3(d, d);
  Real toMid[3];
  for (int k = 0; k < 3; ++k) toMid[k] = m[k] - o[k];
  const Real tc = dot3(toMid, d) / dd;
  for (int k = 0; k < 3; ++k) o[k] += tc * d[k];
  Real lo = INFINITY, hi = -INFINITY;
  auto take = [&](Real t) { lo = std::min(lo, t), hi = std::max(hi, t); };
  for (const Real* c : {s.a, s.b}) {
    if (!(c[3] > 0)) continue;
    Real f[3];
    for (int k = 0; k < 3; ++k) f[k] = o[k] - c[k];
    const Real b = dot3(f, d), cc = dot3(f, f) - c[3] * c[3], disc = b * b - dd * cc;
    if (disc < 0) continue;
    take((-b - std::sqrt(disc)) / dd), take((-b + std::sqrt(disc)) / dd);
  }
  Real e[3], O[3];
  for (int k = 0; k < 3; ++k) e[k] = s.b[k] - s.a[k], O[k] = o[k] - s.a[k];
  const Real dr = s.b[3] - s.a[3], r0 = s.a[3], l2 = dot3(e, e), g = l2 - dr * dr;
  if (g > 0) {
    const Real dOdP = dot3(d, e), OdP = dot3(O, e);
    const Real A = g * dd - dOdP * dOdP;
    const Real B = g * dot3(O, d) - dOdP * (OdP + r0 * dr);
    const Real C = g * dot3(O, O) - OdP * OdP - r0 * r0 * l2 - 2 * r0 * dr * OdP;
    const Real disc = B * B - A * C;
    if (disc >= 0 && A != 0)
      for (Real sign : {-1.0L, 1.0L}) {
        const Real t = (-B + sign * std::sqrt(disc)) / A;
        const Real y = OdP + t * dOdP;
        if (y >= -r0 * dr && y <= l2 - s.b[3] * dr) take(t);
      }
  }
  if (!(lo <= hi)) return false;
  *tin = tc + lo;
  *tout = tc + hi;
  return true;
}

struct RefHit {
  Real t = INFINITY;
  std::uint32_t segment = RayHit::kNoHit;
  Real cosine = 1;  ///< |cos| between the ray and the surface normal at the hit
};

/// The first crossing of the curves' surface in (tmin, tmax): a hull's
/// entry or exit that lies in no other hull.
RefHit referenceFirst(const std::vector<RSeg>& segs, const Ray& ray) {
  RefHit best;
  best.t = ray.tmax;
  for (std::uint32_t i = 0; i < segs.size(); ++i) {
    Real tin, tout;
    if (!hullRoots(segs[i], ray, &tin, &tout)) continue;
    for (Real t : {tin, tout}) {
      if (!(t > ray.tmin && t < best.t)) continue;
      Real p[3];
      for (int k = 0; k < 3; ++k) p[k] = Real(ray.origin[k]) + t * Real(ray.direction[k]);
      const Real scale = std::fabs(segs[i].a[0]) + std::fabs(segs[i].a[1]) + std::fabs(segs[i].a[2]) + segs[i].a[3];
      bool inside = false;
      for (std::uint32_t j = 0; j < segs.size() && !inside; ++j)
        inside = j != i && hullDistance(segs[j], p) < -1e-9L * scale;
      if (inside) continue;
      best.t = t;
      best.segment = i;
      Real n[3], d[3];
      hullDistance(segs[i], p, n);
      for (int k = 0; k < 3; ++k) d[k] = ray.direction[k];
      best.cosine = std::fabs(dot3(n, d)) / std::sqrt(dot3(d, d));
      break;
    }
  }
  return best;
}

/// Whether the ray's line passes within float rounding of segment i's
/// silhouette: the least hull distance along the line (a convex function
/// of t, found by golden-section search) is about 0.
bool grazes(const std::vector<RSeg>& segs, const Ray& ray, std::uint32_t i) {
  if (i == RayHit::kNoHit) return false;
  const RSeg& s = segs[i];
  auto at = [&](Real t) {
    Real p[3];
    for (int k = 0; k < 3; ++k) p[k] = Real(ray.origin[k]) + t * Real(ray.direction[k]);
    return hullDistance(s, p);
  };
  Real m[3], o[3], d[3];
  for (int k = 0; k < 3; ++k) m[k] = (s.a[k] + s.b[k]) / 2 - ray.origin[k], o[k] = ray.origin[k], d[k] = ray.direction[k];
  Real e[3];
  for (int k = 0; k < 3; ++k) e[k] = s.b[k] - s.a[k];
  const Real reach = std::sqrt(dot3(e, e)) + s.a[3] + s.b[3];
  const Real tc = dot3(m, d) / dot3(d, d), span = 2 * reach / std::sqrt(dot3(d, d));
  Real lo = tc - span, hi = tc + span;
  const Real phi = (std::sqrt(5.0L) - 1) / 2;
  for (int it = 0; it < 200; ++it) {
    const Real x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
    if (at(x1) < at(x2)) hi = x2;
    else lo = x1;
  }
  const Real closest = at((lo + hi) / 2);
  const Real size = std::sqrt(dot3(o, o)) + std::sqrt(dot3(s.a, s.a)) + reach;
  return std::fabs(closest) <= 1e-5L * std::max(s.a[3], s.b[3]) + 2e-6L * size;
}

/// A random walk of `points` joints from `start`, steps of `step`, radii
/// log-uniform in [rLo, rHi] (each joint its own).
void addWalk(Scene& scene, std::mt19937& rng, glm::vec3 start, int points, float step, float rLo, float rHi,
             CurveBasis basis = CurveBasis::kLinear) {
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), logr(std::log10(rLo), std::log10(rHi));
  Curve c;
  c.firstPoint = std::uint32_t(scene.curvePoints.size());
  c.pointCount = std::uint32_t(points);
  c.basis = basis;
  glm::vec3 p = start, dir(1, 0, 0);
  for (int i = 0; i < points; ++i) {
    scene.curvePoints.push_back({p.x, p.y, p.z, std::pow(10.0f, logr(rng))});
    glm::vec3 turn(unit(rng), unit(rng), unit(rng));
    dir = glm::normalize(dir + 0.8f * turn);
    p += step * dir;
  }
  scene.curves.push_back(c);
}

/// Random curves over a 100-unit cube (radii 1e-3 to 1, segments from
/// shorter than thick to 100 times longer), B-splines among them, a wire
/// 1e4 times longer than thick, a thin curve 1e4 away and a tapered one
/// ending in radius 0.
Scene curveField(std::uint32_t seed) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  scene.materialNames.push_back("grey");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-50.0f, 50.0f), logs(-2.0f, 0.7f);
  std::uniform_int_distribution<int> count(2, 9);
  for (int i = 0; i < 60; ++i) {
    const float step = std::pow(10.0f, logs(rng));
    const float r = step * std::pow(10.0f, logs(rng) - 1.2f);
    addWalk(scene, rng, glm::vec3(pos(rng), pos(rng), pos(rng)), count(rng), step, 0.3f * std::min(r, 1.0f),
            std::min(r, 1.0f), i % 5 == 0 ? CurveBasis::kBSpline : CurveBasis::kLinear);
  }
  auto add = [&](std::initializer_list<glm::vec4> points) {
    Curve c;
    c.firstPoint = std::uint32_t(scene.curvePoints.size());
    c.pointCount = std::uint32_t(points.size());
    for (const glm::vec4& p : points) scene.curvePoints.push_back({p.x, p.y, p.z, p.w});
    scene.curves.push_back(c);
  };
  add({{-40, 10, 5, 0.005f}, {40, 12, 5, 0.005f}, {40, 12, -45, 0.004f}});          // a wire
  add({{1e4f, 3, 0, 0.01f}, {1e4f, 3.2f, 0.1f, 0.012f}, {1e4f, 3.3f, 0.3f, 0.01f}});  // far away
  add({{5, -5, 30, 0.5f}, {6, -4, 31, 0.3f}, {7, -3.5f, 31.5f, 0.1f}, {8, -3, 32, 0.0f}});  // tapered
  return scene;
}

/// Rays from random points aimed near random segments (many graze them),
/// plus open random rays.
std::vector<Ray> raysAtCurves(const PrimitiveRows& rows, std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-70.0f, 70.0f), unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  const std::size_t segments = rows.ids.size();
  std::uniform_int_distribution<std::size_t> pick(0, segments - 1);
  std::vector<Ray> rays(count);
  for (std::size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    r.origin = glm::vec3(pos(rng), pos(rng), pos(rng));
    const CurveSegment s = curveSegment(rows, primIndex(rows.ids[pick(rng)]));
    const float along = u01(rng);
    const glm::vec4 c = s.p0 + along * (s.p1 - s.p0);
    glm::vec3 jitter;
    do jitter = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(jitter, jitter) > 1.0f);
    // within 1.2 radii of a point on the axis: inside, at and just past the silhouette
    glm::vec3 target = glm::vec3(c) + 1.2f * c.w * jitter;
    if (glm::length(glm::vec3(c)) > 1e3f) r.origin *= 0.01f;  // the far curve from near the origin
    if (i % 7 == 0) target = r.origin + glm::vec3(unit(rng), unit(rng), unit(rng));
    r.direction = glm::normalize(target - r.origin);
    if (!(glm::dot(r.direction, r.direction) > 0.5f)) r.direction = glm::vec3(0, 1, 0);
    r.tmin = 0.0f;
    r.tmax = (i % 4 == 1) ? 200.0f * u01(rng) : 1e30f;
  }
  return rays;
}

/// The kernel's answer for a ray against the reference: the same t (to float
/// precision, more where the ray meets the surface at a grazing angle), or
/// another answer only where a silhouette is grazed.
bool agrees(const std::vector<RSeg>& segs, const Ray& ray, const RayHit& hit, const RefHit& want, std::string* why) {
  const std::uint32_t got = hit.prim == RayHit::kNoHit ? RayHit::kNoHit : primIndex(hit.prim);
  const Real tGot = got == RayHit::kNoHit ? Real(ray.tmax) : Real(hit.t);
  Real scale = glm::length(ray.origin);
  for (std::uint32_t i : {got, want.segment})
    if (i != RayHit::kNoHit) scale += std::sqrt(dot3(segs[i].a, segs[i].a)) + segs[i].a[3] + segs[i].b[3];
  const bool bothMiss = got == RayHit::kNoHit && want.segment == RayHit::kNoHit;
  const Real tol = 2e-6L * (std::fabs(want.t) + scale) + 4e-7L * scale / std::max(want.cosine, Real(1e-9));
  if (bothMiss || (got != RayHit::kNoHit && want.segment != RayHit::kNoHit && std::fabs(tGot - want.t) <= tol))
    return true;
  if (grazes(segs, ray, want.segment) || grazes(segs, ray, got)) return true;
  *why = "kernel segment " + std::to_string(got) + " t=" + std::to_string(double(tGot)) + ", reference segment " +
         std::to_string(want.segment) + " t=" + std::to_string(double(want.t)) + " (cos " +
         std::to_string(double(want.cosine)) + ")";
  return false;
}

TEST(Curves, ClosestHitMatchesLongDoubleReference) {
  const Scene scene = curveField(1);
  const PrimitiveRows rows = gatherPrimitives(scene);
  const std::vector<RSeg> segs = referenceSegments(rows);
  const std::vector<Ray> rays = raysAtCurves(rows, test::testSize(6000, 300), 2);
  // the walks' nodes low in the tree are oriented (WT_BVH4_ORIENTED), so the rays cross frames too
  const PrimitiveTree tree = buildPrimitiveTree(rows, BvhBuildOptions{});
  std::size_t oriented = 0;
  for (std::size_t n = 0; n < tree.bvh4.nodes.size(); ++n) {
    const WtBvh4Node& node = tree.bvh4.nodes[n];
    for (int k = 0; k < 4; ++k) oriented += node.child[k] != WT_BVH4_EMPTY && node.count[k] == 0 && (node.child[k] & WT_BVH4_ORIENTED);
    if (oriented > 0) break;
  }
  EXPECT_GT(oriented, 0u);
  Tracer tracer(test::deviceContext(), scene);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    std::vector<RayHit> hits = tracer.traceClosest(rays, traversal);
    int bad = 0, hitCount = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const RefHit want = referenceFirst(segs, rays[i]);
      hitCount += want.segment != RayHit::kNoHit;
      if (hits[i].prim != RayHit::kNoHit) {
        EXPECT_EQ(primType(hits[i].prim), WT_PRIM_CURVE);
      }
      std::string why;
      if (!agrees(segs, rays[i], hits[i], want, &why) && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << " (traversal " << int(traversal) << "): " << why;
    }
    EXPECT_EQ(bad, 0);
    EXPECT_GT(hitCount, int(rays.size() / 3));  // the rays do find curves
  }
}

TEST(Curves, ThinCurveFarAwayKeepsItsHits) {
  // a curve of radius 1e-2 at 1e4 seen from near the origin, and a wire
  // 1e4 times longer than thick: aimed within 0.9 radii of the axis, every
  // ray must hit
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  auto add = [&](glm::vec4 a, glm::vec4 b) {
    scene.curves.push_back({std::uint32_t(scene.curvePoints.size()), 2, 0, CurveBasis::kLinear});
    scene.curvePoints.push_back({a.x, a.y, a.z, a.w});
    scene.curvePoints.push_back({b.x, b.y, b.z, b.w});
  };
  add({1e4f, 3.0f, -2.0f, 0.01f}, {1e4f, 3.5f, -2.1f, 0.012f});
  add({-50.0f, -5.0f, -20.0f, 0.01f}, {50.0f, -5.0f, -20.0f, 0.01f});
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 4000; ++i) {
    const WtVec4 p0 = scene.curvePoints[2 * (i % 2)], p1 = scene.curvePoints[2 * (i % 2) + 1];
    const float s = u01(rng);
    const glm::vec3 axis = glm::vec3(p1.x, p1.y, p1.z) - glm::vec3(p0.x, p0.y, p0.z);
    const glm::vec3 c = glm::vec3(p0.x, p0.y, p0.z) + s * axis;
    const float r = p0.w + s * (p1.w - p0.w);
    Ray ray;
    ray.origin = glm::vec3(unit(rng), unit(rng), unit(rng));
    glm::vec3 toAxis = glm::normalize(c - ray.origin);
    // across the line of sight and the axis: the direction in which the tube is thinnest
    glm::vec3 across = glm::cross(toAxis, glm::normalize(axis));
    if (glm::length(across) < 1e-3f) across = glm::vec3(0, 0, 1);
    ray.direction = glm::normalize(c + 0.9f * r * unit(rng) * glm::normalize(across) - ray.origin);
    rays.push_back(ray);
  }
  Tracer tracer(test::deviceContext(), scene);
  int misses = 0;
  for (const RayHit& h : tracer.traceClosest(rays)) misses += h.prim == RayHit::kNoHit;
  EXPECT_EQ(misses, 0);
}

TEST(Curves, AnyHitAgreesWithClosestHitInEveryTraversal) {
  const Scene scene = curveField(3);
  const PrimitiveRows rows = gatherPrimitives(scene);
  const std::vector<RSeg> segs = referenceSegments(rows);
  const std::vector<Ray> rays = raysAtCurves(rows, test::testSize(20000, 600), 4);
  Tracer tracer(test::deviceContext(), scene);
  const std::vector<RayHit> closest = tracer.traceClosest(rays);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays, traversal);
    int bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bool hit = closest[i].prim != RayHit::kNoHit;
      if (bool(occluded[i]) == hit) continue;
      // a hit at the segment's very end may go either way
      const RefHit want = referenceFirst(segs, rays[i]);
      if (std::abs(want.t - Real(rays[i].tmax)) <= 1e-5L * rays[i].tmax || grazes(segs, rays[i], want.segment)) continue;
      if (++bad <= 5)
        ADD_FAILURE() << "ray " << i << " traversal " << int(traversal) << ": occluded " << int(occluded[i])
                      << ", closest hit " << closest[i].prim;
    }
    EXPECT_EQ(bad, 0);
  }
}

using test::Spawned;
using test::spawnFrom;

TEST(Curves, SpawnedRaysLeaveTheSurfaceOrCrossItOnce) {
  const Scene scene = curveField(6);
  const PrimitiveRows rows = gatherPrimitives(scene);
  const std::vector<RSeg> segs = referenceSegments(rows);
  const std::vector<Ray> rays = raysAtCurves(rows, test::testSize(8000, 400), 7);
  Tracer tracer(test::deviceContext(), scene);
  const std::vector<RayHit> hits = tracer.traceClosest(rays);
  const Spawned s = spawnFrom(rows, rays, hits, 8);
  ASSERT_GT(s.from.size(), 100u);
  const std::vector<RayHit> again = tracer.traceClosest(s.out), through = tracer.traceClosest(s.in);
  int selfHits = 0, badOut = 0, badIn = 0, reentered = 0;
  for (std::size_t i = 0; i < s.from.size(); ++i) {
    selfHits += again[i].prim == s.from[i];
    reentered += through[i].prim == s.from[i];
    std::string why;
    // where the reference itself crosses a surface within rounding of the
    // start (a joint's crease), either answer holds
    const RSeg& from = segs[primIndex(s.from[i])];
    const Real start = 1e-4L * std::max(from.a[3], from.b[3]) +
                       4e-6L * (glm::length(s.out[i].origin) + std::sqrt(dot3(from.a, from.a)));
    // outwards: what the reference meets past the start (a neighbour across
    // a bend may be met legitimately, at any distance)
    const RefHit wantOut = referenceFirst(segs, s.out[i]);
    if (wantOut.t > start && !agrees(segs, s.out[i], again[i], wantOut, &why) && ++badOut <= 5)
      ADD_FAILURE() << "ray out of segment " << primIndex(s.from[i]) << ": " << why;
    // inwards: the wall on the far side, or another curve inside this one
    // (a neighbour's wall within rounding of the start may be met there)
    const RefHit wantIn = referenceFirst(segs, s.in[i]);
    const bool nearStart = through[i].prim != RayHit::kNoHit && through[i].t <= start;
    if (wantIn.t > start && !nearStart && !agrees(segs, s.in[i], through[i], wantIn, &why) && ++badIn <= 5)
      ADD_FAILURE() << "ray into segment " << primIndex(s.from[i]) << ": " << why;
  }
  EXPECT_EQ(selfHits, 0) << "of " << s.from.size() << " rays leaving a curve";
  EXPECT_EQ(badOut, 0) << "of " << s.from.size() << " rays leaving a curve";
  EXPECT_EQ(badIn, 0) << "of " << s.from.size() << " rays entering a curve";
  EXPECT_GT(reentered, int(0.5 * double(s.from.size())));  // the rest leave through a neighbour's wall
  // any hit inwards (a shadow ray through the fibre; bvh_prims_occluded tests the segment it leaves first):
  // nothing before half the closest hit's distance, something before 1.5 times it
  std::vector<Ray> shortRays, longRays;
  for (std::size_t i = 0; i < s.from.size(); ++i) {
    if (through[i].prim == RayHit::kNoHit || !(through[i].t > 0.0f)) continue;
    Ray a = s.in[i], b = s.in[i];
    a.tmax = 0.5f * through[i].t, b.tmax = 1.5f * through[i].t;
    shortRays.push_back(a), longRays.push_back(b);
  }
  ASSERT_GT(shortRays.size(), 100u);
  const std::vector<std::uint8_t> shortBlocked = tracer.traceOccluded(shortRays, Traversal::kSingle),
                                  longBlocked = tracer.traceOccluded(longRays, Traversal::kSingle);
  int wrongShort = 0, wrongLong = 0;
  for (std::size_t i = 0; i < shortRays.size(); ++i) wrongShort += shortBlocked[i] != 0, wrongLong += longBlocked[i] == 0;
  EXPECT_EQ(wrongShort, 0) << "of " << shortRays.size() << " rays into a curve, blocked before its closest hit";
  EXPECT_EQ(wrongLong, 0) << "of " << longRays.size() << " rays into a curve, not blocked past its closest hit";
}

TEST(Curves, PacketsMatchSingleRaysAtCurveEnds) {
  const Scene scene = curveField(8);
  const PrimitiveRows rows = gatherPrimitives(scene);
  Tracer tracer(test::deviceContext(), scene);
  test::expectCurvePacketsMatchSingleRays(
      tracer, rows, test::raysAtCurveEnds(rows, test::testSize(400, 60), tracer.packetWidth(), 9));
}

/// A bent tube: `joints` joints on a helix of radius 1.5 and pitch 2.5,
/// turning by 6 to 52 degrees at each joint, radii varying smoothly between
/// 0.2 and 0.35; only neighbours' hulls overlap.
Scene bentTube(int joints) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  Curve c;
  c.pointCount = std::uint32_t(joints);
  float angle = 0.0f;
  for (int i = 0; i < joints; ++i) {
    const float r = 0.275f + 0.075f * std::sin(0.7f * float(i));
    scene.curvePoints.push_back({1.5f * std::cos(angle), 2.5f * angle / (2.0f * 3.14159265f), 1.5f * std::sin(angle), r});
    angle += 0.5f + 0.4f * std::sin(float(i));
  }
  scene.curves.push_back(c);
  return scene;
}

TEST(Curves, RaysAtJointsNeverLeakThroughATube) {
  const Scene scene = bentTube(40);
  const PrimitiveRows rows = gatherPrimitives(scene);
  ASSERT_EQ(rows.ids.size(), 39u);
  const std::vector<RSeg> segs = referenceSegments(rows);
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> joint(1, 38);
  std::vector<Ray> rays, inside;
  for (int i = 0; i < int(test::testSize(6000, 300)); ++i) {
    const WtVec4 j = scene.curvePoints[joint(rng)];
    glm::vec3 jitter;
    do jitter = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(jitter, jitter) > 1.0f);
    const glm::vec3 target = glm::vec3(j.x, j.y, j.z) + 0.95f * j.w * jitter;
    Ray r;
    glm::vec3 from;
    do from = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(from, from) > 1.0f || glm::dot(from, from) < 0.1f);
    // from outside, at any distance up to 20 tube lengths, and from the joint itself
    r.origin = target + (i % 2 ? 20.0f : 1.5f) * glm::normalize(from);
    r.direction = glm::normalize(target - r.origin);
    rays.push_back(r);
    r.origin = target;
    r.direction = glm::normalize(from);
    inside.push_back(r);
  }
  Tracer tracer(test::deviceContext(), scene);
  for (const std::vector<Ray>* set : {&rays, &inside}) {
    const std::vector<RayHit> hits = tracer.traceClosest(*set);
    int leaks = 0, bad = 0;
    for (std::size_t i = 0; i < set->size(); ++i) {
      const Ray& r = (*set)[i];
      if (hits[i].prim == RayHit::kNoHit) {
        if (++leaks <= 5) ADD_FAILURE() << (set == &rays ? "ray from outside" : "ray from inside") << " " << i << " leaked";
        continue;
      }
      // the hit is the tube's surface, not a wall inside it
      Real p[3];
      for (int k = 0; k < 3; ++k) p[k] = Real(r.origin[k]) + Real(hits[i].t) * Real(r.direction[k]);
      Real deepest = INFINITY;
      for (const RSeg& s : segs) deepest = std::min(deepest, hullDistance(s, p));
      if (std::fabs(deepest) > 1e-5L && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << " hit at distance " << double(deepest) << " from the tube's surface";
    }
    EXPECT_EQ(leaks, 0);
    EXPECT_EQ(bad, 0);
  }
  // any hit: every ray blocked, in every traversal
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    int open = 0;
    for (std::uint8_t b : tracer.traceOccluded(rays, traversal)) open += b == 0;
    EXPECT_EQ(open, 0) << "traversal " << int(traversal);
  }
}

TEST(Curves, RaysLeavingAStraightTubeMeetNothingAndRaysEnteringItMeetItsFarWall) {
  // a capsule of 16 collinear segments is convex: a ray spawned outwards
  // meets nothing, one spawned inwards meets the far wall once (the joints
  // inside it are not walls). Far from the origin the float joints are no
  // longer in line (a segment 1e4 times shorter than its distance tilts by
  // 1e-3): there both sets must agree with the reference of those joints.
  for (auto [scale, offset] : {std::pair{1e-3f, 0.0f}, std::pair{1.0f, 0.0f}, std::pair{1e3f, 0.0f},
                                std::pair{0.1f, 1e3f}, std::pair{1.0f, 1e4f}, std::pair{1e3f, 1e4f}}) {
    Scene scene;
    scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
    Curve c;
    c.pointCount = 17;
    const glm::vec3 base(offset, -0.5f * offset, 0.25f * offset);
    const glm::vec3 axis = glm::normalize(glm::vec3(1.0f, 0.3f, -0.2f));
    for (int i = 0; i < 17; ++i) {
      const glm::vec3 p = base + scale * (float(i) - 8.0f) * axis;
      scene.curvePoints.push_back({p.x, p.y, p.z, 0.4f * scale});
    }
    scene.curves.push_back(c);
    const PrimitiveRows rows = gatherPrimitives(scene);
    const std::vector<RSeg> segs = referenceSegments(rows);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < 3000; ++i) {
      glm::vec3 from;
      do from = glm::vec3(unit(rng), unit(rng), unit(rng));
      while (glm::dot(from, from) > 1.0f || glm::dot(from, from) < 0.1f);
      Ray r;
      // aimed at the axis, often at a joint
      const float along = i % 2 ? std::round(8.0f * unit(rng)) : 8.0f * unit(rng);
      const glm::vec3 target = base + scale * along * axis + 0.3f * scale * glm::vec3(unit(rng), unit(rng), unit(rng));
      r.origin = target + 3.0f * scale * glm::normalize(from);
      r.direction = glm::normalize(target - r.origin);
      rays.push_back(r);
    }
    Tracer tracer(test::deviceContext(), scene);
    const std::vector<RayHit> hits = tracer.traceClosest(rays);
    // (a ray along the wall within rounding of it may leave at once either way)
    const Spawned s = spawnFrom(rows, rays, hits, 14, 1e-2f);
    ASSERT_GT(s.from.size(), 1000u);
    const std::vector<RayHit> out = tracer.traceClosest(s.out), in = tracer.traceClosest(s.in);
    const std::vector<std::uint8_t> outBlocked = tracer.traceOccluded(s.out, Traversal::kStream);
    const bool inLine = offset == 0.0f;
    int offWall = 0, bounced = 0, lost = 0, bad = 0;
    for (std::size_t i = 0; i < s.from.size(); ++i) {
      bounced += out[i].prim != RayHit::kNoHit || outBlocked[i] != 0;
      lost += in[i].prim == RayHit::kNoHit;
      std::string why;
      for (const auto& [ray, hit, what] : {std::tuple{s.out[i], out[i], "out of"}, std::tuple{s.in[i], in[i], "into"}})
        if (!agrees(segs, ray, hit, referenceFirst(segs, ray), &why) && ++bad <= 5)
          ADD_FAILURE() << "scale " << scale << " at " << offset << ": ray " << what << " segment " << primIndex(s.from[i])
                        << ": " << why;
      if (in[i].prim == RayHit::kNoHit || !inLine) continue;
      // the far wall: the exit point lies on the capsule's surface, across its axis
      const glm::vec3 p = s.in[i].origin + in[i].t * s.in[i].direction;
      const glm::vec3 rel = p - base;
      const float along = glm::dot(rel, axis);
      const float across = glm::length(rel - along * axis);
      const float ends = std::max(std::fabs(along) - 8.0f * scale, 0.0f);
      const float surface = std::sqrt(across * across + ends * ends) - 0.4f * scale;
      offWall += std::fabs(surface) > 1e-5f * scale;
    }
    EXPECT_EQ(bad, 0) << "scale " << scale << " at " << offset;
    if (inLine) {
      EXPECT_EQ(bounced, 0) << "scale " << scale;
      EXPECT_EQ(lost, 0) << "scale " << scale;
      EXPECT_EQ(offWall, 0) << "scale " << scale << ": exits not on the far wall";
    }
  }
}

TEST(Curves, CurveOnTrianglesAndSpheresLeaksNothing) {
  // a hair of ten segments lying on a floor of two triangles beside a
  // sphere; rays aimed at the contacts stop at one of the three
  Scene scene = makeGrid(1, glm::vec3(0.0f), 10.0f, glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), makeMaterial(glm::vec3(0.5f)));
  scene.spheres.push_back({glm::vec3(2.6f, 0.5f, 0.0f), 0.5f, 0});
  Curve c;
  c.pointCount = 11;
  for (int i = 0; i < 11; ++i) scene.curvePoints.push_back({-2.0f + 0.4f * float(i), 0.05f, 0.02f * float(i % 2), 0.05f});
  scene.curves.push_back(c);
  std::mt19937 rng(15);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), up(0.2f, 3.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 4000; ++i) {
    Ray r;
    r.origin = glm::vec3(3.0f * unit(rng), up(rng), 3.0f * unit(rng));
    const glm::vec3 target(2.0f * unit(rng), 0.04f * std::abs(unit(rng)), 0.06f * unit(rng));
    r.direction = glm::normalize(target - r.origin);
    rays.push_back(r);
  }
  test::expectNoLeaksOnFloor(scene, rays, WT_PRIM_CURVE);
}

TEST(Curves, DegenerateInputIsLeftOutOrMerged) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  auto add = [&](std::initializer_list<glm::vec4> points, CurveBasis basis = CurveBasis::kLinear) {
    Curve c;
    c.firstPoint = std::uint32_t(scene.curvePoints.size());
    c.pointCount = std::uint32_t(points.size());
    c.basis = basis;
    for (const glm::vec4& p : points) scene.curvePoints.push_back({p.x, p.y, p.z, p.w});
    scene.curves.push_back(c);
  };
  add({{0, 0, -5, 0}, {1, 0, -5, 0}});                         // radius 0: invisible, left out
  add({{0, 0, -5, 0.1f}, {NAN, 0, -5, 0.1f}, {2, 0, -5, 0.1f}});  // NaN: both segments left out
  add({{0, 0, -5, 0.1f}, {1, 0, -5, -1.0f}});                  // negative radius
  add({{0, 0, -5, 0.1f}, {0, 0, -5, 0.3f}, {0, 0, -5, 0.2f}});   // one point thrice: nothing to trace
  add({{0, 0, -5, 0.1f}, {0, 0, -5, 0.1f}, {INFINITY, 0, 0, 1}, {1, 1, 1, 1}}, CurveBasis::kBSpline);
  add({{-1, 0, -4, 0.5f}, {-1, 0, -4, 0.5f}, {1, 0, -4, 0.5f}, {1, 0, -4, 0.5f}});  // coincident pairs: one segment
  add({{0, 0, -8, 0.5f}});                                      // a single point: no segment
  const PrimitiveRows rows = gatherPrimitives(scene);
  EXPECT_EQ(rows.ids.size(), 1u);
  EXPECT_EQ(rows.count[WT_PRIM_CURVE], 1u + 2u + 1u + 0u + 1u + 1u);
  EXPECT_EQ(rows.skipped, 1u + 2u + 1u + 0u + 1u);
  const CurveSegment s = curveSegment(rows, 0);
  EXPECT_EQ(s.curve, 5u);
  EXPECT_FALSE(s.left);
  EXPECT_FALSE(s.right);
  Tracer tracer(test::deviceContext(), scene);
  EXPECT_EQ(tracer.sceneBuffers().skippedPrimitives(), rows.skipped);
  Ray r;
  r.origin = glm::vec3(0.0f);
  r.direction = glm::vec3(0, 0, -1);
  std::vector<RayHit> hits = tracer.traceClosest(std::span<const Ray>(&r, 1));
  EXPECT_EQ(hits[0].prim, primId(WT_PRIM_CURVE, 0));
  EXPECT_NEAR(hits[0].t, 3.5f, 1e-5f);
}

/// The uniform cubic B-spline of 4-D points c at parameter u in [0, 1]
/// over its segments.
glm::dvec4 bspline(const std::vector<glm::dvec4>& c, double u) {
  const double x = u * double(c.size() - 3);
  const std::size_t i = std::min<std::size_t>(std::size_t(x), c.size() - 4);
  const double t = x - double(i), t2 = t * t, t3 = t2 * t;
  return ((1 - t) * (1 - t) * (1 - t) * c[i] + (3 * t3 - 6 * t2 + 4) * c[i + 1] +
          (-3 * t3 + 3 * t2 + 3 * t + 1) * c[i + 2] + t3 * c[i + 3]) / 6.0;
}

TEST(CurveGather, BSplinesAreSubdividedToTheirFlatness) {
  // a wavy B-spline: the joints lie on the spline, the spline within
  // kCurveFlatness of its radius from the segments, and its ends are the
  // spline's ends
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  Curve c;
  c.basis = CurveBasis::kBSpline;
  std::vector<glm::dvec4> control;
  for (int i = 0; i < 12; ++i) {
    const glm::vec4 p(float(i), std::sin(1.3f * float(i)) * 2.0f, std::cos(0.9f * float(i)), 0.05f + 0.02f * float(i % 3));
    scene.curvePoints.push_back({p.x, p.y, p.z, p.w});
    control.push_back(glm::dvec4(p));
  }
  c.pointCount = 12;
  scene.curves.push_back(c);
  const PrimitiveRows rows = gatherPrimitives(scene);
  const std::size_t n = rows.ids.size();
  ASSERT_GT(n, 9u * 4u);
  EXPECT_EQ(rows.skipped, 0u);
  for (std::uint32_t i = 0; i < n; ++i) {
    const CurveSegment s = curveSegment(rows, i);
    EXPECT_EQ(s.left, i > 0);
    EXPECT_EQ(s.right, i + 1 < n);
    for (const auto& [p, u] : {std::pair{s.p0, s.u0}, std::pair{s.p1, s.u1}}) {
      const glm::dvec4 want = bspline(control, u);
      EXPECT_LT(glm::length(glm::dvec4(p) - want), 1e-5) << "segment " << i << " u " << u;
    }
    // the spline between the joints stays near the segment (position and radius)
    for (int k = 1; k < 8; ++k) {
      const double f = k / 8.0;
      const glm::dvec4 on = bspline(control, s.u0 + f * (s.u1 - s.u0));
      const glm::dvec4 chord = glm::dvec4(s.p0) + f * (glm::dvec4(s.p1) - glm::dvec4(s.p0));
      EXPECT_LE(glm::length(on - chord), kCurveFlatness * std::min(s.p0.w, s.p1.w) * 1.01 + 1e-6) << "segment " << i;
    }
  }
  EXPECT_FLOAT_EQ(curveSegment(rows, 0).u0, 0.0f);
  EXPECT_FLOAT_EQ(curveSegment(rows, std::uint32_t(n - 1)).u1, 1.0f);
}

}  // namespace
}  // namespace wt
