// Checks shared by the instancing tests (test_instancing.cpp, the primitive
// and surface instancing tests, the assets test): the instanced form of a
// scene against its flattened form, and rays aimed at placed copies.
#pragma once

#include "brute_force.h"
#include "device/tracer.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

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

/// A scene of placed copies and, per copy, where it is and how large.
struct Placed {
  Scene scene;
  std::vector<glm::vec3> centres;
  std::vector<float> scales;
};

/// Rays from around each copy towards points inside it (within `inside` of
/// its scale from its centre), some short, some starting ahead.
inline std::vector<Ray> raysAtCopies(const Placed& p, float inside, std::size_t perCopy, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), t01(0.0f, 1.0f);
  auto direction = [&] {
    glm::vec3 d;
    do d = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-3f);
    return glm::normalize(d);
  };
  std::vector<Ray> rays;
  for (std::size_t c = 0; c < p.centres.size(); ++c)
    for (std::size_t i = 0; i < perCopy; ++i) {
      const float r = p.scales[c];
      Ray ray;
      ray.origin = p.centres[c] + 3.0f * r * direction();
      ray.direction = glm::normalize(p.centres[c] + inside * r * t01(rng) * direction() - ray.origin);
      ray.tmin = (i % 7 == 3) ? r * t01(rng) : 0.0f;
      ray.tmax = (i % 5 == 1) ? 2.0f * r + 2.0f * r * t01(rng) : 1e30f;
      rays.push_back(ray);
    }
  return rays;
}

}  // namespace wt::test
