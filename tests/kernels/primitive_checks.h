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

}  // namespace wt::test
