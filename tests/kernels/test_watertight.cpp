// Watertightness: rays aimed exactly at the shared vertices and edges of
// closed meshes must never pass between the triangles, whichever builder made
// the BVH, traced one ray per work-item, in packets or, any hit, in streams
// (wt::countLeaks).
#include "bvh/builders.h"
#include "device_fixture.h"
#include "device/tracer.h"
#include "scene/generators.h"
#include "stress/stress.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <random>
#include <set>

namespace wt {
namespace {

constexpr BvhBuilder kBuilders[] = {BvhBuilder::Auto, BvhBuilder::Lbvh, BvhBuilder::Ploc, BvhBuilder::Sah};

/// Shoot from each origin at each target through every builder's tree; count
/// rays that find no surface, over all trees.
std::uint64_t countLeaks(const Scene& scene, const std::vector<glm::vec3>& origins,
                         const std::vector<glm::vec3>& targets) {
  std::uint64_t leaks = 0;
  for (BvhBuilder builder : kBuilders) {
    BvhBuildOptions options;
    options.builder = builder;
    for (int width : {8, 16}) {  // packets of either width (packetWidthFor)
      Tracer tracer(test::deviceContext(), scene, options, width);
      std::uint64_t rays = 0;
      const std::uint64_t leaked = wt::countLeaks(tracer, origins, targets, &rays);
      EXPECT_EQ(leaked, 0u) << bvhBuilderName(builder) << " tree, packets of " << width << ": " << leaked << " of "
                            << rays << " rays leaked";
      leaks += leaked;
    }
  }
  return leaks;
}

TEST(Watertight, IcosphereFromInside) {
  for (glm::vec3 center : {glm::vec3(0.0f), glm::vec3(3.7f, -1.2f, 0.4f)}) {
    Scene scene = makeIcosphere(3, center, 1.0f, makeMaterial(glm::vec3(0.5f)));
    std::vector<glm::vec3> origins = {center, center + glm::vec3(0.3f, -0.2f, 0.1f),
                                      center + glm::vec3(-0.6f, 0.5f, 0.2f)};
    EXPECT_EQ(countLeaks(scene, origins, edgeTargets(scene, 2, 1)), 0u);
  }
}

TEST(Watertight, PlacedCopiesFromInside) {
  // three turned, scaled and moved copies of one closed mesh: the auto
  // builder gives them one refitted tree (the other builders the whole)
  Scene mesh = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  const glm::vec3 centers[] = {glm::vec3(0.0f), glm::vec3(2.5f, 0.3f, -0.4f), glm::vec3(-0.7f, 2.8f, 1.1f)};
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 3; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), centers[c]);
    m = glm::rotate(m, 0.7f * float(c), glm::normalize(glm::vec3(1.0f, 2.0f, 0.5f + float(c))));
    transforms.push_back(glm::scale(m, glm::vec3(1.0f, 0.8f + 0.1f * float(c), 1.1f)));
  }
  Scene scene = placeCopies(mesh, transforms);
  std::vector<glm::vec3> origins;
  for (const glm::vec3& c : centers) origins.push_back(c + glm::vec3(0.1f, -0.15f, 0.05f));
  EXPECT_EQ(countLeaks(scene, origins, edgeTargets(scene, 1, 1)), 0u);
}

TEST(Watertight, HeightFieldFromAbove) {
  // Large enough for the LBVH's flat regions (the auto builder builds it with
  // the LBVH). From high above, rays steeper than any of the field's slopes
  // (at most about 2) see no silhouette: every one aimed at an inner vertex or
  // edge crosses the field.
  const Scene scene = makeBumpyGrid(70000);
  std::vector<glm::vec3> targets;
  const std::size_t stride = test::testSize(7, 61);
  std::size_t k = 0;
  for (const glm::vec3& t : edgeTargets(scene, 0, 4))
    if (std::abs(t.x) < 0.99f && std::abs(t.z) < 0.99f && k++ % stride == 0) targets.push_back(t);
  const std::vector<glm::vec3> origins = {glm::vec3(0.1f, 20.0f, 0.2f), glm::vec3(-0.4f, 15.0f, 0.3f)};
  EXPECT_EQ(countLeaks(scene, origins, targets), 0u);
}

TEST(Watertight, BoxFromInsideAndOutside) {
  Scene scene = makeBox(glm::vec3(-1.0f), glm::vec3(1.0f), makeMaterial(glm::vec3(0.5f)));
  // inside, and outside on a diagonal so that every target is in front of a face
  std::vector<glm::vec3> inside = {glm::vec3(0.0f), glm::vec3(0.25f, -0.5f, 0.125f)};
  const int perEdge = int(test::testSize(64, 8));
  EXPECT_EQ(countLeaks(scene, inside, edgeTargets(scene, perEdge, 2)), 0u);
  std::vector<glm::vec3> outside = {glm::vec3(3.0f, 2.0f, 2.5f)};
  std::vector<glm::vec3> visible;
  for (const glm::vec3& t : edgeTargets(scene, perEdge, 3))
    // edges shared by two visible faces; silhouette edges are grazing, not leaks
    if ((t.x > 0.99f) + (t.y > 0.99f) + (t.z > 0.99f) >= 2 && glm::all(glm::greaterThan(t, glm::vec3(-0.99f))))
      visible.push_back(t);
  EXPECT_EQ(countLeaks(scene, outside, visible), 0u);
}

}  // namespace
}  // namespace wt
