// The scene as uploaded: each triangle's corners in leaf order, with the
// corner's vertex index in w, tagged so that the lane is a normal float
// (shared/types.h, WT_VERTEX_TAG: arithmetic on a subnormal lane costs a
// microcode assist per operation on x86).
#include "device/scene_buffers.h"
#include "device_fixture.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

namespace wt {
namespace {

TEST(SceneBuffers, CornersCarryTheirVertexIndexInANormalFloatLane) {
  // enough vertices that untagged indices would span zero and the subnormals
  Scene scene = makeIcosphere(4, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  appendScene(scene, makeBumpyGrid(20000));
  ASSERT_GT(scene.positions.size(), 10000u);
  Context& context = test::deviceContext();
  SceneBuffers buffers(context, scene);
  const std::size_t triangles = scene.triangles.size() - buffers.skippedTriangles();
  std::vector<WtVec4> corners(3 * triangles);
  context.queue().enqueueReadBuffer(buffers.triVerts, CL_TRUE, 0, corners.size() * sizeof(WtVec4), corners.data());
  for (std::size_t leaf = 0; leaf < triangles; ++leaf) {
    const WtTriangle& t = scene.triangles[buffers.sceneTriangle(std::uint32_t(leaf))];
    const std::uint32_t expected[3] = {t.v0, t.v1, t.v2};
    for (int k = 0; k < 3; ++k) {
      const WtVec4& c = corners[3 * leaf + std::size_t(k)];
      std::uint32_t bits;
      std::memcpy(&bits, &c.w, sizeof bits);
      ASSERT_EQ(bits & WT_VERTEX_INDEX, expected[k]) << "leaf triangle " << leaf << " corner " << k;
      ASSERT_EQ(std::fpclassify(c.w), FP_NORMAL) << "leaf triangle " << leaf << " corner " << k << ": w bits " << bits;
      const WtVec4& p = scene.positions[expected[k]];
      ASSERT_EQ(c.x, p.x);
      ASSERT_EQ(c.y, p.y);
      ASSERT_EQ(c.z, p.z);
    }
  }
}

}  // namespace
}  // namespace wt
