// KHR_materials_clearcoat's clearcoatNormalTexture end to end: the coat
// reflects about its own normal (kernels/materials/textured.cl
// clearcoat_normal, bsdf.cl bsdf_coat_normal).
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <cmath>

namespace wt {
namespace {

using test::expectUniform;
using test::render;

/// A 1x1 linear texture holding the tangent-space normal (sin t, 0, cos t)
/// as 8-bit texels; *decoded: the unit normal those texels decode to.
std::uint32_t addTiltTexture(Scene& scene, float degrees, glm::dvec3* decoded) {
  const double t = glm::radians(double(degrees));
  DecodedImage image;
  image.width = image.height = 1;
  image.name = "coat normal";
  auto texel = [](double v) { return std::uint8_t(std::lround((v + 1.0) * 0.5 * 255.0)); };
  image.rgba8 = {texel(std::sin(t)), texel(0.0), texel(std::cos(t)), 255};
  glm::dvec3 n(2.0 * image.rgba8[0] / 255.0 - 1.0, 2.0 * image.rgba8[1] / 255.0 - 1.0,
               2.0 * image.rgba8[2] / 255.0 - 1.0);
  *decoded = glm::normalize(n);
  return scene.textures.addTexture(scene.textures.addImage(image, false), -1, -1, test::kNearest, test::kNearest);
}

// A black floor (specularFactor 0) under a mirror clear coat whose normal
// map tilts the coat's normal by 20 degrees towards +x (the tangent), seen
// straight down: the coat mirrors the view 40 degrees off the vertical into
// an emitter there, so every pixel is the emitter's radiance times the
// coat's Schlick Fresnel at the tilt, F0 0.04. A coat that ignored its
// normal map would mirror the view straight up into the black sky (0), and
// one that took the base's (flat) normal likewise.
TEST(ClearcoatNormal, TheCoatMirrorsAboutItsOwnNormal) {
  const glm::vec3 emitted(2.0f, 3.0f, 5.0f);
  const WtMaterial coated = withClearcoat(withSpecular(makePbrMaterial(glm::vec3(0.0f), 0.0f, 0.5f), 0.0f), 1.0f, 0.0f);
  Scene scene = test::makeFloor(2.0f, 0.0f, coated);
  scene.tangents.assign(scene.positions.size(), glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
  glm::dvec3 n;
  test::setMaterialTexture(scene, 0, WT_TEXTURE_SLOT_CLEARCOAT_NORMAL, addTiltTexture(scene, 20.0f, &n));
  // the mirrored rays leave x in [-0.5, 0.5] at 40 degrees: they meet y = 3 at x in [2, 3]
  appendScene(scene, makeBox(glm::vec3(1.2f, 3.0f, -3.0f), glm::vec3(8.0f, 4.0f, 3.0f),
                             makeMaterial(glm::vec3(0.0f), emitted)));
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 2.0f, 0.0f), 0.5f);
  RenderSettings s;
  s.width = s.height = 8;
  s.maxBounces = 2;
  s.seed = 3;
  const double f = 0.04 + 0.96 * std::pow(1.0 - n.z, 5.0);  // wo is the tangent frame's z
  expectUniform(render(scene, s, 16), glm::dvec3(emitted) * f, 1e-4, 5.0, "tilted coat normal");

  // a flat coat normal (the base's) mirrors the view into the sky
  Scene flat = scene;
  glm::dvec3 unused;
  flat.materialTextures[WT_TEXTURE_SLOT_CLEARCOAT_NORMAL].texture = addTiltTexture(flat, 0.0f, &unused);
  expectUniform(render(flat, s, 16), glm::dvec3(0.0), 0.0, 5.0, "flat coat normal");
}

}  // namespace
}  // namespace wt
