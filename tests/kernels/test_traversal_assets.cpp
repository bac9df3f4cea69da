// Traversal against brute force on real meshes from ../shared/assets.
#include "brute_force.h"
#include "device_fixture.h"
#include "scene/gltf_loader.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <random>

namespace wt {
namespace {

/// Rays from a sphere around the mesh towards random points in its bounds.
std::vector<Ray> raysAround(const Scene& scene, std::size_t count, std::uint32_t seed) {
  Aabb box = scene.bounds();
  glm::vec3 c = box.center();
  float r = glm::length(box.extent());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-1.0f, 1.0f);
  std::vector<Ray> rays(count);
  for (Ray& ray : rays) {
    glm::vec3 d;
    do d = glm::vec3(s(rng), s(rng), s(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-4f);
    ray.origin = c + r * glm::normalize(d);
    glm::vec3 target = box.lo + glm::vec3(u(rng), u(rng), u(rng)) * box.extent();
    ray.direction = glm::normalize(target - ray.origin);
  }
  return rays;
}

void checkMesh(const std::filesystem::path& file, std::size_t rayCount) {
  Scene scene = loadGltf(file.string());
  ASSERT_GT(scene.triangles.size(), 0u);
  std::vector<Ray> rays = raysAround(scene, rayCount, 11);
  Tracer tracer(test::deviceContext(), scene);
  std::vector<RayHit> hits = tracer.traceClosest(rays);
  int disagreements = 0, hitCount = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    test::BruteHit want = test::bruteClosest(scene, rays[i]);
    hitCount += want.triangle != RayHit::kNoHit;
    if (!test::agrees(scene, rays[i], hits[i], want) && ++disagreements <= 5)
      ADD_FAILURE() << file.filename() << " ray " << i << ": kernel " << hits[i].triangle << " t="
                    << hits[i].t << ", brute force " << want.triangle << " t=" << want.t;
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(hitCount, int(rays.size() / 10));
}

TEST(TraversalAssets, SuzanneMatchesBruteForce) {
  WT_REQUIRE_ASSET(file, "gltf/Suzanne/glTF/Suzanne.gltf");
  checkMesh(file, 3000);
}

TEST(TraversalAssets, DamagedHelmetMatchesBruteForce) {
  WT_REQUIRE_ASSET(file, "gltf/DamagedHelmet/glTF/DamagedHelmet.gltf");
  checkMesh(file, 1000);
}

}  // namespace
}  // namespace wt
