// Checks the tests of every geometry type beside triangles share.
#pragma once

#include "device/tracer.h"
#include "device_fixture.h"
#include "geometry/primitives.h"

#include <gtest/gtest.h>

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

}  // namespace wt::test
