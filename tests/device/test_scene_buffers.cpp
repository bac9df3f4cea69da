// The scene as uploaded: each leaf-order triangle's corners in its block's
// lane (shared/types.h, WT_TRIANGLE_BLOCK), with the corner's vertex index
// in the index rows, and every triangle the BVH holds exactly once.
#include "device/scene_buffers.h"
#include "device_fixture.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace wt {
namespace {

TEST(SceneBuffers, BlocksHoldEachLeafTriangleCornersAndVertexIndices) {
  Scene scene = makeIcosphere(4, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  appendScene(scene, makeBumpyGrid(20000));
  ASSERT_GT(scene.positions.size(), 10000u);
  Context& context = test::deviceContext();
  SceneBuffers buffers(context, scene);
  const std::size_t triangles = scene.triangles.size() - buffers.skippedTriangles();
  ASSERT_EQ(buffers.leafOrder().size(), triangles);
  const std::size_t blockCount = (triangles + WT_TRIANGLE_BLOCK - 1) / WT_TRIANGLE_BLOCK;
  std::vector<float> blocks(48 * blockCount);
  context.queue().enqueueReadBuffer(buffers.triVerts, CL_TRUE, 0, blocks.size() * sizeof(float), blocks.data());
  std::vector<int> seen(scene.triangles.size(), 0);
  for (std::size_t leaf = 0; leaf < triangles; ++leaf) {
    const std::uint32_t sceneIndex = buffers.sceneTriangle(std::uint32_t(leaf));
    ASSERT_LT(sceneIndex, scene.triangles.size());
    ++seen[sceneIndex];
    ASSERT_EQ(buffers.leafTriangle(sceneIndex), leaf);
    const WtTriangle& t = scene.triangles[sceneIndex];
    const std::uint32_t expected[3] = {t.v0, t.v1, t.v2};
    const float* lane = blocks.data() + 48 * (leaf / 4) + leaf % 4;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t index;
      std::memcpy(&index, &lane[16 * k + 12], sizeof index);
      ASSERT_EQ(index, expected[k]) << "leaf triangle " << leaf << " corner " << k;
      const WtVec4& p = scene.positions[expected[k]];
      ASSERT_EQ(lane[16 * k + 0], p.x) << "leaf triangle " << leaf << " corner " << k;
      ASSERT_EQ(lane[16 * k + 4], p.y);
      ASSERT_EQ(lane[16 * k + 8], p.z);
    }
  }
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_LE(seen[i], 1) << "scene triangle " << i;
}

}  // namespace
}  // namespace wt
