// Instances of spheres and curves (WT_INSTANCE_PRIMITIVES,
// kernels/bvh_prims.cl): a set of spheres and curves placed several times
// is stored once, the ray moved into each copy's object space. The
// instanced form against the flattened one (Instancing::Off): the same hits
// on random rays in every traversal mode, spawned rays that never meet the
// surface they leave, the same image within noise, and the memory it saves.
#include "../render/render_helpers.h"
#include "core/spawn.h"
#include "device/scene_buffers.h"
#include "device_fixture.h"
#include "geometry/primitives.h"
#include "instancing_checks.h"
#include "geometry/primitive_checks.h"
#include "scene/generators.h"
#include "scene/scene_file.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

namespace wt {
namespace {

using test::Placed;
using test::raysAtCopies;
using test::withInstancing;

/// One geometry: `spheres` spheres of radii 0.05-0.3 in the unit ball (on
/// a grid of 0.5 without overlaps when `apart`, radii 0.05-0.2) and
/// `curves` bent strands of 6 points (radius 0.02-0.06, tapering), linear or
/// B-spline by turns.
Scene sphereAndCurveGeometry(int spheres, int curves, std::uint32_t seed, bool apart = false) {
  Scene s;
  s.materials.push_back(makeMaterial(glm::vec3(0.6f)));
  s.materialNames.push_back("grey");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), r01(0.0f, 1.0f);
  for (int i = 0; i < spheres; ++i) {
    const glm::vec3 c(unit(rng), unit(rng), unit(rng));
    if (apart)
      s.spheres.push_back({0.5f * glm::vec3(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1), 0.05f + 0.15f * r01(rng), 0u});
    else
      s.spheres.push_back({0.7f * c, 0.05f + 0.25f * r01(rng), 0u});
  }
  for (int i = 0; i < curves; ++i) {
    Curve curve;
    curve.firstPoint = std::uint32_t(s.curvePoints.size());
    curve.pointCount = 6;
    curve.basis = i % 2 ? CurveBasis::kBSpline : CurveBasis::kLinear;
    glm::vec3 p(0.8f * unit(rng), -0.9f, 0.8f * unit(rng));
    const float r = 0.02f + 0.04f * r01(rng);
    for (int k = 0; k < 6; ++k) {
      s.curvePoints.push_back({p.x, p.y, p.z, r * (1.0f - 0.1f * float(k))});
      p += glm::vec3(0.15f * unit(rng), 0.35f, 0.15f * unit(rng));
    }
    s.curves.push_back(curve);
  }
  return s;
}

/// Copies turned, scaled uniformly (one mirrored), near and 1e4 from the
/// origin; `mesh`: an icosphere in the geometry too (copies of triangles beside those of spheres and curves).
Placed placedGeometry(int copies = 8, int spheres = 30, int curves = 12, bool apart = false, bool mesh = false) {
  Scene geometry = sphereAndCurveGeometry(spheres, curves, 7, apart);
  if (mesh) appendScene(geometry, makeIcosphere(1, glm::vec3(0.2f, -0.3f, 0.1f), 0.35f, geometry.materials[0]));
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> turn(-3.0f, 3.0f), size(0.4f, 1.6f);
  const glm::vec3 places[] = {{0, 0, 0},    {4, 0, 0},       {0, 4, 1},     {-4, -1, 0}, {3.5f, 3.5f, -3},
                              {1e4f, 0, 0}, {-1e4f, 2e3f, 5}, {0, -4, -4}};
  Placed out;
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < copies; ++c) {
    const glm::vec3 at = places[c % 8] + glm::vec3(0.0f, 0.0f, 8.0f * float(c / 8));
    glm::mat4 m = glm::translate(glm::mat4(1.0f), at);
    m = glm::rotate(m, turn(rng), glm::normalize(glm::vec3(turn(rng), turn(rng), 1.0f)));
    const float k = size(rng);
    m = glm::scale(m, c == 3 ? glm::vec3(k, -k, k) : glm::vec3(k));  // copy 3 mirrored
    transforms.push_back(m);
    out.centres.push_back(at);
    out.scales.push_back(k);
  }
  out.scene = placeCopies(geometry, transforms);
  return out;
}

/// Whether ray r passes within the float rounding of a flattened copy's
/// coordinates (a few ulps of their magnitude) of primitive `prim`'s
/// silhouette: the sphere's, or the segment's round cone's to first order
/// (the line's closest approach to its axis against the radius there).
bool grazes(const Scene& scene, const PrimitiveRows& rows, const Ray& r, std::uint32_t prim) {
  if (prim == RayHit::kNoHit) return false;
  const glm::dvec3 o(r.origin), d = glm::normalize(glm::dvec3(r.direction));
  glm::dvec3 c;
  double radius, distance;
  if (primType(prim) == WT_PRIM_SPHERE) {
    const Sphere& s = scene.spheres[primIndex(prim)];
    c = glm::dvec3(s.center);
    radius = s.radius;
    distance = glm::length((c - o) - glm::dot(c - o, d) * d);
  } else {
    const CurveSegment seg = curveSegment(rows, primIndex(prim));
    const glm::dvec3 a(seg.p0), e = glm::dvec3(seg.p1) - a, w = a - o;
    const double ee = glm::dot(e, e), ed = glm::dot(e, d), denom = ee - ed * ed;
    const double u = denom > 1e-30 ? std::clamp((ed * glm::dot(w, d) - glm::dot(w, e)) / denom, 0.0, 1.0) : 0.0;
    c = a + u * e;
    radius = seg.p0.w + u * (seg.p1.w - seg.p0.w);
    distance = glm::length((c - o) - glm::dot(c - o, d) * d);
  }
  const double rounding = 4e-6 * (1.0 + std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)}));
  return std::abs(distance - radius) <= rounding;
}

/// Every copy of the spheres and of the curves becomes an instance with
/// Instancing::On, none with Off; a copy that is not its geometry moved by
/// its transform (an uneven scale turns spheres into ellipsoids, which a
/// flattened copy is not) stays flat.
TEST(PrimitiveInstancing, CopiesBecomeInstances) {
  // the uploaded buffers alone: a Tracer would also build a program these checks never run
  const Placed p = placedGeometry();
  SceneBuffers on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  EXPECT_EQ(on.instanceCount(), 16u);
  EXPECT_TRUE(on.primitivesInstanced());
  SceneBuffers off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  EXPECT_EQ(off.instanceCount(), 0u);
  EXPECT_FALSE(off.primitivesInstanced());

  Scene uneven = p.scene;
  uneven.primitiveInstances[2].transform = glm::scale(uneven.primitiveInstances[2].transform, glm::dvec3(1, 1.5, 1));
  uneven.primitiveInstances[5].transform = glm::translate(uneven.primitiveInstances[5].transform, glm::dvec3(0, 0.1, 0));
  SceneBuffers some(test::deviceContext(), uneven, withInstancing(Instancing::On));
  EXPECT_EQ(some.instanceCount(), 14u);
}

/// Closest and any hits, in every traversal mode: the instanced form against
/// the flattened one, on rays at every copy (the mirrored one and those 1e4
/// away included): the same flattened primitive at t within the float
/// rounding of the copy's placement, or two at one distance, or where the
/// nearer hit's silhouette is grazed within that rounding (grazes), another.
TEST(PrimitiveInstancing, HitsMatchTheFlattenedScene) {
  const Placed p = placedGeometry();
  const std::vector<Ray> rays = raysAtCopies(p, 0.8f, 500, 11);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 16u);
  const PrimitiveRows rows = gatherPrimitives(p.scene);
  const std::vector<RayHit> flat = off.traceClosest(rays);
  const std::vector<std::uint8_t> flatBlocked = off.traceOccluded(rays);
  int flatHits = 0;
  for (const RayHit& h : flat) flatHits += h.prim != RayHit::kNoHit;
  EXPECT_GT(flatHits, int(rays.size() / 2));
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    SCOPED_TRACE(traversal == Traversal::kSingle ? "single" : "packet");
    const std::vector<RayHit> got = on.traceClosest(rays, traversal);
    int bad = 0, grazing = 0, instanceHits = 0, curveHits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      instanceHits += got[i].instance != RayHit::kNoHit;
      curveHits += got[i].prim != RayHit::kNoHit && primType(got[i].prim) == WT_PRIM_CURVE;
      const double magnitude = 1.0 + std::max({std::abs(rays[i].origin.x), std::abs(rays[i].origin.y),
                                               std::abs(rays[i].origin.z)});
      const double tol = 2e-6 * (magnitude + (flat[i].prim != RayHit::kNoHit ? flat[i].t : 0.0));
      const bool same = got[i].prim == flat[i].prim &&
                        (got[i].prim == RayHit::kNoHit || std::abs(got[i].t - flat[i].t) <= tol);
      if (same) continue;
      // two primitives at one distance (a curve's joint, touching spheres) or a silhouette grazed
      const bool bothHit = got[i].prim != RayHit::kNoHit && flat[i].prim != RayHit::kNoHit;
      const RayHit& nearer = got[i].prim != RayHit::kNoHit && (flat[i].prim == RayHit::kNoHit || got[i].t < flat[i].t)
                                 ? got[i] : flat[i];
      if ((bothHit && std::abs(got[i].t - flat[i].t) <= tol) || grazes(p.scene, rows, rays[i], nearer.prim)) {
        ++grazing;
        continue;
      }
      if (++bad <= 5)
        ADD_FAILURE() << "ray " << i << ": instanced prim " << std::hex << got[i].prim << std::dec
                      << " t=" << got[i].t << " (instance " << got[i].instance << "), flattened prim " << std::hex
                      << flat[i].prim << std::dec << " t=" << flat[i].t;
    }
    EXPECT_EQ(bad, 0);
    EXPECT_LT(grazing, int(rays.size() / 100));
    EXPECT_GT(instanceHits, int(rays.size() / 3));
    EXPECT_GT(curveHits, int(rays.size() / 50));
  }
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    const std::vector<std::uint8_t> blocked = on.traceOccluded(rays, traversal);
    int differ = 0;
    // differences only where a ray grazes a silhouette, as the closest hits' (a few in 1e3 at most)
    for (std::size_t i = 0; i < rays.size(); ++i) differ += blocked[i] != flatBlocked[i];
    EXPECT_LE(differ, int(rays.size() / 500)) << "traversal " << int(traversal);
  }
}

/// Packets go on inside instances (kernels/bvh_prims_packet.cl): the packet
/// traversal's closest and any hits are the single ray's, bit for bit, on
/// copies turned, scaled, mirrored and 1e4 from the origin, with flat
/// spheres and curves beside them (a copy scaled unevenly stays flat) and a
/// mesh in every copy (instanced triangles inside the packet's walk); on
/// rays at the copies and on rays spawned off what those hit (which skip
/// that surface on its own copy only). Two hits at exactly one distance may
/// come out either way (the walks visit nodes in another order).
TEST(PrimitiveInstancing, PacketsInsideInstancesMatchSingleRays) {
  Placed p = placedGeometry(8, 30, 12, false, true);
  p.scene.primitiveInstances[2].transform =
      glm::scale(p.scene.primitiveInstances[2].transform, glm::dvec3(1, 1.5, 1));
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 15u + 8u);
  // whole packets at each copy
  std::vector<Ray> rays = raysAtCopies(p, 0.8f, 320, 31);
  const std::vector<Ray> spawned = test::raysFromHitPoints(rays, on.traceClosest(rays), 3);
  rays.insert(rays.end(), spawned.begin(), spawned.end());
  ASSERT_GT(rays.size(), p.centres.size() * 320 * 4 / 3);  // a third of them hit
  // two hits at one distance: touching spheres, a curve's joint, a mesh's edge
  int ties = 0;
  const std::vector<RayHit> single =
      test::expectPacketClosestMatchesSingle(on, rays, [](const RayHit&, const RayHit&) { return true; }, &ties);
  int instanceHits = 0, meshHits = 0, flatHits = 0;
  for (const RayHit& a : single) {
    instanceHits += a.instance != RayHit::kNoHit && a.triangle == RayHit::kNoHit;
    meshHits += a.instance != RayHit::kNoHit && a.triangle != RayHit::kNoHit;
    flatHits += a.instance == RayHit::kNoHit && a.prim != RayHit::kNoHit && a.triangle == RayHit::kNoHit;
  }
  EXPECT_LT(ties, int(rays.size() / 200));
  EXPECT_GT(instanceHits, int(rays.size() / 5));
  EXPECT_GT(meshHits, int(rays.size() / 50));
  EXPECT_GT(flatHits, int(rays.size() / 200));
  // any hits, on segments cut short too
  for (std::size_t i = 0; i < rays.size(); i += 3) rays[i].tmax = 0.5f;
  int blocked = 0;
  for (std::uint8_t b : test::expectPacketOcclusionMatchesSingle(on, rays)) blocked += b;
  EXPECT_GT(blocked, int(rays.size() / 3));
  EXPECT_LT(blocked, int(rays.size()) - int(rays.size() / 10));
}

/// Curve ends inside instances: packets aimed across the silhouettes of the
/// curves' free ends in every copy (turned, scaled, mirrored, 1e4 away) and
/// the rays spawned off what they hit get the single rays' closest hits and
/// occlusion (test::expectCurvePacketsMatchSingleRays), the copies' lanes
/// moved into object space and walked there as a packet.
TEST(PrimitiveInstancing, PacketsMatchSingleRaysAtInstancedCurveEnds) {
  const Placed p = placedGeometry(8, 30, 12, false, true);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 3u * 8u);
  // the flattened segments: every copy's ends in scene space, as the hits name them
  const PrimitiveRows rows = gatherPrimitives(p.scene);
  test::expectCurvePacketsMatchSingleRays(on, rows,
                                          test::raysAtCurveEnds(rows, test::testSize(240, 40), on.packetWidth(), 19));
}

/// Spheres and curves are stored as the copy whose floats are finest for its
/// size, as triangles are: here the large copy 300 from the origin, not the
/// tiny one (1e-5 of its size) beside the origin, whose points are rounded
/// to about 0.5 % of its size. Both copies become instances (the large one,
/// drawn as the tiny one moved, would not match its own floats), and the
/// large copy's hits match its flattened ones.
TEST(PrimitiveInstancing, TheStoredCopyIsTheFinestForItsSize) {
  Scene geometry = sphereAndCurveGeometry(30, 12, 7);
  // linear only: the tiny copy's rounded B-spline points would subdivide
  // into other segments than the large copy's, and such copies stay flat
  for (Curve& c : geometry.curves) c.basis = CurveBasis::kLinear;
  Placed p;
  const glm::mat4 copies[] = {glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.5f, 0.0f)), glm::vec3(1e-5f)),
                              glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(300.0f, 0.0f, 0.0f)), 0.4f,
                                          glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)))};
  p.scene = placeCopies(geometry, copies);
  p.centres = {glm::vec3(300.0f, 0.0f, 0.0f)};  // the large copy's rays only: the tiny one's floats are too coarse
  p.scales = {1.0f};
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 4u);  // spheres and curves, two copies each
  const PrimitiveRows rows = gatherPrimitives(p.scene);
  const std::vector<Ray> rays = raysAtCopies(p, 0.8f, 4000, 17);
  const std::vector<RayHit> flat = off.traceClosest(rays), got = on.traceClosest(rays);
  int bad = 0, grazing = 0, hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    hits += flat[i].prim != RayHit::kNoHit;
    const double tol = 2e-6 * (301.0 + (flat[i].prim != RayHit::kNoHit ? flat[i].t : 0.0));
    if (got[i].prim == flat[i].prim && (got[i].prim == RayHit::kNoHit || std::abs(got[i].t - flat[i].t) <= tol))
      continue;
    const bool bothHit = got[i].prim != RayHit::kNoHit && flat[i].prim != RayHit::kNoHit;
    if ((bothHit && std::abs(got[i].t - flat[i].t) <= tol) || grazes(p.scene, rows, rays[i], flat[i].prim) ||
        grazes(p.scene, rows, rays[i], got[i].prim)) {
      ++grazing;
      continue;
    }
    if (++bad <= 5)
      ADD_FAILURE() << "ray " << i << ": instanced prim " << std::hex << got[i].prim << std::dec << " t=" << got[i].t
                    << ", flattened prim " << std::hex << flat[i].prim << std::dec << " t=" << flat[i].t;
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(hits, int(rays.size() / 2));
  EXPECT_LT(grazing, int(rays.size() / 100));
}

/// Rays spawned off instanced spheres (the point from the flattened sphere,
/// pushed past its error bound and the copy's float placement, skipping that
/// sphere): outwards they never meet it again, inwards they meet it once
/// more, on its far side, on the same copy.
TEST(PrimitiveInstancing, SpawnedRaysLeaveTheirSphere) {
  const Placed p = placedGeometry(8, 27, 0, true);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 8u);
  std::vector<Ray> rays = raysAtCopies(p, 0.8f, 400, 23);
  for (Ray& r : rays) r.tmin = 0.0f, r.tmax = 1e30f;
  const std::vector<RayHit> hits = on.traceClosest(rays);
  std::vector<Ray> outward, inward;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit& h = hits[i];
    if (h.instance == RayHit::kNoHit) continue;
    const Sphere& s = p.scene.spheres[primIndex(h.prim)];
    glm::vec3 error, n;
    const glm::vec3 point = spherePoint(s.center, s.radius, rays[i].origin, rays[i].direction, h.t, &error, &n);
    error += 32.0f * 5.96e-8f * (glm::abs(point) + glm::vec3(s.radius));
    Ray out;
    out.origin = offsetRayOrigin(point, error, n);
    out.direction = glm::normalize(n + 0.9f * glm::normalize(rays[i].direction - n * glm::dot(rays[i].direction, n) +
                                                               glm::vec3(1e-3f)));
    out.skip = h.prim;
    outward.push_back(out);
    Ray in = out;
    in.origin = offsetRayOrigin(point, error, -n);
    in.direction = -out.direction;
    inward.push_back(in);
  }
  ASSERT_GT(outward.size(), rays.size() / 3);
  const std::vector<RayHit> outHits = on.traceClosest(outward);
  const std::vector<RayHit> inHits = on.traceClosest(inward);
  int selfOut = 0, missedIn = 0;
  for (std::size_t i = 0; i < outward.size(); ++i) {
    if (outHits[i].prim == outward[i].skip && ++selfOut <= 5)
      ADD_FAILURE() << "outward ray " << i << " met its own sphere at t=" << outHits[i].t;
    // inwards: the far side of its own sphere, unless another sphere of the copy overlaps it first
    if (inHits[i].prim == RayHit::kNoHit && ++missedIn <= 5)
      ADD_FAILURE() << "inward ray " << i << " met nothing";
  }
  EXPECT_EQ(selfOut, 0);
  EXPECT_EQ(missedIn, 0);
  for (Ray& r : outward) r.tmax = 0.02f;
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    const std::vector<std::uint8_t> blocked = on.traceOccluded(outward, traversal);
    int count = 0;
    for (std::uint8_t b : blocked) count += b;
    EXPECT_EQ(count, 0) << "traversal " << int(traversal);
  }
}

/// The instanced and the flattened forms render the same image for a seed
/// within noise (not bit for bit: the copies' points differ in the last
/// bits, and the paths decorrelate).
TEST(PrimitiveInstancing, RendersMatchTheFlattenedScene) {
  Placed p = placedGeometry(5);
  const std::uint32_t light = std::uint32_t(p.scene.materials.size());
  p.scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f), true));
  p.scene.materialNames.push_back("light");
  appendScene(p.scene, test::makeFloor(1.5f, 6.0f, p.scene.materials[light], true));
  CameraDesc camera;
  camera.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.5f, 1.0f, 12.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0)));
  camera.yfov = 0.9f;
  p.scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = 48;
  settings.maxBounces = 4;
  settings.seed = 3;
  settings.background = glm::vec3(0.2f);
  // the floor light sampled as triangles: the programs are then SceneFileInstancesAreStoredOnce's,
  // compiled once in the suite (quad lights are not what this compares)
  settings.quadLights = false;
  settings.instancing = Instancing::Off;
  const Image flat = test::render(p.scene, settings, 64);
  settings.instancing = Instancing::On;
  const Image instanced = test::render(p.scene, settings, 64);
  test::expectSameImage(flat, instanced, 6, 4.5, "instanced spheres and curves against flattened");
}

/// A convex white geometry: one sphere, or one straight curve of 12
/// collinear segments (a capsule), white with geometric normals.
Scene whiteConvexGeometry(bool curve) {
  Scene s;
  s.materials.push_back(makeMaterial(glm::vec3(1.0f)));
  s.materialNames.push_back("white");
  if (!curve) {
    s.spheres.push_back({glm::vec3(0.1f, -0.2f, 0.0f), 0.9f, 0u});
    return s;
  }
  Curve c;
  c.pointCount = 13;
  for (int k = 0; k < 13; ++k) {
    const glm::vec3 p = glm::vec3(-1.2f, -0.3f, 0.1f) + float(k) / 12.0f * glm::vec3(2.4f, 0.6f, -0.2f);
    s.curvePoints.push_back({p.x, p.y, p.z, 0.35f});
  }
  s.curves.push_back(c);
  return s;
}

/// White instanced spheres and curves (each copy convex) in a uniform sky
/// return the sky: a bounce or shadow ray that met the surface it leaves, on
/// the instanced surface the renderer computes, would darken its pixel.
/// Copies 1e4 from the origin and a mirrored one, alone in view; packets
/// and single rays.
TEST(PrimitiveInstancing, WhiteInstancedCopiesInUniformSky) {
  for (bool curve : {false, true}) {
  SCOPED_TRACE(curve ? "curve" : "sphere");
  const Scene geometry = whiteConvexGeometry(curve);
  const glm::vec3 places[] = {{0, 0, 0}, {1e4f, 0, 0}, {-1e4f, 2e3f, 5}, {0, 3e3f, 0}};
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 4; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), places[c]);
    m = glm::rotate(m, 0.7f * float(c + 1), glm::normalize(glm::vec3(1.0f, 2.0f, float(c))));
    transforms.push_back(glm::scale(m, c == 3 ? glm::vec3(1.2f, -1.2f, 1.2f) : glm::vec3(0.8f)));
  }
  Scene scene = placeCopies(geometry, transforms);
  {
    SceneBuffers on(test::deviceContext(), scene, withInstancing(Instancing::On));
    ASSERT_EQ(on.instanceCount(), 4u);
  }
  RenderSettings settings;
  settings.width = settings.height = 24;
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.seed = 3;
  settings.instancing = Instancing::On;
  for (int c : {1, 2, 3}) {
    SCOPED_TRACE("copy " + std::to_string(c));
    CameraDesc camera;
    // (3.2 radii of the largest copy: as close as the flat sphere's own sky test)
    camera.cameraToWorld = glm::translate(glm::mat4(1.0f), places[c] + glm::vec3(0.0f, 0.0f, 3.6f));
    scene.camera = camera;
    for (bool packets : {true, false}) {
      settings.packets = packets;
      test::expectUniform(test::render(scene, settings, 32), glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0,
                          "white instanced spheres and curves in a uniform sky");
    }
  }
  }
}

/// A scene file's "instances" of spheres and of curves (B-splines with
/// children, a mirrored and a scaled copy) are stored once with
/// Instancing::On, and render the flattened image within noise.
TEST(PrimitiveInstancing, SceneFileInstancesAreStoredOnce) {
  const SceneFile file = loadSceneFileFromMemory(R"({"version": 1,
      "camera": {"from": [0, 1, 9], "to": [0, 0, 0], "fov": 50},
      "materials": {"white": {"type": "lambert", "base_color": [0.8, 0.8, 0.8]},
                    "red": {"type": "lambert", "base_color": [0.8, 0.2, 0.1]}},
      "objects": [
        {"type": "spheres", "centers": [[0, 0, 0], [0.6, 0.2, 0], [-0.5, 0.3, 0.2]], "radii": [0.4, 0.2, 0.25],
         "material": "white", "instances": [{"translate": [-2.5, 0, 0]}, {"rotate": [0, 1, 0, 90], "scale": 1.5},
                                            {"translate": [2.5, 0, 0], "scale": [-1, 1, 1]}]},
        {"type": "curves", "material": "red", "basis": "bspline", "children": 8, "child_radius": 0.1,
         "strands": [[[0, -1, 0, 0.06], [0.1, -0.5, 0, 0.06], [0.3, 0, 0.1, 0.04], [0.6, 0.5, 0.1, 0.02], [1, 1, 0.2, 0]]],
         "instances": [{"translate": [-2.5, 0.8, 0]}, {"translate": [0, 0.8, 0], "scale": 1.4},
                       {"translate": [2.5, 0.8, 0], "rotate": [0, 0, 1, 30]}]}]})",
                                                 "instances.json", ".");
  const Scene& scene = file.scene;
  ASSERT_EQ(scene.primitiveInstances.size(), 6u);
  {
    SceneBuffers on(test::deviceContext(), scene, withInstancing(Instancing::On));
    EXPECT_EQ(on.instanceCount(), 6u);
  }
  RenderSettings settings;
  settings.width = 48;
  settings.height = 32;
  settings.maxBounces = 3;
  settings.seed = 4;
  settings.background = glm::vec3(0.6f, 0.7f, 0.9f);
  settings.instancing = Instancing::Off;
  const Image flat = test::render(scene, settings, 64);
  settings.instancing = Instancing::On;
  const Image instanced = test::render(scene, settings, 64);
  test::expectSameImage(flat, instanced, 4, 4.5, "scene-file instances against their flattened copies");
}

/// Memory: 98 copies of spheres and curves stored once take about 1/98 of
/// the flattened form's primitive bytes, plus the instances' rows and tree.
TEST(PrimitiveInstancing, StoredOnce) {
  // the uploaded buffers alone: a Tracer would also build a program these checks never run
  const Scene geometry = sphereAndCurveGeometry(200, 100, 9);
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 98; ++c)
    transforms.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(3.0f * float(c % 14), 3.0f * float(c / 14), 0)));
  const Scene scene = placeCopies(geometry, transforms);
  SceneBuffers on(test::deviceContext(), scene, withInstancing(Instancing::On));
  SceneBuffers off(test::deviceContext(), scene, withInstancing(Instancing::Off));
  ASSERT_EQ(on.instanceCount(), 2u * 98u);
  const double flatBytes = double(off.primitiveBytes);
  const double ratio = double(on.primitiveBytes) / flatBytes;
  // per instance: 6 rows of 16 bytes, an info row, a typed id and its share of a node
  const double overhead = 2.0 * 98.0 * (7 * 16 + 4 + 128.0 / 2) / flatBytes;
  EXPECT_LT(ratio, 1.0 / 98.0 * 1.1 + overhead);
  EXPECT_GT(ratio, 1.0 / 98.0 * 0.9);
}

/// Every curve entry of the primitive trees, the instanced geometries' own
/// trees included, carries its segment's rows as its leaf joints (the
/// leaf's reject and the segment test read them in place of the rows).
TEST(PrimitiveInstancing, InstancedCurveEntriesCarryTheirJoints) {
  const Scene geometry = sphereAndCurveGeometry(20, 30, 5);
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 6; ++c) transforms.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(3.0f * float(c), 0, 0)));
  SceneBuffers on(test::deviceContext(), placeCopies(geometry, transforms), withInstancing(Instancing::On));
  ASSERT_TRUE(on.primitivesInstanced());
  Context& ctx = test::deviceContext();
  std::vector<std::uint32_t> refs(on.primRefs.getInfo<CL_MEM_SIZE>() / sizeof(std::uint32_t));
  std::vector<WtVec4> data(on.primData.getInfo<CL_MEM_SIZE>() / sizeof(WtVec4));
  ctx.queue().enqueueReadBuffer(on.primRefs, CL_TRUE, 0, refs.size() * sizeof(std::uint32_t), refs.data());
  ctx.queue().enqueueReadBuffer(on.primData, CL_TRUE, 0, data.size() * sizeof(WtVec4), data.data());
  std::size_t curves = 0;
  for (std::size_t i = 0; i < refs.size(); ++i) {
    if (primType(refs[i]) != WT_PRIM_CURVE) continue;
    ++curves;
    const std::size_t row = on.geometry.data_first[WT_PRIM_CURVE] + 2 * std::size_t(primIndex(refs[i]));
    for (std::size_t end = 0; end < 2; ++end) {
      const WtVec4& joint = data.at(on.geometry.leaf_joints + WT_LEAF_JOINT_ROWS * i + end);
      const WtVec4& want = data.at(row + end);
      ASSERT_EQ(std::memcmp(&joint, &want, sizeof(WtVec4)), 0) << "entry " << i << " end " << end;
    }
  }
  EXPECT_GT(curves, 0u);  // the copies' curves: all in the geometry's own tree
}

}  // namespace
}  // namespace wt
