// Watertightness: rays aimed exactly at the shared vertices and edges of
// closed meshes must never pass between the triangles.
#include "device_fixture.h"
#include "device/tracer.h"
#include "scene/generators.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace wt {
namespace {

/// Every vertex, every edge midpoint and random points along every edge.
std::vector<glm::vec3> edgeTargets(const Scene& scene, std::uint32_t seed, int perEdge) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::vec3> targets;
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  auto pos = [&](std::uint32_t v) { return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
  for (std::uint32_t v = 0; v < scene.positions.size(); ++v) targets.push_back(pos(v));
  for (const WtTriangle& t : scene.triangles)
    for (auto [a, b] : {std::pair{t.v0, t.v1}, std::pair{t.v1, t.v2}, std::pair{t.v2, t.v0}})
      edges.insert(std::minmax(a, b));
  for (auto [a, b] : edges) {
    targets.push_back(0.5f * (pos(a) + pos(b)));
    for (int k = 0; k < perEdge; ++k) {
      float s = u(rng);
      targets.push_back((1.0f - s) * pos(a) + s * pos(b));
    }
  }
  return targets;
}

/// Shoot from each origin at each target; count rays that find no surface.
int countLeaks(const Scene& scene, const std::vector<glm::vec3>& origins,
               const std::vector<glm::vec3>& targets) {
  std::vector<Ray> rays;
  for (const glm::vec3& o : origins)
    for (const glm::vec3& t : targets) {
      Ray r;
      r.origin = o;
      r.direction = glm::normalize(t - o);
      rays.push_back(r);
    }
  Tracer tracer(test::deviceContext(), scene);
  int leaks = 0;
  for (const RayHit& h : tracer.traceClosest(rays)) leaks += h.triangle == RayHit::kNoHit;
  std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays);
  for (std::uint8_t o : occluded) leaks += o == 0;
  return leaks;
}

TEST(Watertight, IcosphereFromInside) {
  for (glm::vec3 center : {glm::vec3(0.0f), glm::vec3(3.7f, -1.2f, 0.4f)}) {
    Scene scene = makeIcosphere(3, center, 1.0f, makeMaterial(glm::vec3(0.5f)));
    std::vector<glm::vec3> origins = {center, center + glm::vec3(0.3f, -0.2f, 0.1f),
                                      center + glm::vec3(-0.6f, 0.5f, 0.2f)};
    EXPECT_EQ(countLeaks(scene, origins, edgeTargets(scene, 1, 2)), 0);
  }
}

TEST(Watertight, BoxFromInsideAndOutside) {
  Scene scene = makeBox(glm::vec3(-1.0f), glm::vec3(1.0f), makeMaterial(glm::vec3(0.5f)));
  // inside, and outside on a diagonal so that every target is in front of a face
  std::vector<glm::vec3> inside = {glm::vec3(0.0f), glm::vec3(0.25f, -0.5f, 0.125f)};
  const int perEdge = int(test::testSize(64, 8));
  EXPECT_EQ(countLeaks(scene, inside, edgeTargets(scene, 2, perEdge)), 0);
  std::vector<glm::vec3> outside = {glm::vec3(3.0f, 2.0f, 2.5f)};
  std::vector<glm::vec3> visible;
  for (const glm::vec3& t : edgeTargets(scene, 3, perEdge))
    // edges shared by two visible faces; silhouette edges are grazing, not leaks
    if ((t.x > 0.99f) + (t.y > 0.99f) + (t.z > 0.99f) >= 2 && glm::all(glm::greaterThan(t, glm::vec3(-0.99f))))
      visible.push_back(t);
  EXPECT_EQ(countLeaks(scene, outside, visible), 0);
}

}  // namespace
}  // namespace wt
