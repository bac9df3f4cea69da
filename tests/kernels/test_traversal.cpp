// The kernels' closest-hit and any-hit traversal against a brute-force loop
// over every triangle, on random soups, for every BVH builder and leaf size.
#include "brute_force.h"
#include "bvh/builders.h"
#include "device_fixture.h"
#include "scene/generators.h"
#include "test_util.h"
#include "tree_param.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <tuple>

namespace wt {
namespace {

std::vector<Ray> randomRays(std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> box(-0.5f, 1.5f), unit(-1.0f, 1.0f), t01(0.0f, 1.0f);
  std::vector<Ray> rays(count);
  for (std::size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    r.origin = glm::vec3(box(rng), box(rng), box(rng));
    glm::vec3 d;
    do d = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-4f);
    r.direction = glm::normalize(d);
    // a mix of open rays, finite segments and rays starting ahead of the origin
    r.tmin = (i % 5 == 3) ? 0.3f * t01(rng) : 0.0f;
    r.tmax = (i % 3 == 1) ? 0.2f + t01(rng) : 1e30f;
  }
  // axis-parallel rays hit the slab test's zero-direction path
  for (std::size_t i = 0; i < std::min<std::size_t>(count, 300); i += 3) {
    int axis = int(i / 3) % 3;
    glm::vec3 d(0.0f);
    d[axis] = (i % 2) ? 1.0f : -1.0f;
    rays[i].direction = d;
  }
  return rays;
}

void expectAgreement(const Scene& scene, const std::vector<Ray>& rays, const BvhBuildOptions& options) {
  Tracer tracer(test::deviceContext(), scene, options);
  std::vector<RayHit> hits = tracer.traceClosest(rays);
  std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays);
  ASSERT_EQ(hits.size(), rays.size());
  int disagreements = 0, hitCount = 0, occlusionErrors = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    test::BruteHit want = test::bruteClosest(scene, rays[i]);
    hitCount += want.triangle != RayHit::kNoHit;
    if (!test::agrees(scene, rays[i], hits[i], want)) {
      if (++disagreements <= 5)
        ADD_FAILURE() << "ray " << i << ": kernel triangle " << hits[i].triangle << " t=" << hits[i].t
                      << ", brute force triangle " << want.triangle << " t=" << want.t;
    }
    // any-hit must agree with "closest hit exists", except at edge grazes
    bool wantOccluded = want.triangle != RayHit::kNoHit;
    if (bool(occluded[i]) != wantOccluded && !(wantOccluded && want.minBarycentric < 1e-5) &&
        !(bool(occluded[i]) && hits[i].triangle != RayHit::kNoHit))
      ++occlusionErrors;
  }
  EXPECT_EQ(disagreements, 0);
  EXPECT_EQ(occlusionErrors, 0);
  // the ray set must actually exercise hits and misses
  EXPECT_GT(hitCount, int(rays.size() / 10));
  EXPECT_LT(hitCount, int(rays.size()));
}

/// Every builder's tree at several leaf sizes: the kernels must not depend on how the tree was made.
class TraversalLeafSize : public test::TreeParamTest {};

TEST_P(TraversalLeafSize, RandomSoupMatchesBruteForce) {
  const BvhBuildOptions options = this->options();
  for (std::uint32_t seed : {1u, 2u}) {
    Scene scene = makeTriangleSoup(3000, seed, 0.15f);
    expectAgreement(scene, randomRays(test::testSize(4000, 500), seed + 100), options);
  }
}

TEST_P(TraversalLeafSize, ClosedSphereMatchesBruteForce) {
  const BvhBuildOptions options = this->options();
  Scene scene = makeIcosphere(3, glm::vec3(0.5f), 0.6f, makeMaterial(glm::vec3(0.5f)));
  expectAgreement(scene, randomRays(4000, 7), options);
}

TEST_P(TraversalLeafSize, TinySoupsMatchBruteForce) {
  // a root that is one leaf, and 4-wide nodes with empty slots
  const BvhBuildOptions options = this->options();
  for (std::uint32_t count : {1u, 2u, 3u, 5u, 6u, 9u, 13u}) {
    Scene scene = makeTriangleSoup(count, count, 0.9f);
    Tracer tracer(test::deviceContext(), scene, options);
    std::vector<Ray> rays = randomRays(2000, count + 40);
    std::vector<RayHit> hits = tracer.traceClosest(rays);
    std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays);
    int disagreements = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      test::BruteHit want = test::bruteClosest(scene, rays[i]);
      if (!test::agrees(scene, rays[i], hits[i], want) && ++disagreements <= 3)
        ADD_FAILURE() << count << " triangles, ray " << i << ": kernel triangle " << hits[i].triangle
                      << ", brute force " << want.triangle;
      bool wantOccluded = want.triangle != RayHit::kNoHit;
      if (bool(occluded[i]) != wantOccluded && !(wantOccluded && want.minBarycentric < 1e-5) &&
          !(bool(occluded[i]) && hits[i].triangle != RayHit::kNoHit))
        ADD_FAILURE() << count << " triangles, ray " << i << ": occluded " << int(occluded[i]);
    }
  }
}

// Leaf sizes 1 and 2 give 4-wide nodes over many small leaves, 8 few large ones.
INSTANTIATE_TEST_SUITE_P(LeafSizes, TraversalLeafSize,
                         ::testing::Combine(::testing::Values(BvhBuilder::Lbvh, BvhBuilder::Ploc, BvhBuilder::Sah),
                                            ::testing::Values(1, 2, 4, 8)),
                         test::treeParamName);

/// The auto builder's tree over placed copies (one tree per geometry,
/// refitted per copy): icospheres turned, scaled and moved, one flattened by
/// a zero scale, among a soup; the mesh has a zero-area triangle each copy
/// loses. The same answers as brute force at every leaf size.
TEST(Traversal, PlacedCopiesMatchBruteForce) {
  Scene mesh = makeIcosphere(2, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  mesh.triangles[7].v2 = mesh.triangles[7].v0;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> at(-0.2f, 1.2f), turn(-3.0f, 3.0f), size(0.05f, 0.3f);
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 24; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(at(rng), at(rng), at(rng)));
    m = glm::rotate(m, turn(rng), glm::normalize(glm::vec3(turn(rng), turn(rng), 1.0f)));
    transforms.push_back(glm::scale(m, c == 5 ? glm::vec3(0.0f) : glm::vec3(size(rng), size(rng), size(rng))));
  }
  Scene scene = makeTriangleSoup(600, 4, 0.15f);
  appendScene(scene, placeCopies(mesh, transforms));
  for (int leaf : {1, 4, 8}) {
    SCOPED_TRACE("leaf size " + std::to_string(leaf));
    BvhBuildOptions options;
    options.builder = BvhBuilder::Auto;
    options.maxLeafSize = leaf;
    expectAgreement(scene, randomRays(test::testSize(4000, 250), 31 + leaf), options);
    // the copies' shared tree is what was traced (all but the flattened one)
    EXPECT_EQ(Tracer(test::deviceContext(), scene, options).sceneBuffers().bvhStats().copiesPlaced, 23u);
  }
}

/// A height field large enough for the LBVH's flat regions (keys with the
/// height last, host/bvh/lbvh.cpp), through the LBVH and the auto builder (which
/// builds it with the LBVH) at leaf sizes 1 and 8.
TEST(Traversal, FlatRegionsMatchBruteForce) {
  const Scene scene = makeBumpyGrid(70000);
  ASSERT_GT(scene.triangles.size(), 65536u);
  for (BvhBuilder builder : {BvhBuilder::Lbvh, BvhBuilder::Auto})
    for (int leaf : {1, 8}) {
      SCOPED_TRACE(std::string(bvhBuilderName(builder)) + ", leaf size " + std::to_string(leaf));
      BvhBuildOptions options;
      options.builder = builder;
      options.maxLeafSize = leaf;
      expectAgreement(scene, randomRays(test::testSize(1000, 250), 57 + leaf), options);
      EXPECT_GT(Tracer(test::deviceContext(), scene, options).sceneBuffers().bvhStats().flatRegions, 0u);
    }
}

TEST(Traversal, DegenerateTrianglesAreNeverHit) {
  // zero-area triangles: a point and a segment, among ordinary ones
  Scene scene = makeTriangleSoup(50, 3, 0.2f);
  std::uint32_t base = std::uint32_t(scene.positions.size());
  for (glm::vec3 p : {glm::vec3(0.5f), glm::vec3(0.5f), glm::vec3(0.5f), glm::vec3(0.2f), glm::vec3(0.4f),
                      glm::vec3(0.6f)}) {
    scene.positions.push_back({p.x, p.y, p.z, 0});
    scene.normals.push_back({0, 0, 0, 0});
    scene.texcoords.emplace_back(0.0f);
  }
  scene.triangles.push_back({base, base + 1, base + 2, 0});
  scene.triangles.push_back({base + 3, base + 4, base + 5, 0});
  std::vector<Ray> rays;
  for (int i = 0; i < 64; ++i) {
    Ray r;
    r.origin = glm::vec3(0.5f) - glm::vec3(std::cos(i * 0.1f), std::sin(i * 0.1f), 0.3f);
    r.direction = glm::normalize(glm::vec3(0.5f) - r.origin);
    rays.push_back(r);
  }
  Tracer tracer(test::deviceContext(), scene);
  for (const RayHit& h : tracer.traceClosest(rays)) {
    EXPECT_NE(h.triangle, base / 3);
    EXPECT_NE(h.triangle, base / 3 + 1);
  }
}

TEST(Traversal, NonFiniteRaysMissAndStayInTheTree) {
  // A NaN or infinite origin or direction turns the slab test of an empty
  // child slot (lo = +inf, hi = -inf) into NaN on every axis, which fmin and
  // fmax drop: the slot passed and traversal read node 0xffffffff (PoCL
  // crashed; Oclgrind reported the read and then never finished; the
  // self-intersection stress rows found it too, from a direction that float
  // rounding 1e8 from the origin had made 0/0). Such a ray hits nothing, and
  // carries no light: it counts as occluded.
  Scene scene = makeTriangleSoup(200, 11, 0.1f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  std::vector<Ray> rays;
  for (glm::vec3 o : {glm::vec3(nan, 0.5f, 0.5f), glm::vec3(0.5f, inf, 0.5f), glm::vec3(0.5f, 0.5f, -inf),
                      glm::vec3(nan), glm::vec3(inf), glm::vec3(0.5f, 0.5f, -2.0f)})
    for (glm::vec3 d : {glm::vec3(0.0f, 0.0f, 1.0f), glm::vec3(nan, 0.0f, 1.0f), glm::vec3(0.0f, inf, 1.0f),
                        glm::vec3(nan), glm::vec3(inf), glm::vec3(-inf, inf, inf), glm::vec3(0.3f, -0.2f, 0.9f)}) {
      auto finite = [](glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
      if (finite(o) && finite(d)) continue;
      Ray r;
      r.origin = o;
      r.direction = d;
      rays.push_back(r);
    }
  Tracer tracer(test::deviceContext(), scene);
  std::vector<RayHit> hits = tracer.traceClosest(rays);
  std::vector<std::uint8_t> occluded = tracer.traceOccluded(rays);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(hits[i].triangle, RayHit::kNoHit) << "ray " << i;
    EXPECT_EQ(occluded[i], 1) << "ray " << i;
  }
}

TEST(Traversal, EmptySceneMissesEverything) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  Tracer tracer(test::deviceContext(), scene);
  std::vector<Ray> rays = randomRays(100, 5);
  for (const RayHit& h : tracer.traceClosest(rays)) EXPECT_EQ(h.triangle, RayHit::kNoHit);
  for (std::uint8_t o : tracer.traceOccluded(rays)) EXPECT_EQ(o, 0);
}

}  // namespace
}  // namespace wt
