// The light list weighs an emitter with holes (alphaMode MASK or BLEND) by
// the share of it that is there (meanCoverage), in the alias table and in
// the light tree, so that NEE spends few samples on a mostly transparent
// lamp; the estimator is unbiased whatever the weights.
#include "render/image_error.h"
#include "render/light_list.h"
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <algorithm>

namespace wt {
namespace {

/// A w x 1 texture of white texels whose alphas are `alphas`, nearest, clamped.
std::uint32_t addAlphaTexture(Scene& scene, const std::vector<std::uint8_t>& alphas) {
  DecodedImage image;
  image.width = std::uint32_t(alphas.size());
  image.height = 1;
  image.name = "alpha";
  for (std::uint8_t a : alphas)
    for (std::uint8_t c : {std::uint8_t(255), std::uint8_t(255), std::uint8_t(255), a}) image.rgba8.push_back(c);
  return scene.textures.addTexture(scene.textures.addImage(image, true), 33071, 33071, test::kNearest, test::kNearest);
}

/// Appends a face-down emitting triangle of material `material` at height 1,
/// centred on x, with texture coordinates `uv`.
void addLampTriangle(Scene& scene, float x, std::uint32_t material, std::array<glm::vec2, 3> uv) {
  const std::uint32_t first = std::uint32_t(scene.positions.size());
  for (glm::vec3 p : {glm::vec3(x - 0.2f, 1.0f, -0.2f), glm::vec3(x + 0.2f, 1.0f, -0.2f), glm::vec3(x, 1.0f, 0.2f)}) {
    scene.positions.push_back({p.x, p.y, p.z, 0});
    scene.normals.push_back({0, 0, 0, 0});
  }
  for (glm::vec2 t : uv) scene.texcoords.push_back(t);
  scene.triangles.push_back({first, first + 1, first + 2, material});
}

/// A floor and three emitting triangles of equal area and emission whose
/// material's alpha texture (two texels: alpha 0 for u < 0.5, then `right`)
/// puts the first in the hole, the second astride the edge (symmetric about
/// u = 0.5: half of it on each side) and the third on the right texel.
Scene threeLampScene(std::uint32_t mode, std::uint8_t left, std::uint8_t right) {
  Scene scene = test::makeFloor(2.0f, 0.0f, makeMaterial(glm::vec3(0.7f)));
  WtMaterial lamp = makeMaterial(glm::vec3(0.0f), glm::vec3(4.0f));
  lamp.alpha_mode = mode;
  lamp.alpha_cutoff = 0.5f;
  scene.materials.push_back(lamp);
  scene.materialNames.push_back("lamp");
  test::setBaseColorTexture(scene, 1, addAlphaTexture(scene, {left, right}));
  addLampTriangle(scene, -1.0f, 1, {glm::vec2(0.05f, 0.1f), glm::vec2(0.45f, 0.1f), glm::vec2(0.25f, 0.9f)});
  addLampTriangle(scene, 0.0f, 1, {glm::vec2(0.5f, 0.0f), glm::vec2(0.0f, 1.0f), glm::vec2(1.0f, 1.0f)});
  addLampTriangle(scene, 1.0f, 1, {glm::vec2(0.55f, 0.1f), glm::vec2(0.95f, 0.1f), glm::vec2(0.75f, 0.9f)});
  return scene;
}

/// The weights (selection probabilities relative to the largest) of the
/// scene's emissive triangles, ascending: from the alias table with the
/// power sampler, from the tree's leaves with the tree.
std::vector<double> relativeWeights(const Scene& scene, LightSampler sampler) {
  RenderSettings s;
  s.width = s.height = 4;
  s.lightSampler = sampler;
  Renderer renderer(test::deviceContext(), scene, s);
  const LightList& list = renderer.lights();
  std::vector<double> w;
  if (sampler == LightSampler::Power) {
    for (std::size_t i = list.analyticCount; i < list.alias.size(); ++i)
      if (list.lights[i].type == WT_LIGHT_TRIANGLE) w.push_back(list.alias[i].pmf);
  } else {
    for (const WtLightNode& n : list.tree)
      if (n.leaf) w.push_back(n.power);
  }
  std::sort(w.begin(), w.end());
  for (double& x : w) x /= w.back();
  return w;
}

// A triangle in the hole, half in it and out of it weighs the floor, 1/2 and
// 1 of its emission (MASK by the cutoff, BLEND by alpha: here 0 and 128/255
// so that BLEND's half triangle weighs 1/4 and its right one 1/2). The edge
// u = 0.5 crosses about 8 of the 64 strata of the half triangle, each off
// by at most 1/64, so its estimate is within 1/8.
TEST(LightCoverage, EmittersWeighByTheShareThatIsThere) {
  for (LightSampler sampler : {LightSampler::Power, LightSampler::Tree}) {
    const char* how = sampler == LightSampler::Power ? "alias table" : "light tree";
    std::vector<double> mask = relativeWeights(threeLampScene(WT_ALPHA_MASK, 0, 255), sampler);
    ASSERT_EQ(mask.size(), 3u) << how;
    EXPECT_NEAR(mask[0], kMinCoverageWeight, 1e-6) << how << ": MASK, in the hole";
    EXPECT_NEAR(mask[1], 0.5, 0.125) << how << ": MASK, half in the hole";
    EXPECT_EQ(mask[2], 1.0) << how;
    // BLEND relative to an opaque triangle: weights are absolute powers over the largest
    std::vector<double> blend = relativeWeights(threeLampScene(WT_ALPHA_BLEND, 0, 128), sampler);
    ASSERT_EQ(blend.size(), 3u) << how;
    EXPECT_NEAR(blend[0], kMinCoverageWeight / (128.0 / 255.0), 1e-6) << how << ": BLEND, in the hole";
    EXPECT_NEAR(blend[1], 0.5, 0.125) << how << ": BLEND, half in the hole";
  }
  // meanCoverage itself, absolute: 0, about 1/2 and 1 for MASK; BLEND alpha 128/255 on the right
  Scene mask = threeLampScene(WT_ALPHA_MASK, 0, 255), blend = threeLampScene(WT_ALPHA_BLEND, 0, 128);
  const std::size_t first = mask.triangles.size() - 3;
  EXPECT_EQ(meanCoverage(mask, mask.triangles[first]), 0.0);
  EXPECT_NEAR(meanCoverage(mask, mask.triangles[first + 1]), 0.5, 0.125);
  EXPECT_EQ(meanCoverage(mask, mask.triangles[first + 2]), 1.0);
  EXPECT_NEAR(meanCoverage(blend, blend.triangles[first + 2]), 128.0 / 255.0, 1e-9);
  EXPECT_EQ(meanCoverage(mask, mask.triangles[0]), 1.0);  // the opaque floor
  // without the weights every lamp triangle weighs its emission
  RenderSettings s;
  s.width = s.height = 4;
  s.lightSampler = LightSampler::Power;
  s.lightCoverageWeights = false;
  Renderer unweighted(test::deviceContext(), mask, s);
  const LightList& list = unweighted.lights();
  ASSERT_EQ(list.emissiveTriangles, 3u);
  for (std::size_t i = 0; i < list.alias.size(); ++i) EXPECT_NEAR(list.alias[i].pmf, 1.0 / 3.0, 1e-6);
}


/// A floor lit by two face-down square lamps of equal emission side by side
/// at height 1.5, the one at x < 0 opaque, the one at x > 0 BLEND with a
/// base colour texture's alpha of 26/255 (90% transparent). Side by side,
/// they light every floor point about alike, so that the best choice between
/// them hardly depends on the point (the power sampler's premise).
Scene twoLampScene() {
  Scene scene = test::makeFloor(2.0f, 0.0f, makePbrMaterial(glm::vec3(0.7f), 0.0f, 0.6f));
  for (float x : {-0.25f, 0.25f}) {
    Scene lamp = test::makeFloor(0.25f, 1.5f, makeMaterial(glm::vec3(0.0f), glm::vec3(4.0f)), /*faceDown=*/true);
    for (WtVec4& p : lamp.positions) p.x += x;
    appendScene(scene, lamp);
  }
  const std::uint32_t holed = std::uint32_t(scene.materials.size()) - 1;
  scene.materials[holed].alpha_mode = WT_ALPHA_BLEND;
  test::setBaseColorTexture(scene, holed, addAlphaTexture(scene, {26, 26}));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.4f, 2.6f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  return scene;
}

// With the coverage weights NEE picks the 90%-transparent lamp about a tenth
// as often as the opaque one instead of as often (by the alias table and by
// the light tree), and the image's relMSE at equal samples against a
// converged reference is lower. Both renders share
// a seed and the reference; the per-pixel difference of their relative
// squared errors (ImageError::relMse's terms, the reference's own noise
// cancelling) must be below 0 by 4 standard errors of its mean over pixels.
// Both the difference and its spread scale as 1/spp, so the power comes from
// the pixels: 24 x 24 of them put the measured difference at 6 to 18 standard
// errors over seven seeds (docs/lab/2026-12-05-light-coverage-weights.md); 16
// spp keeps it quick, the reference's 64x more keep its noise small.
TEST(LightCoverage, HoledLampWeighedByCoverageLowersRelMse) {
  const Scene scene = twoLampScene();
  for (LightSampler sampler : {LightSampler::Power, LightSampler::Tree}) {
    const char* how = sampler == LightSampler::Power ? "alias table" : "light tree";
    RenderSettings s;
    s.width = s.height = 24;
    s.maxBounces = 1;  // direct light: where light selection acts
    s.textureFootprint = false;
    s.lightSampler = sampler;
    constexpr int kSpp = 16;
    s.seed = 101;
    const Image reference = test::render(scene, s, 64 * kSpp);
    s.seed = 7;
    const Image weighted = test::render(scene, s, kSpp);
    s.lightCoverageWeights = false;
    const Image unweighted = test::render(scene, s, kSpp);
    double sum = 0.0, sumSq = 0.0, varWeighted = 0.0, varUnweighted = 0.0;
    const std::size_t n = reference.rgb.size();
    for (std::size_t i = 0; i < n; ++i) {
      const double r = reference.rgb[i], scale = r * r + 0.01;
      const double a = weighted.rgb[i] - r, b = unweighted.rgb[i] - r;
      const double d = (a * a - b * b) / scale;
      sum += d, sumSq += d * d;
      varWeighted += weighted.rgbVariance[i] / scale, varUnweighted += unweighted.rgbVariance[i] / scale;
    }
    const double mean = sum / double(n), se = std::sqrt((sumSq / double(n) - mean * mean) / double(n - 1));
    const double relWeighted = imageError(weighted, reference).relMse;
    const double relUnweighted = imageError(unweighted, reference).relMse;
    EXPECT_LT(mean + 4.0 * se, 0.0) << how << ": relMSE " << relWeighted << " with the coverage weights, "
                                    << relUnweighted << " without; paired difference " << mean << " +- " << se
                                    << "; relative per-pixel variance " << varWeighted / double(n) << " vs "
                                    << varUnweighted / double(n);
  }
}

}  // namespace
}  // namespace wt
