// Textured emitters are lights: the light list weighs each triangle by its
// emissive texture's average over it, NEE reads the texture at the point it
// samples, and `path` (NEE and MIS) converges to `minimal` (BSDF sampling
// alone), which never asks the light list.
#include "render/light_list.h"
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

namespace wt {
namespace {

/// A 4x4 emissive texture: bright orange in its left half, black in its
/// right half except one dim blue texel, linear.
std::uint32_t addLampTexture(Scene& scene) {
  DecodedImage image;
  image.width = image.height = 4;
  image.name = "lamp";
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) {
      std::array<std::uint8_t, 4> c = x < 2 ? std::array<std::uint8_t, 4>{255, 128, 0, 255}
                                            : std::array<std::uint8_t, 4>{0, 0, 0, 255};
      if (x == 3 && y == 1) c = {0, 0, 60, 255};
      image.rgba8.insert(image.rgba8.end(), c.begin(), c.end());
    }
  const std::uint32_t index = scene.textures.addImage(image, false);
  // nearest, clamped: each triangle's texels are exactly the ones under it
  return scene.textures.addTexture(index, 33071, 33071, 9728, 9728);
}

/// A floor lit by a face-down emitting quad whose texture is given by uv
/// (u along x), the uv of its four corners chosen by `uvs`.
Scene lampScene(std::array<glm::vec2, 4> uvs) {
  Scene scene = test::makeFloor(2.0f, 0.0f, makePbrMaterial(glm::vec3(0.7f), 0.0f, 0.6f));
  Scene lamp = test::makeFloor(0.5f, 1.0f, makeMaterial(glm::vec3(0.0f), glm::vec3(4.0f)), /*faceDown=*/true);
  for (int v = 0; v < 4; ++v) lamp.texcoords[v] = uvs[v];
  appendScene(scene, lamp);
  const std::uint32_t texture = addLampTexture(scene);
  test::setMaterialTexture(scene, 1, WT_TEXTURE_SLOT_EMISSIVE, texture);
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.4f, 2.6f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  return scene;
}

// makeFloor's corners: (-h, -h), (h, -h), (h, h), (-h, h) in x, z; u follows x
const std::array<glm::vec2, 4> kAcross = {glm::vec2(0, 0), glm::vec2(1, 0), glm::vec2(1, 1), glm::vec2(0, 1)};

TEST(TexturedLights, PathWithNeeMatchesBsdfSamplingAlone) {
  Scene scene = lampScene(kAcross);
  RenderSettings s;
  s.width = s.height = 16;
  s.seed = 3;
  s.maxBounces = 2;
  s.integrator = Integrator::Minimal;
  s.textureFootprint = false;
  // (the z test takes its tolerance from the renders' variances: it holds at the small size)
  Image reference = test::render(scene, s, test::testSize(4096, 1024));
  s.integrator = Integrator::Path;
  Image img = test::render(scene, s, test::testSize(512, 128));
  test::expectSameImage(reference, img, 4, 5.0, "a half-black textured lamp");
  // the lamp lights the floor: a missing texture read in NEE would make the
  // floor orange and black at once; a lamp without its texture twice as bright
  test::BlockStat floor = test::blockStat(img, 0, 12, 16, 16, 0);
  EXPECT_GT(floor.mean, 0.01);
}

// The light list weighs each of the lamp's two triangles by the texture
// under it: with u along x, a quarter and three quarters of them lie on the
// orange half; with
// one triangle mapped onto the orange half and the other onto a black row,
// the black one leaves the list.
TEST(TexturedLights, TrianglesEnterTheListByTheirTexture) {
  Scene across = lampScene(kAcross);
  // the lamp's triangles are corners (0, 1, 2) and (0, 2, 3): the first on u <= 0.5 (orange),
  // the second on u >= 0.5 within v in [0.9, 0.95], the last row's black texels
  Scene split = lampScene({glm::vec2(0.5f, 0.9f), glm::vec2(0.0f, 0.9f), glm::vec2(0.5f, 0.95f), glm::vec2(1.0f, 0.95f)});
  for (const Scene* s : {&across, &split}) {
    const std::size_t lamp = s->triangles.size() - 2;
    for (std::size_t t = lamp; t < lamp + 2; ++t) {
      glm::dvec3 average = averageEmissiveTexture(*s, s->triangles[t]);
      EXPECT_TRUE(std::isfinite(average.x) && average.x >= 0.0 && average.x <= 1.0);
    }
  }
  const std::size_t lamp = across.triangles.size() - 2;
  glm::dvec3 a0 = averageEmissiveTexture(across, across.triangles[lamp]);
  glm::dvec3 a1 = averageEmissiveTexture(across, across.triangles[lamp + 1]);
  // the diagonal u = v splits the square: below it (corners 0, 1, 2) a quarter
  // of the area has u < 0.5 (orange, red 1), above it three quarters; 16
  // stratified texels estimate it within 1/16 or so
  EXPECT_NEAR(a0.x, 0.25, 0.07);
  EXPECT_NEAR(a1.x, 0.75, 0.07);
  EXPECT_NEAR(a1.y, 0.75 * 128.0 / 255.0, 0.07);
  RenderSettings s;
  Renderer renderer(test::deviceContext(), across, s);
  EXPECT_EQ(renderer.lights().emissiveTriangles, 2u);
  Renderer dark(test::deviceContext(), split, s);
  EXPECT_EQ(dark.lights().emissiveTriangles, 1u);
}

/// lampScene's lamp (no emissive texture) with holes: MASK with a checker
/// of 16 x 16 cells in its base colour texture's alpha (half of it a hole),
/// or BLEND with an alpha factor of 0.5 and no texture; OPAQUE: no holes.
/// The floor reads the checker's white as its base colour (an opaque
/// material: its alpha is not read), so that every mode compiles textures in
/// and MASK and BLEND share one program per integrator.
Scene holedLampScene(std::uint32_t mode) {
  Scene scene = lampScene(kAcross);
  const std::uint32_t lamp = 1;
  scene.materials[lamp].texture_mask = 0u;  // no emissive texture: the lamp emits 4 wherever it is there
  const std::uint32_t checker = test::addCheckerTexture(scene, 16);
  test::setBaseColorTexture(scene, 0, checker);
  if (mode == WT_ALPHA_OPAQUE) return scene;
  scene.materials[lamp].alpha_mode = mode;
  scene.materials[lamp].alpha_cutoff = 0.5f;
  if (mode == WT_ALPHA_MASK) {
    test::setBaseColorTexture(scene, lamp, checker);
  } else {
    scene.materials[lamp].alpha = 0.5f;
  }
  return scene;
}

RenderSettings holedLampSettings(Integrator integrator) {
  RenderSettings s;
  s.width = s.height = 16;
  s.seed = 5;
  s.maxBounces = 2;
  s.integrator = integrator;
  s.textureFootprint = false;
  return s;
}

// An emitter with holes (alphaMode MASK or BLEND) emits only where it is
// there, in next-event estimation as for BSDF sampling (which finds it
// through traversal's alpha test): `path` with NEE and MIS converges to
// `minimal` (BSDF sampling alone), and the floor receives half of what the
// opaque lamp gives it: exactly for BLEND 0.5; for the MASK checker within
// 5 standard errors plus 2% for the checker's cells (1/16 of the lamp at a
// distance of 1 or more; their pattern's effect on the irradiance is of the
// order (cell / distance)^2). With the light list ignoring the holes the
// floor gets about 3/4 of the opaque lamp's light.
// The opaque lamp is lit as two triangles (no rectangle light, as the holed
// ones): its program is PathWithNeeMatchesBsdfSamplingAlone's `path`.
TEST(TexturedLights, HoledEmittersEmitOnlyWhereTheyAreThere) {
  RenderSettings opaque = holedLampSettings(Integrator::Path);
  opaque.quadLights = false;
  Image full = test::render(holedLampScene(WT_ALPHA_OPAQUE), opaque, 256);
  test::BlockStat fullFloor = test::blockStat(full, 0, 12, 16, 16, 0);
  ASSERT_GT(fullFloor.mean, 0.01);
  for (std::uint32_t mode : {WT_ALPHA_MASK, WT_ALPHA_BLEND}) {
    const std::string what = mode == WT_ALPHA_MASK ? "a MASK lamp, half of it holes" : "a BLEND lamp of alpha 0.5";
    Scene scene = holedLampScene(mode);
    Image img = test::render(scene, holedLampSettings(Integrator::Path), 256);
    Image reference = test::render(scene, holedLampSettings(Integrator::Minimal), test::testSize(4096, 1024));
    test::expectSameImage(reference, img, 4, 5.0, what);
    test::BlockStat floor = test::blockStat(img, 0, 12, 16, 16, 0);
    double ratio = floor.mean / fullFloor.mean;
    double se = ratio * std::sqrt(floor.varianceOfMean / (floor.mean * floor.mean) +
                                  fullFloor.varianceOfMean / (fullFloor.mean * fullFloor.mean));
    double geometric = mode == WT_ALPHA_MASK ? 0.02 : 0.0;
    EXPECT_NEAR(ratio, 0.5, 5.0 * se + geometric) << what << ": the floor gets " << ratio << " +- " << se
                                                   << " of the opaque lamp's light";
  }
}

}  // namespace
}  // namespace wt
