// Analytic spheres (kernels/geometry/sphere.cl) through the kernels'
// traversal: against a long-double reference on random rays, with spheres
// from 1e-3 to 1e4 in radius and from close by to 1e4 away; any hit against
// closest hit in every traversal; rays spawned from a hit; and a sphere
// resting on triangles.
#include "device/tracer.h"
#include "device_fixture.h"
#include "primitive_checks.h"
#include "geometry/primitives.h"
#include "scene/generators.h"
#include "core/spawn.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace wt {
namespace {

using Real = long double;

struct RefHit {
  Real t = INFINITY;
  std::uint32_t sphere = RayHit::kNoHit;
  Real lineDistance = 0;  ///< from the hit sphere's center to the ray's line
};

/// The nearer root in (tmin, tmax) of every sphere, in long double.
RefHit referenceClosest(const Scene& scene, const Ray& ray, std::uint32_t leaving = RayHit::kNoHit) {
  RefHit best;
  best.t = ray.tmax;
  for (std::uint32_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& s = scene.spheres[i];
    Real f[3], d[3];
    for (int k = 0; k < 3; ++k) f[k] = Real(ray.origin[k]) - Real(s.center[k]), d[k] = ray.direction[k];
    Real a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    Real b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
    Real c = f[0] * f[0] + f[1] * f[1] + f[2] * f[2] - Real(s.radius) * Real(s.radius);
    Real disc = b * b - a * c;
    if (disc < 0) continue;
    Real sq = std::sqrt(disc);
    Real t0 = (-b - sq) / a, t1 = (-b + sq) / a;
    const bool isLeaving = primId(WT_PRIM_SPHERE, i) == leaving;
    if (isLeaving && b >= 0) continue;
    Real t = (!isLeaving && t0 > ray.tmin) ? t0 : t1;
    if (t > ray.tmin && t < best.t) {
      best.t = t;
      best.sphere = i;
      best.lineDistance = std::sqrt(std::max(Real(0), c + Real(s.radius) * Real(s.radius) - b * b / a));
    }
  }
  return best;
}

/// Whether a float ray test may disagree with the exact answer: the line
/// passes within float rounding of the sphere's silhouette.
bool grazes(const Scene& scene, const Ray& ray, std::uint32_t sphere) {
  if (sphere == RayHit::kNoHit) return false;
  const Sphere& s = scene.spheres[sphere];
  Real f[3], d[3];
  for (int k = 0; k < 3; ++k) f[k] = Real(ray.origin[k]) - Real(s.center[k]), d[k] = ray.direction[k];
  Real a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  Real b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
  Real ff = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
  Real line = std::sqrt(std::max(Real(0), ff - b * b / a));
  // float origin, center and direction carry about 1e-7 of their size each
  Real slack = 1e-5L * s.radius + 1e-6L * (std::sqrt(ff) + glm::length(s.center) + glm::length(ray.origin));
  return std::abs(line - Real(s.radius)) <= slack;
}

/// Spheres from 1e-3 to 10 in radius spread over a 100-unit cube, a tiny
/// one 1e4 away, a huge one (radius 1e4) whose surface passes close to the
/// cube, and a sphere of radius 2e-3 beside a sphere of radius 5.
Scene sphereField(std::uint32_t seed) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  scene.materialNames.push_back("grey");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-50.0f, 50.0f), logr(-3.0f, 1.0f);
  for (int i = 0; i < 300; ++i) scene.spheres.push_back({glm::vec3(pos(rng), pos(rng), pos(rng)), std::pow(10.0f, logr(rng)), 0});
  scene.spheres.push_back({glm::vec3(1e4f, 0.0f, 0.0f), 0.01f, 0});
  scene.spheres.push_back({glm::vec3(0.0f, -1e4f - 60.0f, 0.0f), 1e4f, 0});
  scene.spheres.push_back({glm::vec3(5.0f, 5.0f, 60.0f), 5.0f, 0});
  scene.spheres.push_back({glm::vec3(10.002f, 5.0f, 60.0f), 2e-3f, 0});
  return scene;
}

/// Rays from random points aimed near random spheres (many graze them), plus
/// open random rays.
std::vector<Ray> raysAtSpheres(const Scene& scene, std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-70.0f, 70.0f), unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::uniform_int_distribution<std::size_t> pick(0, scene.spheres.size() - 1);
  std::vector<Ray> rays(count);
  for (std::size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    r.origin = glm::vec3(pos(rng), pos(rng), pos(rng));
    const Sphere& s = scene.spheres[pick(rng)];
    glm::vec3 jitter;
    do jitter = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(jitter, jitter) > 1.0f);
    // aim within 1.2 radii of the center: inside, at and just past the silhouette
    glm::vec3 target = s.center + 1.2f * s.radius * jitter;
    if (i % 7 == 0) target = r.origin + glm::vec3(unit(rng), unit(rng), unit(rng));
    r.direction = glm::normalize(target - r.origin);
    if (!(glm::dot(r.direction, r.direction) > 0.5f)) r.direction = glm::vec3(0, 1, 0);
    r.tmin = 0.0f;
    r.tmax = (i % 4 == 1) ? 200.0f * u01(rng) : 1e30f;
  }
  return rays;
}

TEST(Spheres, ClosestHitMatchesLongDoubleReference) {
  const Scene scene = sphereField(1);
  const std::vector<Ray> rays = raysAtSpheres(scene, test::testSize(20000, 500), 2);
  Tracer tracer(test::deviceContext(), scene);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    std::vector<RayHit> hits = tracer.traceClosest(rays, traversal);
    int bad = 0, hitCount = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const RefHit want = referenceClosest(scene, rays[i]);
      const std::uint32_t got = hits[i].prim == RayHit::kNoHit ? RayHit::kNoHit : primIndex(hits[i].prim);
      hitCount += want.sphere != RayHit::kNoHit;
      if (hits[i].prim != RayHit::kNoHit) {
        EXPECT_EQ(primType(hits[i].prim), WT_PRIM_SPHERE);
      }
      bool ok;
      if (got == want.sphere) {
        // the same sphere: t to float precision of the ray's and sphere's coordinates
        const Real scale = glm::length(rays[i].origin) + (got == RayHit::kNoHit ? 0.0f : glm::length(scene.spheres[got].center) + scene.spheres[got].radius);
        // plus the root's sensitivity to the line's distance from the center, which
        // float coordinates know to about 4e-7 of their size: large near a silhouette
        const Real halfChord =
            got == RayHit::kNoHit ? 1 : std::sqrt(std::max(Real(1e-30), Real(scene.spheres[got].radius) * scene.spheres[got].radius -
                                                                            want.lineDistance * want.lineDistance));
        ok = got == RayHit::kNoHit ||
             std::abs(Real(hits[i].t) - want.t) <= 2e-6L * (want.t + scale) + 4e-7L * scale * want.lineDistance / halfChord;
      } else {
        // another answer only where a silhouette is grazed, or two hits tie within rounding
        const Real tGot = got == RayHit::kNoHit ? Real(rays[i].tmax) : Real(hits[i].t);
        ok = grazes(scene, rays[i], want.sphere) || grazes(scene, rays[i], got) ||
             std::abs(tGot - want.t) <= 2e-6L * (want.t + 100);
      }
      if (!ok && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << " (traversal " << int(traversal) << "): kernel sphere " << got << " t=" << hits[i].t
                      << ", reference sphere " << want.sphere << " t=" << double(want.t);
    }
    EXPECT_EQ(bad, 0);
    EXPECT_GT(hitCount, int(rays.size() / 3));  // the rays do find spheres
  }
}

TEST(Spheres, SmallSphereFarAwayKeepsItsHits) {
  // a sphere of radius 1e-2 at 1e4: the textbook discriminant b^2 - ac loses
  // every digit here; aimed within 0.9 radii it must always be hit
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  scene.spheres.push_back({glm::vec3(1e4f, 3.0f, -2.0f), 0.01f, 0});
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 2000; ++i) {
    glm::vec3 j;
    do j = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(j, j) > 1.0f);
    Ray r;
    r.origin = glm::vec3(unit(rng), unit(rng), unit(rng));
    glm::vec3 toCenter = glm::normalize(scene.spheres[0].center - r.origin);
    j -= glm::dot(j, toCenter) * toCenter;  // across the line of sight
    r.direction = glm::normalize(scene.spheres[0].center + 0.9f * 0.01f * j - r.origin);
    rays.push_back(r);
  }
  Tracer tracer(test::deviceContext(), scene);
  int misses = 0;
  for (const RayHit& h : tracer.traceClosest(rays)) misses += h.prim == RayHit::kNoHit;
  EXPECT_EQ(misses, 0);
}

TEST(Spheres, AnyHitAgreesWithClosestHitInEveryTraversal) {
  const Scene scene = sphereField(3);
  const std::vector<Ray> rays = raysAtSpheres(scene, test::testSize(20000, 600), 4);
  Tracer tracer(test::deviceContext(), scene);
  const std::vector<RayHit> closest = tracer.traceClosest(rays);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays, traversal);
    int bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bool hit = closest[i].prim != RayHit::kNoHit;
      if (bool(occluded[i]) == hit) continue;
      // a hit at the segment's very end may go either way
      const RefHit want = referenceClosest(scene, rays[i]);
      if (std::abs(want.t - Real(rays[i].tmax)) <= 1e-5L * rays[i].tmax || grazes(scene, rays[i], want.sphere)) continue;
      if (++bad <= 5)
        ADD_FAILURE() << "ray " << i << " traversal " << int(traversal) << ": occluded " << int(occluded[i])
                      << ", closest hit " << closest[i].prim;
    }
    EXPECT_EQ(bad, 0);
  }
}

/// The origin shade spawns from: the hit reprojected onto the sphere as the
/// kernel does, pushed to `side` (+1 outward, -1 inward) past its rounding error.
glm::vec3 spawnOrigin(const Sphere& s, const Ray& ray, float t, float side) {
  glm::vec3 error, n;
  glm::vec3 p = spherePoint(s.center, s.radius, ray.origin, ray.direction, t, &error, &n);
  return offsetRayOrigin(p, error, side * n);
}

TEST(Spheres, SpawnedRaysLeaveTheSurfaceOrCrossItOnce) {
  const Scene scene = sphereField(6);
  const std::vector<Ray> rays = raysAtSpheres(scene, test::testSize(20000, 600), 7);
  Tracer tracer(test::deviceContext(), scene);
  const std::vector<RayHit> hits = tracer.traceClosest(rays);
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> out, in;
  std::vector<std::uint32_t> from;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].prim == RayHit::kNoHit) continue;
    const Sphere& s = scene.spheres[primIndex(hits[i].prim)];
    glm::vec3 n = glm::normalize(rays[i].origin + hits[i].t * rays[i].direction - s.center);
    glm::vec3 w;
    do w = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(w, w) > 1.0f || glm::dot(w, w) < 1e-3f);
    w = glm::normalize(w);
    if (glm::dot(w, n) < 0.0f) w = -w;
    Ray r;
    r.skip = hits[i].prim;
    r.origin = spawnOrigin(s, rays[i], hits[i].t, 1.0f);
    r.direction = w;  // away from the surface: reflection
    out.push_back(r);
    r.origin = spawnOrigin(s, rays[i], hits[i].t, -1.0f);
    r.direction = -w;  // into the sphere: refraction
    in.push_back(r);
    from.push_back(hits[i].prim);
  }
  ASSERT_GT(from.size(), 100u);
  const std::vector<RayHit> again = tracer.traceClosest(out), through = tracer.traceClosest(in);
  int selfHits = 0, lost = 0, reentered = 0;
  for (std::size_t i = 0; i < from.size(); ++i) {
    selfHits += again[i].prim == from[i];
    // from inside, the ray meets its sphere again at the chord's end (or a sphere inside it first)
    const RefHit want = referenceClosest(scene, in[i], from[i]);
    // (a sphere far smaller than its distance from the origin, whose float
    // surface point is off by a tenth of its radius, can be left along a
    // grazing chord: the reference then finds no hit either)
    const std::uint32_t wantId = want.sphere == RayHit::kNoHit ? RayHit::kNoHit : primId(WT_PRIM_SPHERE, want.sphere);
    reentered += through[i].prim == from[i];
    const bool isLost = through[i].prim != wantId && !grazes(scene, in[i], want.sphere);
    if (isLost && ++lost <= 5)
      ADD_FAILURE() << "ray into sphere " << primIndex(from[i]) << " (radius " << scene.spheres[primIndex(from[i])].radius
                    << "): kernel " << through[i].prim << " t=" << through[i].t << ", reference sphere " << want.sphere
                    << " t=" << double(want.t);
  }
  EXPECT_EQ(selfHits, 0) << "of " << from.size() << " rays leaving a sphere";
  EXPECT_EQ(lost, 0) << "of " << from.size() << " rays entering a sphere";
  EXPECT_GT(reentered, int(0.9 * double(from.size())));  // the rest meet a sphere inside first
}

TEST(Spheres, SphereOnTrianglesLeaksNothing) {
  // a unit sphere resting on a floor of two triangles; rays from above aimed
  // at the contact region must all stop at the sphere or the floor
  Scene scene = makeGrid(1, glm::vec3(0.0f), 10.0f, glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), makeMaterial(glm::vec3(0.5f)));
  scene.spheres.push_back({glm::vec3(0.0f, 1.0f, 0.0f), 1.0f, 0});
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), up(0.2f, 3.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 4000; ++i) {
    Ray r;
    r.origin = glm::vec3(3.0f * unit(rng), up(rng), 3.0f * unit(rng));
    glm::vec3 target(0.05f * unit(rng), 0.02f * std::abs(unit(rng)), 0.05f * unit(rng));
    r.direction = glm::normalize(target - r.origin);
    rays.push_back(r);
  }
  test::expectNoLeaksOnFloor(scene, rays, WT_PRIM_SPHERE);
}

TEST(Spheres, DegenerateSpheresAreLeftOut) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  scene.spheres.push_back({glm::vec3(0.0f), 0.0f, 0});
  scene.spheres.push_back({glm::vec3(0.0f), -1.0f, 0});
  scene.spheres.push_back({glm::vec3(NAN, 0.0f, 0.0f), 1.0f, 0});
  scene.spheres.push_back({glm::vec3(0.0f, 0.0f, -5.0f), 1.0f, 0});
  Tracer tracer(test::deviceContext(), scene);
  EXPECT_EQ(tracer.sceneBuffers().skippedPrimitives(), 3u);
  Ray r;
  r.origin = glm::vec3(0.0f);
  r.direction = glm::vec3(0, 0, -1);
  std::vector<RayHit> hits = tracer.traceClosest(std::span<const Ray>(&r, 1));
  EXPECT_EQ(hits[0].prim, primId(WT_PRIM_SPHERE, 3));
  EXPECT_NEAR(hits[0].t, 4.0f, 1e-5f);
}

}  // namespace
}  // namespace wt
