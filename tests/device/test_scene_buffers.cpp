// The scene as uploaded: each leaf-order triangle's corners in its block's
// lane (shared/types.h, WT_TRIANGLE_BLOCK), its vertex indices and material
// in tri_info, and every triangle the BVH holds exactly once.
#include "device/scene_buffers.h"
#include "device_fixture.h"
#include "scene/generators.h"
#include "texture_helpers.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <vector>

namespace wt {
namespace {

TEST(SceneBuffers, BlocksHoldEachLeafTriangleCornersAndInfoItsIndicesAndMaterial) {
  Scene scene = makeIcosphere(4, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  appendScene(scene, makeBumpyGrid(20000));
  ASSERT_GT(scene.positions.size(), 10000u);
  Context& context = test::deviceContext();
  SceneBuffers buffers(context, scene);
  const std::size_t triangles = scene.triangles.size() - buffers.skippedTriangles();
  ASSERT_EQ(buffers.leafOrder().size(), triangles);
  const std::size_t blockCount = (triangles + WT_TRIANGLE_BLOCK - 1) / WT_TRIANGLE_BLOCK;
  std::vector<float> blocks(4 * WT_TRIANGLE_BLOCK_ROWS * blockCount);
  context.queue().enqueueReadBuffer(buffers.triVerts, CL_TRUE, 0, blocks.size() * sizeof(float), blocks.data());
  std::vector<cl_uint4> info(triangles);
  context.queue().enqueueReadBuffer(buffers.triangleInfo, CL_TRUE, 0, info.size() * sizeof(cl_uint4), info.data());
  std::vector<int> seen(scene.triangles.size(), 0);
  for (std::size_t leaf = 0; leaf < triangles; ++leaf) {
    const std::uint32_t sceneIndex = buffers.sceneTriangle(std::uint32_t(leaf));
    ASSERT_LT(sceneIndex, scene.triangles.size());
    ++seen[sceneIndex];
    ASSERT_EQ(buffers.leafTriangle(sceneIndex), leaf);
    const WtTriangle& t = scene.triangles[sceneIndex];
    const std::uint32_t expected[3] = {t.v0, t.v1, t.v2};
    const float* lane = blocks.data() + 4 * WT_TRIANGLE_BLOCK_ROWS * (leaf / 4) + leaf % 4;
    ASSERT_EQ(info[leaf].s[3], t.material) << "leaf triangle " << leaf;
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(info[leaf].s[k], expected[k]) << "leaf triangle " << leaf << " corner " << k;
      const WtVec4& p = scene.positions[expected[k]];
      ASSERT_EQ(lane[12 * k + 0], p.x) << "leaf triangle " << leaf << " corner " << k;
      ASSERT_EQ(lane[12 * k + 4], p.y);
      ASSERT_EQ(lane[12 * k + 8], p.z);
    }
  }
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_LE(seen[i], 1) << "scene triangle " << i;
}

TEST(SceneBuffers, TexelsAreReadInPlaceOnlyWhereTheSceneOutlivesTheBuffers) {
  // in place, a CPU device reads the scene's own texel array (no copy, no
  // second set of pages); otherwise the buffer holds a copy. The device sees
  // the same words either way.
  Scene scene = makeIcosphere(1, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));
  test::setBaseColorTexture(scene, 0, test::addCheckerTexture(scene, 64));
  ASSERT_GT(scene.textures.texels.size(), 64u * 64u);
  Context& context = test::deviceContext();
  for (bool inPlace : {false, true}) {
    BvhBuildOptions options;
    options.texelsInPlace = inPlace;
    SceneBuffers buffers(context, scene, options);
    ASSERT_TRUE(buffers.hasTextures());
    const void* host = buffers.texels.getInfo<CL_MEM_HOST_PTR>();
    EXPECT_EQ(host == scene.textures.texels.data(), inPlace && context.info().isCpu) << "in place: " << inPlace;
    ASSERT_EQ(buffers.texels.getInfo<CL_MEM_SIZE>(), scene.textures.texels.size() * sizeof(wt_uint));
    std::vector<wt_uint> words(scene.textures.texels.size());
    context.queue().enqueueReadBuffer(buffers.texels, CL_TRUE, 0, words.size() * sizeof(wt_uint), words.data());
    EXPECT_EQ(words, scene.textures.texels) << "in place: " << inPlace;
  }
}

TEST(SceneBuffers, CopiesThatLostTheSameTrianglesShareAGeometry) {
  // a mesh with a zero-area triangle (a sphere's pole, say): every copy
  // loses it and the copies still share a geometry; a copy flattened by a
  // zero scale loses all of its triangles and is no instance at all; a copy
  // that lost another triangle gets a geometry of its own
  Scene mesh = makeTriangleSoup(6, 2, 0.2f);
  mesh.triangles[2].v2 = mesh.triangles[2].v1;  // zero area
  const std::vector<glm::mat4> transforms = {glm::mat4(1.0f), glm::translate(glm::mat4(1.0f), glm::vec3(2, 0, 0)),
                                             glm::scale(glm::mat4(1.0f), glm::vec3(0.0f)),
                                             glm::translate(glm::mat4(1.0f), glm::vec3(0, 2, 0))};
  Scene scene = makeTriangleSoup(5, 9, 0.2f);
  appendScene(scene, placeCopies(mesh, transforms));
  scene.triangles[5 + 3 * 6 + 4].v0 = scene.triangles[5 + 3 * 6 + 4].v1;  // the last copy's fifth triangle
  std::vector<std::uint32_t> bvhToScene;
  for (std::uint32_t i = 0; i < scene.triangles.size(); ++i) {
    const bool lost = i == 5 + 2 || i == 5 + 6 + 2 || (i >= 5 + 12 && i < 5 + 18) || i == 5 + 18 + 2 || i == 5 + 18 + 4;
    if (!lost) bvhToScene.push_back(i);
  }
  const std::vector<BvhInstance> instances = bvhInstances(scene, bvhToScene);
  ASSERT_EQ(instances.size(), 3u);
  EXPECT_EQ(instances[0].first, 5u);
  EXPECT_EQ(instances[0].count, 5u);
  EXPECT_EQ(instances[1].first, 10u);
  EXPECT_EQ(instances[1].count, 5u);
  EXPECT_EQ(instances[0].geometry, instances[1].geometry);
  EXPECT_EQ(instances[2].first, 15u);
  EXPECT_EQ(instances[2].count, 4u);
  EXPECT_NE(instances[2].geometry, instances[0].geometry);
}

}  // namespace
}  // namespace wt
