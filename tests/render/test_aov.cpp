// AOVs (kernels/aov.cl, render --aov) against the values the geometry and
// the materials fix: a plane seen head-on by an orthographic camera, a
// mirror in front of a diffuse wall; the EXR's named layers; and a render
// without AOVs unchanged bit for bit by their code.
#include "output/debug_view.h"
#include "output/image_io.h"
#include "render/render_helpers.h"
#include "test_util.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cstring>

namespace wt {
namespace {

constexpr int kSize = 16;
constexpr float kHeight = 2.5f;  // the camera above the floor
constexpr float kHalfView = 1.0f;

RenderSettings aovSettings(bool aovs) {
  RenderSettings s;
  s.width = s.height = kSize;
  s.maxBounces = 4;
  s.aovs = aovs;
  s.background = glm::vec3(0.25f, 0.5f, 1.0f);
  return s;
}

/// A floor of `material` filling the view of a camera kHeight above it, looking down.
Scene floorScene(const WtMaterial& material) {
  Scene scene = test::makeFloor(4.0f * kHalfView, 0.0f, material);
  scene.camera = test::topDownCamera(glm::vec3(0.0f, kHeight, 0.0f), kHalfView);
  return scene;
}

TEST(Aov, PlaneSeenHeadOnHasItsAnalyticValues) {
  const glm::vec3 albedo(0.6f, 0.3f, 0.2f);
  const int spp = 4;
  Image image = test::render(floorScene(makeMaterial(albedo)), aovSettings(true), spp);
  const Aovs& a = image.aovs;
  ASSERT_FALSE(a.empty());
  const std::size_t pixels = std::size_t(kSize) * kSize;
  ASSERT_EQ(a.depth.size(), pixels);
  int bad = 0;
  for (std::size_t p = 0; p < pixels && bad < 5; ++p) {
    const int x = int(p % kSize), y = int(p / kSize);
    // every sample meets the plane at the camera's height, along a normal of exactly (0, 1, 0)
    for (int c = 0; c < 3; ++c) {
      if (std::abs(a.albedo[3 * p + c] - albedo[c]) > 1e-6f) ++bad, ADD_FAILURE() << "albedo at " << p;
      if (std::abs(a.normal[3 * p + c] - (c == 1 ? 1.0f : 0.0f)) > 1e-6f) ++bad, ADD_FAILURE() << "normal at " << p;
    }
    if (std::abs(a.depth[p] - kHeight) > 1e-5f * kHeight) ++bad, ADD_FAILURE() << "depth " << a.depth[p] << " at " << p;
    // the mean hit lies inside the pixel's footprint on the plane (x right, image top at -z)
    const float pixel = 2.0f * kHalfView / kSize;
    const float x0 = -kHalfView + x * pixel, z0 = -kHalfView + y * pixel;
    const float px = a.position[3 * p], py = a.position[3 * p + 1], pz = a.position[3 * p + 2];
    if (std::abs(py) > 1e-5f || px < x0 || px > x0 + pixel || pz < z0 || pz > z0 + pixel)
      ++bad, ADD_FAILURE() << "position (" << px << ", " << py << ", " << pz << ") outside pixel " << x << "," << y;
    if (a.material[p] != 0u) ++bad, ADD_FAILURE() << "material " << a.material[p] << " at " << p;
    if (a.instance[p] != Aovs::kNoId) ++bad, ADD_FAILURE() << "instance " << a.instance[p] << " at " << p;
    if (a.primitive[p] == Aovs::kNoId) ++bad, ADD_FAILURE() << "no primitive at " << p;
  }
  EXPECT_EQ(bad, 0);
}

TEST(Aov, MissesHaveTheEnvironmentAndNoDepth) {
  // the floor far below the view: every camera ray escapes
  Scene scene = test::makeFloor(0.1f, 0.0f, makeMaterial(glm::vec3(0.5f)));
  scene.camera = test::topDownCamera(glm::vec3(5.0f, kHeight, 5.0f), 0.5f);
  RenderSettings settings = aovSettings(true);
  Image image = test::render(scene, settings, 2);
  for (std::size_t p = 0; p < image.aovs.depth.size(); ++p) {
    ASSERT_TRUE(std::isinf(image.aovs.depth[p])) << p;
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(image.aovs.albedo[3 * p + c], settings.background[c]) << p;
      ASSERT_EQ(image.aovs.normal[3 * p + c], 0.0f) << p;
    }
    ASSERT_EQ(image.aovs.material[p], Aovs::kNoId);
    ASSERT_EQ(image.aovs.bounces[p], 0.0f);
  }
}

/// A floor mirror (metallic, of `roughness`) under the camera and a diffuse
/// ceiling above the camera facing down: the mirror's reflection of the
/// camera rays meets the ceiling head-on.
Scene mirrorScene(float roughness, glm::vec3 wallAlbedo) {
  Scene scene = floorScene(makePbrMaterial(glm::vec3(0.9f, 0.8f, 0.7f), 1.0f, roughness));
  appendScene(scene, test::makeFloor(20.0f, 2.0f * kHeight, makeMaterial(wallAlbedo), /*faceDown=*/true));
  return scene;
}

TEST(Aov, AlbedoAndNormalLookThroughASmoothMirror) {
  const glm::vec3 wall(0.2f, 0.5f, 0.7f);
  const int spp = 4;
  Image image = test::render(mirrorScene(0.0f, wall), aovSettings(true), spp);
  const Aovs& a = image.aovs;
  for (std::size_t p = 0; p < a.depth.size(); ++p) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(a.albedo[3 * p + c], wall[c], 1e-6f) << "albedo at " << p;
      ASSERT_NEAR(a.normal[3 * p + c], c == 1 ? -1.0f : 0.0f, 1e-6f) << "normal at " << p;
    }
    // depth, position and ids are the camera hit's: the mirror
    ASSERT_NEAR(a.depth[p], kHeight, 1e-5f * kHeight);
    ASSERT_EQ(a.material[p], 0u);
    ASSERT_GE(a.bounces[p], 2.0f);  // the mirror and the ceiling at least
  }
}

TEST(Aov, AlbedoStopsAtARoughMirror) {
  // the same mirror made rough is the first non-specular hit: its own colour and normal
  Image image = test::render(mirrorScene(0.5f, glm::vec3(0.2f, 0.5f, 0.7f)), aovSettings(true), 2);
  const Aovs& a = image.aovs;
  const glm::vec3 mirror(0.9f, 0.8f, 0.7f);
  for (std::size_t p = 0; p < a.depth.size(); ++p)
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(a.albedo[3 * p + c], mirror[c], 1e-6f) << "albedo at " << p;
      ASSERT_NEAR(a.normal[3 * p + c], c == 1 ? 1.0f : 0.0f, 1e-6f) << "normal at " << p;
    }
}

TEST(Aov, InstanceIdsTellTheCopiesApart) {
  // one grid stored once and placed twice, side by side: the left half of the
  // view sees one instance, the right half the other
  Scene grid = makeGrid(8, glm::vec3(0.0f), 0.5f, glm::vec3(1, 0, 0), glm::vec3(0, 0, 1),
                        makeMaterial(glm::vec3(0.5f)));
  const glm::mat4 copies[] = {glm::translate(glm::mat4(1.0f), glm::vec3(-0.5f, 0.0f, 0.0f)),
                              glm::translate(glm::mat4(1.0f), glm::vec3(0.5f, 0.0f, 0.0f))};
  Scene scene = placeCopies(grid, copies);
  scene.camera = test::topDownCamera(glm::vec3(0.0f, kHeight, 0.0f), kHalfView);
  RenderSettings settings = aovSettings(true);
  settings.instancing = Instancing::On;
  Renderer renderer(test::deviceContext(), scene, settings);
  ASSERT_EQ(renderer.sceneBuffers().instanceCount(), 2u);
  renderer.renderSample();
  const Aovs a = renderer.readImage().aovs;
  // rows kSize/4 + 1 .. 3 kSize/4 - 2 lie on the copies (z in [-0.5, 0.5]); the others miss
  const std::uint32_t left = a.instance[std::size_t(kSize / 2) * kSize + 1];
  const std::uint32_t right = a.instance[std::size_t(kSize / 2) * kSize + kSize - 2];
  EXPECT_NE(left, Aovs::kNoId);
  EXPECT_NE(right, Aovs::kNoId);
  EXPECT_NE(left, right);
  for (int y = kSize / 4 + 1; y < 3 * kSize / 4 - 1; ++y)
    for (int x = 0; x < kSize; ++x) {
      if (x == kSize / 2 - 1 || x == kSize / 2) continue;  // the seam: jittered across it
      const std::size_t p = std::size_t(y) * kSize + x;
      ASSERT_EQ(a.instance[p], x < kSize / 2 ? left : right) << x << "," << y;
      ASSERT_NE(a.primitive[p], Aovs::kNoId) << x << "," << y;
    }
  EXPECT_EQ(a.instance[0], Aovs::kNoId);  // a corner: no hit
  EXPECT_EQ(a.material[0], Aovs::kNoId);
}

TEST(Aov, BvhCostCountsTheNodesACameraRayVisits) {
  // two triangles: a tree of one node, which every camera ray visits once
  RenderSettings settings = aovSettings(true);
  settings.bvhCost = true;
  Image image = test::render(floorScene(makeMaterial(glm::vec3(0.5f))), settings, 2);
  ASSERT_EQ(image.aovs.bvhCost.size(), std::size_t(kSize) * kSize);
  for (float c : image.aovs.bvhCost) ASSERT_EQ(c, 1.0f);
  // a grid of 32 x 32 quads has a deeper tree: more than the root, never more than it has nodes
  Scene grid = makeGrid(32, glm::vec3(0.0f), 2.0f, glm::vec3(0, 0, 1), glm::vec3(1, 0, 0), makeMaterial(glm::vec3(0.5f)));
  grid.camera = test::topDownCamera(glm::vec3(0.0f, kHeight, 0.0f), kHalfView);
  Renderer renderer(test::deviceContext(), grid, settings);
  renderer.renderSample();
  const Aovs a = renderer.readImage().aovs;
  const float nodes = float(renderer.sceneBuffers().nodeCount);
  for (float c : a.bvhCost) {
    ASSERT_GT(c, 1.0f);
    ASSERT_LE(c, nodes);
  }
  // without the switch nothing is counted
  Image plain = test::render(floorScene(makeMaterial(glm::vec3(0.5f))), aovSettings(true), 1);
  for (float c : plain.aovs.bvhCost) ASSERT_EQ(c, 0.0f);
}

TEST(Aov, RenderWithoutAovsIsUnchangedAndAllocatesNone) {
  // The same image with and without the AOV code compiled in, bit for bit;
  // without AOVs their buffers hold one element each.
  Scene scene = mirrorScene(0.3f, glm::vec3(0.2f, 0.5f, 0.7f));
  appendScene(scene, test::makeFloor(0.3f, kHeight * 1.5f, makeMaterial(glm::vec3(0.0f), glm::vec3(5.0f)), true));
  // shade's lanes take no AOVs (renderKernelFeatures): both one path per work-item
  RenderSettings noAovs = aovSettings(false);
  noAovs.shadeLanes = false;
  Renderer plain(test::deviceContext(), scene, noAovs);
  Renderer withAovs(test::deviceContext(), scene, aovSettings(true));
  for (int s = 0; s < 3; ++s) plain.renderSample(), withAovs.renderSample();
  Image a = plain.readImage(), b = withAovs.readImage();
  EXPECT_TRUE(a.aovs.empty());
  ASSERT_FALSE(b.aovs.empty());
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)), 0);
  EXPECT_EQ(a.srgba, b.srgba);
  const std::size_t pixels = std::size_t(kSize) * kSize;
  EXPECT_EQ(withAovs.pathStateBytes() - plain.pathStateBytes(), (64 + 64 + 16) * (pixels - 1));
}

TEST(Aov, ExrHasTheNamedLayers) {
  Image image = test::render(floorScene(makeMaterial(glm::vec3(0.6f, 0.3f, 0.2f))), aovSettings(true), 2);
  std::filesystem::path path = test::scratchDir("aov") / "layers.exr";
  writeImage(path, image, parseAovList("all"));
  Imf::InputFile file(path.c_str());
  const Imf::ChannelList& channels = file.header().channels();
  for (const char* name : {"R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z",
                           "depth.Z", "position.X", "position.Y", "position.Z", "material.id", "instance.id",
                           "instance.primitive", "mean_variance.R", "mean_variance.G", "mean_variance.B"})
    EXPECT_NE(channels.findChannel(name), nullptr) << name;
  EXPECT_EQ(channels.findChannel("material.id")->type, Imf::UINT);
  // the values come back: normal.Y and depth.Z of every pixel
  const std::size_t pixels = std::size_t(kSize) * kSize;
  std::vector<float> normalY(pixels), depth(pixels);
  std::vector<std::uint32_t> material(pixels, 7u);
  Imf::FrameBuffer fb;
  fb.insert("normal.Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(normalY.data()), 4, 4 * kSize));
  fb.insert("depth.Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(depth.data()), 4, 4 * kSize));
  fb.insert("material.id", Imf::Slice(Imf::UINT, reinterpret_cast<char*>(material.data()), 4, 4 * kSize));
  file.setFrameBuffer(fb);
  file.readPixels(0, kSize - 1);
  std::vector<float> expectedY(pixels);
  for (std::size_t p = 0; p < pixels; ++p) expectedY[p] = image.aovs.normal[3 * p + 1];
  EXPECT_EQ(normalY, expectedY);
  EXPECT_EQ(depth, image.aovs.depth);
  EXPECT_EQ(material, image.aovs.material);

  // one AOV on its own: RGB for a viewer and OIDN's tools
  std::filesystem::path normalPath = test::scratchDir("aov") / "normal.exr";
  writeAovImage(normalPath, image, Aov::Normal);
  Imf::InputFile single(normalPath.c_str());
  EXPECT_NE(single.header().channels().findChannel("G"), nullptr);
  EXPECT_EQ(single.header().channels().findChannel("normal.Y"), nullptr);
}

TEST(Aov, ListParsingNamesTheUnknown) {
  EXPECT_EQ(parseAovList("all").size(), std::size(kAllAovs));
  EXPECT_EQ(parseAovList("depth,albedo"), (std::vector<Aov>{Aov::Albedo, Aov::Depth}));
  try {
    parseAovList("albedo,normals");
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'normals'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseAovList("albedo,"), std::invalid_argument);
  EXPECT_THROW(parseDebugView("bvh"), std::invalid_argument);
  EXPECT_EQ(parseDebugView("bvh-cost"), DebugView::BvhCost);
}

TEST(Aov, AovLayersWithoutRecordedAovsAreAnError) {
  Image image = test::render(floorScene(makeMaterial(glm::vec3(0.5f))), aovSettings(false), 1);
  EXPECT_THROW(writeImage(test::scratchDir("aov") / "none.exr", image, parseAovList("albedo")), OutputError);
}

TEST(Aov, DebugViewNormalsMapsTheNormal) {
  Image image = test::render(floorScene(makeMaterial(glm::vec3(0.5f))), aovSettings(true), 1);
  applyDebugView(image, DebugView::Normals);
  // (0, 1, 0) as colour (0.5, 1, 0.5): sRGB 188, 255, 188
  for (std::size_t p = 0; p < std::size_t(kSize) * kSize; ++p) {
    ASSERT_EQ(image.rgb[3 * p + 1], 1.0f);
    ASSERT_EQ(image.srgba[4 * p + 0], 188);
    ASSERT_EQ(image.srgba[4 * p + 1], 255);
  }
  EXPECT_TRUE(image.rgbVariance.empty());
}

}  // namespace
}  // namespace wt
