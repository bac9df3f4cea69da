// Stream traversal of any-hit queries (kernels/bvh_stream.cl): the same
// answer as one ray per work-item on every ray, and the brute-force answer,
// for every builder and leaf size; windows and streams that end part-way,
// rays that are not finite, and scenes with nothing in them.
#include "brute_force.h"
#include "bvh/builders.h"
#include "device_fixture.h"
#include "scene/generators.h"
#include "test_util.h"
#include "tree_param.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace wt {
namespace {

/// Shadow rays as a renderer makes them: from a point on a triangle (which
/// the ray skips) to a point on another triangle or anywhere in the unit
/// cube around the scene, stopping 1e-4 short; and, every fifth, an open
/// random ray from a random point (no triangle skipped).
std::vector<Ray> shadowRays(const Scene& scene, std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f), box(-0.25f, 1.25f), unit(-1.0f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> pick(0, std::uint32_t(scene.triangles.size() - 1));
  auto pointOn = [&](std::uint32_t tri) {
    const WtTriangle& t = scene.triangles[tri];
    float a = std::sqrt(u01(rng)), b = u01(rng);
    auto p = [&](std::uint32_t v) { return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z); };
    return (1.0f - a) * p(t.v0) + a * (1.0f - b) * p(t.v1) + a * b * p(t.v2);
  };
  std::vector<Ray> rays;
  rays.reserve(count);
  while (rays.size() < count) {
    Ray r;
    if (rays.size() % 5 == 4) {
      r.origin = glm::vec3(box(rng), box(rng), box(rng));
      glm::vec3 d;
      do d = glm::vec3(unit(rng), unit(rng), unit(rng));
      while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-4f);
      r.direction = glm::normalize(d);
    } else {
      const std::uint32_t from = pick(rng);
      r.origin = pointOn(from);
      r.skip = from;
      const glm::vec3 target = rays.size() % 2 ? pointOn(pick(rng)) : glm::vec3(box(rng), box(rng), box(rng));
      const glm::vec3 d = target - r.origin;
      const float distance = glm::length(d);
      if (!(distance > 1e-4f)) continue;
      r.direction = d / distance;
      r.tmax = (1.0f - 1e-4f) * distance;
    }
    rays.push_back(r);
  }
  return rays;
}

/// Stream answers equal single-ray answers ray by ray; rays that skip no
/// triangle also agree with brute force (but for float-precision grazes).
/// The streams ask for each node's children early (WT_STREAM_PREFETCH), which
/// these small scenes would not get by their size; the edge test below runs
/// without.
void expectStreamsMatch(const Scene& scene, const std::vector<Ray>& rays, const BvhBuildOptions& options) {
  Tracer tracer(test::deviceContext(), scene, options, 0, StreamPrefetch::kOn);
  ASSERT_TRUE(tracer.streamPrefetch());
  const std::vector<std::uint8_t> single = tracer.traceOccluded(rays, Traversal::kSingle);
  tracer.traceClosest(rays);  // leaves hits, not flags, in the output a ray left unwritten would show
  const std::vector<std::uint8_t> stream = tracer.traceOccluded(rays, Traversal::kStream);
  ASSERT_EQ(stream.size(), rays.size());
  int differ = 0, wrong = 0, blocked = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    blocked += stream[i] != 0;
    if (stream[i] != single[i] && ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": stream " << int(stream[i]) << ", single " << int(single[i]);
    if (rays[i].skip != RayHit::kNoHit) continue;
    const test::BruteHit want = test::bruteClosest(scene, rays[i]);
    const bool wantBlocked = want.triangle != RayHit::kNoHit;
    if (bool(stream[i]) != wantBlocked && !(wantBlocked && want.minBarycentric < 1e-5) && ++wrong <= 5)
      ADD_FAILURE() << "ray " << i << ": stream " << int(stream[i]) << ", brute force triangle " << want.triangle;
  }
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(wrong, 0);
  // the set must exercise both answers
  EXPECT_GT(blocked, int(rays.size() / 10));
  EXPECT_LT(blocked, int(rays.size() * 9 / 10));
}

class StreamTraversal : public test::TreeParamTest {};

TEST_P(StreamTraversal, ShadowRaysOnASoupMatchSingleRays) {
  Scene scene = makeTriangleSoup(3000, 5, 0.15f);
  expectStreamsMatch(scene, shadowRays(scene, test::testSize(3000, 1000), 11), options());
}

TEST_P(StreamTraversal, ShadowRaysOnAClosedSphereMatchSingleRays) {
  Scene scene = makeIcosphere(3, glm::vec3(0.5f), 0.6f, makeMaterial(glm::vec3(0.5f)));
  expectStreamsMatch(scene, shadowRays(scene, test::testSize(3000, 1000), 12), options());
}

INSTANTIATE_TEST_SUITE_P(Trees, StreamTraversal,
                         ::testing::Combine(::testing::Values(BvhBuilder::Auto, BvhBuilder::Lbvh, BvhBuilder::Ploc,
                                                              BvhBuilder::Sah),
                                            ::testing::Values(1, 4, 8)),
                         test::treeParamName);

TEST(StreamTraversalEdges, PartialWindowsRaysNotFiniteAndEmptyScenes) {
  // batches that end inside a stream and inside a window; windows whose
  // rays all share an octant (several streams of one octant) or take the
  // eight in turn; rays that are not finite (blocked: they carry no light)
  Scene scene = makeTriangleSoup(test::testSize(800, 200), 8, 0.2f);
  std::vector<Ray> rays = shadowRays(scene, 1200, 13);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (std::size_t i = 7; i < rays.size(); i += 41) rays[i].direction.z = (i % 2) ? nan : inf;
  for (std::size_t i = 19; i < rays.size(); i += 53) rays[i].origin.y = nan;
  for (std::size_t i = 256; i < 512; ++i) rays[i].direction = glm::normalize(glm::abs(rays[i].direction) + 0.01f);
  for (std::size_t i = 512; i < 768; ++i) {
    glm::vec3 d = glm::abs(rays[i].direction) + 0.01f;
    for (int axis = 0; axis < 3; ++axis)
      if ((i >> axis) & 1) d[axis] = -d[axis];
    rays[i].direction = glm::normalize(d);
  }
  Tracer tracer(test::deviceContext(), scene, {}, 0, StreamPrefetch::kOff);
  ASSERT_FALSE(tracer.streamPrefetch());
  for (std::size_t count : {std::size_t(1), std::size_t(63), std::size_t(64), std::size_t(65), std::size_t(255),
                            std::size_t(256), std::size_t(257), rays.size()}) {
    SCOPED_TRACE(std::to_string(count) + " rays");
    std::vector<Ray> batch(rays.end() - std::ptrdiff_t(count), rays.end());
    const std::vector<std::uint8_t> single = tracer.traceOccluded(batch, Traversal::kSingle);
    tracer.traceClosest(batch);  // no flags left behind in the output
    const std::vector<std::uint8_t> stream = tracer.traceOccluded(batch, Traversal::kStream);
    ASSERT_EQ(stream.size(), count);
    for (std::size_t i = 0; i < count; ++i) {
      EXPECT_EQ(stream[i], single[i]) << "ray " << i;
      const Ray& r = batch[i];
      if (!std::isfinite(r.origin.y) || !std::isfinite(r.direction.z)) {
        EXPECT_EQ(stream[i], 1) << "ray " << i;
      }
    }
  }
  // closest-hit queries given streams are traced one ray per work-item
  std::vector<RayHit> a = tracer.traceClosest(rays, Traversal::kStream), b = tracer.traceClosest(rays);
  for (std::size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(a[i].triangle, b[i].triangle) << "ray " << i;

  Scene empty;
  empty.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  Tracer none(test::deviceContext(), empty);
  const std::vector<std::uint8_t> single = none.traceOccluded(rays, Traversal::kSingle);
  none.traceClosest(rays);
  EXPECT_EQ(none.traceOccluded(rays, Traversal::kStream), single);
  // nothing blocks but the rays that are not finite
  std::size_t blocked = 0;
  for (std::uint8_t o : single) blocked += o;
  EXPECT_GT(blocked, 0u);
  EXPECT_LT(blocked, rays.size() / 10);
}

TEST(StreamTraversalEdges, ChildrenAskedForWhereTheSceneOutgrowsTheCache) {
  // streamPrefetchFor: by the scene's bytes against the device's cache (a
  // device that reports no cache gets the requests); a tracer's own choice
  // follows its scene's uploaded bytes unless told
  DeviceInfo device = test::deviceContext().info();
  device.globalCacheBytes = std::uint64_t{32} << 20;
  EXPECT_FALSE(streamPrefetchFor(device, 1u << 20));       // DamagedHelmet, about 1 MB
  EXPECT_FALSE(streamPrefetchFor(device, std::size_t{32} << 20));
  EXPECT_TRUE(streamPrefetchFor(device, (std::size_t{32} << 20) + 1));
  EXPECT_TRUE(streamPrefetchFor(device, 57u * 1000000u));  // the 1 M-triangle scenes
  device.globalCacheBytes = 0;
  EXPECT_TRUE(streamPrefetchFor(device, 1024));

  Scene scene = makeTriangleSoup(200, 3, 0.2f);
  Tracer automatic(test::deviceContext(), scene);
  EXPECT_EQ(automatic.streamPrefetch(),
            streamPrefetchFor(test::deviceContext().info(), automatic.sceneBuffers().uploadedBytes));
  EXPECT_TRUE(Tracer(test::deviceContext(), scene, {}, 0, StreamPrefetch::kOn).streamPrefetch());
}

}  // namespace
}  // namespace wt
