// Checks shared by the instancing tests (test_instancing.cpp and the assets
// test): the instanced form of a scene against its flattened form.
#pragma once

#include "brute_force.h"
#include "device/tracer.h"

#include <algorithm>
#include <cmath>

namespace wt::test {

inline BvhBuildOptions withInstancing(Instancing mode) {
  BvhBuildOptions options;
  options.maxLeafSize = 0;
  options.instancing = mode;
  return options;
}

/// Whether a kernel hit and the flattened form's hit of one ray agree: the
/// same scene triangle at t within the float rounding of the copy's
/// placement (the instanced copy is its geometry moved by float matrices, a
/// few ulps of the coordinates' magnitude from the flattened floats), or a
/// different one where the ray passes within that rounding of an edge.
/// Counts such edge calls in *edges.
inline bool hitsAgree(const Scene& scene, const Ray& ray, const RayHit& got, const RayHit& flat, int* edges) {
  const double magnitude = 1.0 + std::max({std::abs(ray.origin.x), std::abs(ray.origin.y), std::abs(ray.origin.z)});
  const double tol = 2e-6 * (magnitude + (flat.triangle != RayHit::kNoHit ? flat.t : 0.0));
  if (got.triangle == flat.triangle) return got.triangle == RayHit::kNoHit || std::abs(got.t - flat.t) <= tol;
  auto nearEdge = [&](const RayHit& h) {
    if (h.triangle == RayHit::kNoHit) return true;
    double t, b0, b1, b2;
    if (!triangleParams(scene, h.triangle, ray, t, b0, b1, b2)) return false;
    return std::min({b0, b1, b2}) > -1e-3 && std::min({b0, b1, b2}) < 1e-3;
  };
  const bool both = got.triangle != RayHit::kNoHit && flat.triangle != RayHit::kNoHit;
  if ((both && std::abs(got.t - flat.t) <= tol) || (nearEdge(got) && nearEdge(flat))) {
    ++*edges;
    return true;
  }
  return false;
}

}  // namespace wt::test
