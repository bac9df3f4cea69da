// Checks the tests of every geometry type beside triangles share.
#pragma once

#include "core/spawn.h"
#include "device/tracer.h"
#include "device_fixture.h"
#include "geometry/primitives.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <span>
#include <vector>

namespace wt::test {

/// Rays from above aimed where primitives of `type` meet a floor at y = 0:
/// every ray must stop at one or the other (closest and any hit), none
/// below the floor, and both must be met by some rays.
inline void expectNoLeaksOnFloor(const Scene& scene, const std::vector<Ray>& rays, std::uint32_t type) {
  Tracer tracer(deviceContext(), scene);
  const std::vector<RayHit> hits = tracer.traceClosest(rays);
  int leaks = 0, ofType = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    leaks += hits[i].prim == RayHit::kNoHit;
    ofType += hits[i].prim != RayHit::kNoHit && primType(hits[i].prim) == type;
    if (hits[i].prim != RayHit::kNoHit) {
      EXPECT_GE(rays[i].origin.y + hits[i].t * rays[i].direction.y, -1e-5f);
    }
  }
  EXPECT_EQ(leaks, 0);
  EXPECT_GT(ofType, 100);
  EXPECT_LT(ofType, int(rays.size()));
  const std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, Traversal::kPacket);
  int unblocked = 0;
  for (std::uint8_t b : blocked) unblocked += b == 0;
  EXPECT_EQ(unblocked, 0);
}

/// Each traversal's closest hit is the brute-force one's (`brute`: the test
/// kernel's hits over every primitive, t < 0 for none), of `type`, with
/// the same t: the BVH loses none. `every` names the brute force in failures.
template <class Hit>
void expectTraversalsFindWhatBruteForceFinds(const Scene& scene, const std::vector<Ray>& rays,
                                             const std::vector<Hit>& brute, std::uint32_t type, const char* every) {
  Tracer tracer(deviceContext(), scene);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    const std::vector<RayHit> hits = tracer.traceClosest(rays, traversal);
    int bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bool hit = hits[i].prim != RayHit::kNoHit;
      bool ok = hit == (brute[i].t >= 0.0f);
      if (ok && hit) ok = primType(hits[i].prim) == type && hits[i].t == brute[i].t;
      if (!ok && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << " traversal " << int(traversal) << ": t " << hits[i].t << " prim "
                      << hits[i].prim << ", " << every << ": t " << brute[i].t;
    }
    EXPECT_EQ(bad, 0);
  }
}

/// Any hit against closest hit in every traversal: a ray blocked must be a
/// ray hit, but for the rays `eitherWay(i)` lets go either way (a tangency
/// or a crossing at the segment's very end, by the test's reference).
template <class EitherWay>
void expectAnyHitAgreesWithClosestHit(const Scene& scene, const std::vector<Ray>& rays, EitherWay eitherWay) {
  Tracer tracer(deviceContext(), scene);
  const std::vector<RayHit> closest = tracer.traceClosest(rays);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    const std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays, traversal);
    int bad = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (bool(occluded[i]) == (closest[i].prim != RayHit::kNoHit)) continue;
      if (eitherWay(i)) continue;
      if (++bad <= 5)
        ADD_FAILURE() << "ray " << i << " traversal " << int(traversal) << ": occluded " << int(occluded[i])
                      << ", closest hit " << closest[i].prim;
    }
    EXPECT_EQ(bad, 0);
  }
}

/// Rays spawned from the test kernel's hits (t < 0: none; a `normal` and
/// an `error` bound each) in random directions within acos(minCos) of the
/// normal: outward they meet nothing, inward they meet the far side, more
/// than 0.7 away. Most of `rays` must hit (the floor scales with
/// WT_TEST_SMALL).
template <class Hit>
void expectSpawnedRaysLeaveOrCross(const Scene& scene, const std::vector<Ray>& rays, const std::vector<Hit>& hits,
                                   std::uint32_t seed, float minCos) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> out, in;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].t < 0.0f) continue;
    const glm::vec3 p = rays[i].origin + hits[i].t * rays[i].direction, n = hits[i].normal;
    glm::vec3 w;
    do w = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(w, w) > 1.0f || glm::dot(w, w) < 1e-3f || std::abs(glm::dot(glm::normalize(w), n)) < minCos);
    w = glm::normalize(w);
    if (glm::dot(w, n) < 0.0f) w = -w;
    Ray r;
    r.origin = offsetRayOrigin(p, hits[i].error, n);
    r.direction = w;
    out.push_back(r);
    r.origin = offsetRayOrigin(p, hits[i].error, -n);
    r.direction = -w;
    in.push_back(r);
  }
  ASSERT_GT(out.size(), rays.size() / 12);
  Tracer tracer(deviceContext(), scene);
  const std::vector<RayHit> again = tracer.traceClosest(out), through = tracer.traceClosest(in);
  int selfHits = 0, lost = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    selfHits += again[i].prim != RayHit::kNoHit;
    lost += through[i].prim == RayHit::kNoHit || !(through[i].t > 0.7f);
  }
  EXPECT_EQ(selfHits, 0) << "of " << out.size() << " rays leaving the surface";
  EXPECT_EQ(lost, 0) << "of " << in.size() << " rays entering it";
}

/// Packet traversal against single rays on one tracer (kernels/bvh_prims_packet.cl
/// walks the primitives with each lane's own calls): the closest hits the same bit
/// for bit (prim, instance, t, b1, b2), but two hits at exactly one distance that
/// `tie(single, packet)` accepts (the packet visits nodes in another order; *ties
/// counts them). Returns the single rays' hits.
template <class Tie>
std::vector<RayHit> expectPacketClosestMatchesSingle(Tracer& tracer, std::span<const Ray> rays, Tie tie, int* ties) {
  const std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
  const std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
  int bad = 0;
  *ties = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit &a = single[i], &b = packet[i];
    if (a.prim == b.prim && a.instance == b.instance &&
        (a.prim == RayHit::kNoHit || (a.t == b.t && a.b1 == b.b1 && a.b2 == b.b2)))
      continue;
    if (a.prim != RayHit::kNoHit && b.prim != RayHit::kNoHit && a.t == b.t && tie(a, b)) {
      ++*ties;
      continue;
    }
    if (++bad <= 5)
      ADD_FAILURE() << "ray " << i << " (skip " << std::hex << rays[i].skip << "): single prim " << a.prim << std::dec
                    << " t=" << a.t << " instance " << a.instance << ", packet prim " << std::hex << b.prim
                    << std::dec << " t=" << b.t << " instance " << b.instance;
  }
  EXPECT_EQ(bad, 0) << "of " << rays.size() << " rays";
  return single;
}

/// Packet and single-ray occlusion the same on every ray; returns the single rays' flags.
inline std::vector<std::uint8_t> expectPacketOcclusionMatchesSingle(Tracer& tracer, std::span<const Ray> rays) {
  const std::vector<std::uint8_t> single = tracer.traceOccluded(rays, Traversal::kSingle);
  const std::vector<std::uint8_t> packet = tracer.traceOccluded(rays, Traversal::kPacket);
  int differ = 0;
  for (std::size_t i = 0; i < rays.size(); ++i)
    if (single[i] != packet[i] && ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": blocked " << int(single[i]) << " alone, " << int(packet[i])
                    << " in its packet";
  EXPECT_EQ(differ, 0) << "of " << rays.size() << " rays";
  return single;
}

/// Whether two curve hits are the two segments that share a joint (one
/// curve, neighbouring segments): the joint's sphere belongs to both, so
/// both may report one crossing at one distance.
inline bool curveJointTie(const PrimitiveRows& rows, const RayHit& a, const RayHit& b) {
  if (a.instance != b.instance || primType(a.prim) != WT_PRIM_CURVE || primType(b.prim) != WT_PRIM_CURVE) return false;
  const std::uint32_t i = primIndex(a.prim), j = primIndex(b.prim);
  return (i + 1 == j || j + 1 == i) && curveSegment(rows, i).curve == curveSegment(rows, j).curve;
}

/// Packets of `width` rays at the free ends of the curves in `rows` (a
/// segment's joint where its curve stops): a packet from 10 to 1000 end
/// radii away (origins jittered by a tenth of the radius) aimed within 3 %
/// of the end's silhouette, seen from past the end, from the side or from
/// inside the tube, so that a packet's lanes split between hit and miss at
/// the cap; every fourth packet mixes the ends of its lanes; every third
/// ray stops near its target, every fifth starts near it.
inline std::vector<Ray> raysAtCurveEnds(const PrimitiveRows& rows, std::size_t packets, int width,
                                        std::uint32_t seed) {
  struct End {
    glm::vec3 centre, axis;  ///< the joint; outwards along its segment
    float radius;
  };
  std::vector<End> ends;
  for (std::uint32_t id : rows.ids) {
    if (primType(id) != WT_PRIM_CURVE) continue;
    const CurveSegment s = curveSegment(rows, primIndex(id));
    const glm::vec3 a(s.p0), b(s.p1);
    if (!(glm::length(b - a) > 0.0f)) continue;
    if (!s.left && s.p0.w > 0.0f) ends.push_back({a, glm::normalize(a - b), s.p0.w});
    if (!s.right && s.p1.w > 0.0f) ends.push_back({b, glm::normalize(b - a), s.p1.w});
  }
  std::vector<Ray> rays;
  if (ends.empty()) return rays;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::uniform_int_distribution<std::size_t> pick(0, ends.size() - 1);
  auto direction = [&] {
    glm::vec3 d;
    do d = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-3f);
    return glm::normalize(d);
  };
  for (std::size_t k = 0; k < packets; ++k) {
    const End packetEnd = ends[pick(rng)];
    const int view = int(k % 3);  // past the end, from the side, from inside
    const glm::vec3 side = glm::normalize(glm::cross(packetEnd.axis, direction()));
    const float distance = packetEnd.radius * std::pow(10.0f, 1.0f + 2.0f * u01(rng));
    for (int l = 0; l < width; ++l) {
      const End e = k % 4 == 3 ? ends[pick(rng)] : packetEnd;
      glm::vec3 from = view == 0   ? e.axis
                       : view == 1 ? (k % 4 == 3 ? glm::normalize(glm::cross(e.axis, direction())) : side)
                                   : -e.axis;
      Ray r;
      r.origin = view == 2 ? e.centre - 0.5f * e.radius * e.axis + 0.1f * e.radius * direction()
                           : e.centre + (k % 4 == 3 ? e.radius * 100.0f : distance) * from +
                                 0.1f * e.radius * direction();
      // across the silhouette: a point of the cap's rim (or the tube's side near it) seen from the origin
      glm::vec3 across = glm::cross(from, direction());
      if (!(glm::length(across) > 1e-3f)) across = glm::cross(from, glm::vec3(0.6f, 0.0f, 0.8f));
      const glm::vec3 target = e.centre + e.radius * (view == 1 ? 1.2f * unit(rng) : 0.0f) * e.axis +
                               e.radius * (1.0f + 0.03f * unit(rng)) * glm::normalize(across);
      r.direction = glm::normalize(target - r.origin);
      if (l % 3 == 2) r.tmax = glm::length(target - r.origin) * (1.0f + 0.01f * unit(rng));
      if (l % 5 == 4) r.tmin = glm::length(target - r.origin) * (0.99f + 0.01f * unit(rng));
      rays.push_back(r);
    }
  }
  return rays;
}

/// Rays spawned where `rays` hit, as shade spawns them: from the hit
/// reprojected onto the segment (curvePoint) and pushed past its rounding
/// error, outwards into a random direction of the outer hemisphere, or
/// inwards into the opposite one; skipping the segment they leave. Directions
/// closer than `minCosine` to the surface's plane are not drawn.
struct Spawned {
  std::vector<Ray> out, in;
  std::vector<std::uint32_t> from;
};

inline Spawned spawnFrom(const PrimitiveRows& rows, std::span<const Ray> rays, std::span<const RayHit> hits,
                  std::uint32_t seed, float minCosine = 0.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  Spawned s;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].prim == RayHit::kNoHit || primType(hits[i].prim) != WT_PRIM_CURVE) continue;
    const CurveSegment seg = curveSegment(rows, primIndex(hits[i].prim));
    glm::vec3 error, n;
    const glm::vec3 p = curvePoint(seg, rays[i].origin, rays[i].direction, hits[i].t, &error, &n);
    glm::vec3 w;
    do {
      do w = glm::vec3(unit(rng), unit(rng), unit(rng));
      while (glm::dot(w, w) > 1.0f || glm::dot(w, w) < 1e-3f);
      w = glm::normalize(w);
    } while (std::fabs(glm::dot(w, n)) < minCosine);
    if (glm::dot(w, n) < 0.0f) w = -w;
    Ray r;
    r.skip = hits[i].prim;
    r.origin = offsetRayOrigin(p, error, n);
    r.direction = w;  // away from the surface: reflection
    s.out.push_back(r);
    r.origin = offsetRayOrigin(p, error, -n);
    r.direction = -w;  // into the curve: refraction
    s.in.push_back(r);
    s.from.push_back(hits[i].prim);
  }
  return s;
}

/// From where each of `rays` hits (o + t d, not pushed off the surface), a
/// ray in a random direction that skips what it hit.
inline std::vector<Ray> raysFromHitPoints(std::span<const Ray> rays, std::span<const RayHit> hits,
                                          std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> out;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (hits[i].prim == RayHit::kNoHit) continue;
    Ray r;
    r.origin = rays[i].origin + hits[i].t * rays[i].direction;
    r.direction = glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)) + 1e-3f);
    r.skip = hits[i].prim;
    out.push_back(r);
  }
  return out;
}

/// Packets through curves (kernels/bvh_prims_packet.cl) give each lane the
/// single ray's answer: packets aimed across the silhouettes of curve ends
/// (their lanes split between hit and miss at the cap), and the rays spawned
/// off what they hit, skipping the surface they leave: outwards and inwards
/// from past its rounding error, and from the hit point itself.
/// Closest hits the same bit for bit, but the two segments of one joint at
/// one distance; occlusion the same, on those rays cut short exactly at
/// their closest hit, one ulp past it, or not at all.
inline void expectCurvePacketsMatchSingleRays(Tracer& tracer, const PrimitiveRows& rows, std::vector<Ray> rays) {
  const auto jointTie = [&](const RayHit& a, const RayHit& b) { return curveJointTie(rows, a, b); };
  const std::size_t width = std::size_t(tracer.packetWidth()), packets = rays.size() / width;
  int ties = 0;
  const std::vector<RayHit> first = expectPacketClosestMatchesSingle(tracer, rays, jointTie, &ties);
  // the packets do split at the ends: some lanes hit, others of the same packet miss
  std::size_t split = 0, hits = 0;
  for (std::size_t k = 0; k < packets; ++k) {
    std::size_t in = 0;
    for (std::size_t l = 0; l < width; ++l) in += first[k * width + l].prim != RayHit::kNoHit;
    split += in > 0 && in < width;
    hits += in;
  }
  EXPECT_GT(split, packets / 2);
  EXPECT_GT(hits, rays.size() / 4);
  const Spawned spawned = spawnFrom(rows, rays, first, 10);
  ASSERT_GT(spawned.from.size(), rays.size() / 4);
  rays.insert(rays.end(), spawned.out.begin(), spawned.out.end());
  rays.insert(rays.end(), spawned.in.begin(), spawned.in.end());
  // and from the hit point itself, not pushed off: only the skip keeps such a ray off the surface it leaves
  const std::vector<Ray> onSurface = raysFromHitPoints(std::span(rays).first(packets * width), first, 11);
  rays.insert(rays.end(), onSurface.begin(), onSurface.end());
  const std::vector<RayHit> all = expectPacketClosestMatchesSingle(tracer, rays, jointTie, &ties);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (all[i].prim == RayHit::kNoHit || i % 3 == 2) continue;
    rays[i].tmax = i % 3 == 0 ? all[i].t : std::nextafter(all[i].t, INFINITY);
  }
  const std::vector<std::uint8_t> blocked = expectPacketOcclusionMatchesSingle(tracer, rays);
  std::size_t blockedCount = 0;
  for (std::uint8_t b : blocked) blockedCount += b;
  EXPECT_GT(blockedCount, rays.size() / 4);
  EXPECT_LT(blockedCount, rays.size() - rays.size() / 10);
}

}  // namespace wt::test
