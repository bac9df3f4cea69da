// glTF alpha modes end to end (kernels/materials/alpha.cl): a cut-out quad's
// shadow lets through the share of light its texture's holes say, a blended
// quad's the share its alpha leaves; seen directly, a blended surface over a
// background averages to alpha of the one and 1 - alpha of the other, a
// masked one shows one or the other per texel; an alpha factor alone cuts
// or keeps the whole surface. Camera rays and their shadow rays run in
// packets and one by one.
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

namespace wt {
namespace {

using test::blockStat;
using test::expectUniform;
using test::render;

using test::kNearest;
using test::setBaseColorTexture;

/// A 4 x 4 texture, white, whose texel (x, y) has alpha (x + 4 y) * 16 / 255:
/// 0 to 240 in steps of 16, so that a cutoff picks how many are holes.
std::uint32_t addRampTexture(Scene& scene) {
  DecodedImage image;
  image.width = image.height = 4;
  image.name = "ramp";
  for (std::uint32_t i = 0; i < 16; ++i)
    for (std::uint8_t c : {255, 255, 255, int(i * 16)}) image.rgba8.push_back(c);
  return scene.textures.addTexture(scene.textures.addImage(image, true), -1, -1, kNearest, kNearest);
}

std::uint32_t addCheckerTexture(Scene& scene) { return test::addCheckerTexture(scene, 4); }

WtMaterial withAlpha(WtMaterial m, std::uint32_t mode, float alpha, float cutoff = 0.5f) {
  m.alpha_mode = mode;
  m.alpha = alpha;
  m.alpha_cutoff = cutoff;
  return m;
}

/// A quad facing up over [-half, half]^2 at `height` appended to `scene`, its
/// texture coordinates (x + half, z + half) / (2 half) * periods.
void appendQuad(Scene& scene, float half, float height, const WtMaterial& material, float periods = 1.0f) {
  const std::size_t first = scene.positions.size();
  appendScene(scene, test::makeFloor(half, height, material));
  scene.texcoords.resize(scene.positions.size());
  for (std::size_t v = first; v < scene.positions.size(); ++v)
    scene.texcoords[v] = glm::vec2(scene.positions[v].x + half, scene.positions[v].z + half) / (2.0f * half) * periods;
}

RenderSettings settings(int side, bool packets) {
  RenderSettings s;
  s.width = s.height = side;
  s.maxBounces = 1;
  s.seed = 3;
  s.packets = packets;
  return s;
}

// ---- shadows ----------------------------------------------------------------------

const float kAlbedo = 0.8f;
const glm::vec3 kLightIntensity(2.0f, 3.0f, 4.0f);  // lux

/// The shadow scenes' directional light along (2, -1, 0) and their camera
/// looking down on the shadow.
void lightFromTheSideAndCameraAbove(Scene& scene) {
  PunctualLight light;
  light.type = WT_LIGHT_DIRECTIONAL;
  light.direction = glm::normalize(glm::vec3(2.0f, -1.0f, 0.0f));
  light.intensity = kLightIntensity;
  scene.lights.push_back(light);
  scene.camera = test::topDownCamera(glm::vec3(2.0f, 5.0f, 0.0f), 0.5f);
}

/// A floor (albedo kAlbedo) lit by a directional light travelling along
/// (2, -1, 0) past `quad` (a quad over [-1, 1]^2 at y = 1, black), seen from
/// above where the shadow of the quad's middle [-0.5, 0.5]^2 falls: x in
/// [1.5, 2.5], z in [-0.5, 0.5]. Nothing but the light reaches the floor
/// (a black sky, one bounce): lit, it has radiance kAlbedo / pi E cos.
Scene shadowScene(const WtMaterial& quad, bool rampTexture) {
  Scene scene = test::makeFloor(10.0f, 0.0f, makeMaterial(glm::vec3(kAlbedo)));
  appendQuad(scene, 1.0f, 1.0f, quad, 2.0f);  // two periods over [-1, 1]: one over the middle
  if (rampTexture) setBaseColorTexture(scene, 1, addRampTexture(scene));
  lightFromTheSideAndCameraAbove(scene);
  return scene;
}

glm::dvec3 litRadiance() {
  return glm::dvec3(kAlbedo / std::numbers::pi * glm::dvec3(kLightIntensity) / std::sqrt(5.0));
}

/// The image's mean per channel is `fraction` of the lit radiance, within
/// 5 standard errors (from the pixels' variances) and float rounding.
void expectShadowFraction(const Image& img, double fraction, const std::string& what) {
  for (int c = 0; c < 3; ++c) {
    test::BlockStat s = blockStat(img, 0, 0, img.width, img.height, c);
    const double expected = fraction * litRadiance()[c];
    EXPECT_NEAR(s.mean, expected, 5.0 * std::sqrt(s.varianceOfMean) + 1e-5 * litRadiance()[c])
        << what << ", channel " << c;
  }
}

// A MASK quad's texture has alpha (x + 4 y) * 16 / 255 per texel: with
// cutoff 0.3, texels 0 to 4 are holes (their alpha below 76.5 / 255), so
// 5 / 16 of the light reaches the floor behind its middle period. Its
// texels' shadows fall on whole pixels: every pixel is lit or not.
TEST(AlphaRender, MaskShadowPassesTheShareOfHoles) {
  Scene scene = shadowScene(withAlpha(makeMaterial(glm::vec3(0.0f)), WT_ALPHA_MASK, 1.0f, 0.3f), true);
  for (bool packets : {true, false}) {
    const std::string what = packets ? "packets" : "single rays";
    Image img = render(scene, settings(32, packets), 4);
    expectShadowFraction(img, 5.0 / 16.0, what);
    int lit = 0, dark = 0;
    for (std::size_t p = 0; p < img.samples.size(); ++p) {
      const double r = img.rgb[3 * p];
      lit += std::abs(r - litRadiance().x) < 1e-5;
      dark += r == 0.0;
    }
    EXPECT_EQ(lit + dark, int(img.samples.size())) << what << ": pixels neither lit nor in shadow";
    EXPECT_EQ(lit, int(img.samples.size()) * 5 / 16) << what;
  }
  // a cutoff of 0.6 (153 / 255): texels 0 to 9 are holes
  scene.materials[1].alpha_cutoff = 0.6f;
  expectShadowFraction(render(scene, settings(32, true), 4), 10.0 / 16.0, "cutoff 0.6");
}

// A BLEND quad of alpha 0.3 passes 0.7 of the light, on average over
// shadow rays that each pass or not; two such quads one above the other
// pass 0.7^2 (independent numbers per surface).
TEST(AlphaRender, BlendShadowPassesOneMinusAlphaOnAverage) {
  const WtMaterial blend = withAlpha(makeMaterial(glm::vec3(0.0f)), WT_ALPHA_BLEND, 0.3f);
  Scene scene = shadowScene(blend, false);
  for (bool packets : {true, false}) {
    Image img = render(scene, settings(16, packets), 64);
    expectShadowFraction(img, 0.7, packets ? "packets" : "single rays");
  }
  // at y = 0.75 the view's shadow rays cross x in [0, 1] (the camera's, x in [1.5, 2.5], miss it)
  appendQuad(scene, 1.0f, 0.75f, blend);
  expectShadowFraction(render(scene, settings(16, true), 64), 0.49, "two quads");
}

// The same with the two quads copies of one geometry stored once
// (instances), placed so that each shadow ray crosses both at the same point
// of the geometry, the same triangle: each copy must draw its own numbers.
TEST(AlphaRender, BlendShadowThroughInstancedCopiesMultiplies) {
  Scene scene = shadowScene(makeMaterial(glm::vec3(0.0f)), false);
  scene.triangles.resize(2);  // the floor alone
  Scene grid = makeGrid(8, glm::vec3(0.0f), 1.0f, glm::vec3(1, 0, 0), glm::vec3(0, 0, 1),
                        withAlpha(makeMaterial(glm::vec3(0.0f)), WT_ALPHA_BLEND, 0.3f));
  // the view's shadow rays cross y = 2 at x in [-2.5, -1.5] and y = 1.75 half a unit further on
  const glm::mat4 copies[] = {glm::translate(glm::mat4(1.0f), glm::vec3(-2.0f, 2.0f, 0.0f)),
                              glm::translate(glm::mat4(1.0f), glm::vec3(-1.5f, 1.75f, 0.0f))};
  appendScene(scene, placeCopies(grid, copies));
  RenderSettings s = settings(16, true);
  s.instancing = Instancing::On;
  ASSERT_GT(SceneBuffers(test::deviceContext(), scene, {.instancing = Instancing::On}).instanceCount(), 0u);
  expectShadowFraction(render(scene, s, 64), 0.49, "two instanced copies");
}

// ---- shadows through alpha-tested glass ---------------------------------------------

/// Reflectance of a dielectric interface of relative index eta at cos_i (unpolarised).
double dielectricFresnel(double cosI, double eta) {
  const double sin2T = (1.0 - cosI * cosI) / (eta * eta);
  const double cosT = std::sqrt(1.0 - sin2T);
  const double rs = (cosI - eta * cosT) / (cosI + eta * cosT), rp = (eta * cosI - cosT) / (eta * cosI + cosT);
  return 0.5 * (rs * rs + rp * rp);
}

double srgbDecoded(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

/// The glass's texture is kGlassTexels x kGlassTexels, finer than the
/// quad's triangles (4 x 4 texels to a cell of two triangles), so that a
/// point read elsewhere in its triangle reads another texel.
constexpr std::uint32_t kGlassTexels = 8;

/// Texel i = x + kGlassTexels y of the glass's texture: a colour of its own and alpha 4 i / 255.
std::array<std::uint8_t, 4> glassTexel(std::uint32_t i) {
  return {std::uint8_t(255 - 3 * i), std::uint8_t(60 + 3 * i), std::uint8_t(40 + 13 * ((5 * i) % 16)), std::uint8_t(4 * i)};
}

const glm::vec3 kGlassFactor(0.95f, 0.9f, 0.8f);
const double kGlassIor = 1.5;

/// shadowScene with a smooth thin glass quad (base colour kGlassFactor
/// times the texture glassTexel, alpha mode `mode`, cutoff 0.3) in place of
/// the black one, stored once and placed twice by instances: the copy that
/// casts the shadow turned, scaled and mirrored, the other under the floor.
/// Shadow rays cross such glass (connect.cl), so the floor under a texel
/// that is there gets kGlassFactor x its colour x (1 - F) of the light.
Scene glassShadowScene(std::uint32_t mode) {
  Scene scene = test::makeFloor(10.0f, 0.0f, makeMaterial(glm::vec3(kAlbedo)));
  const WtMaterial glass = withAlpha(withTransmission(makePbrMaterial(kGlassFactor, 0.0f, 0.0f), 1.0f, float(kGlassIor), true),
                                     mode, 1.0f, 0.3f);
  // the quad over [-1, 1]^2 at y = 1 with appendQuad's coordinates (two periods), 128 triangles
  Scene quad = makeGrid(8, glm::vec3(0.0f, 1.0f, 0.0f), 1.0f, glm::vec3(1, 0, 0), glm::vec3(0, 0, 1), glass);
  const glm::mat4 place = glm::translate(glm::mat4(1.0f), glm::vec3(0.3f, 1.0f, -0.2f)) *
                          glm::rotate(glm::mat4(1.0f), 0.7f, glm::vec3(0, 1, 0)) *
                          glm::scale(glm::mat4(1.0f), glm::vec3(2.0f, 2.0f, -2.0f));
  const glm::mat4 toMesh = glm::inverse(place) * glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -1.0f, 0.0f));
  for (std::size_t v = 0; v < quad.positions.size(); ++v) {
    WtVec4& p = quad.positions[v];
    quad.texcoords[v] = glm::vec2(p.x + 1.0f, p.z + 1.0f);
    const glm::vec3 m(toMesh * glm::vec4(p.x, p.y, p.z, 1.0f));
    p = {m.x, m.y, m.z, 0.0f};
  }
  const glm::mat4 copies[] = {glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f)) * place,
                              glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, -4.0f, 0.0f)) * place};
  appendScene(scene, placeCopies(quad, copies));
  DecodedImage image;
  image.width = image.height = kGlassTexels;
  image.name = "glass";
  for (std::uint32_t i = 0; i < kGlassTexels * kGlassTexels; ++i)
    for (std::uint8_t c : glassTexel(i)) image.rgba8.push_back(c);
  setBaseColorTexture(scene, 1, scene.textures.addTexture(scene.textures.addImage(image, true), -1, -1, kNearest, kNearest));
  lightFromTheSideAndCameraAbove(scene);
  return scene;
}

/// The texel whose shadow pixel (px, py) of a side x side view of
/// glassShadowScene shows: the floor point (x, 0, z) under the pixel's
/// centre sees the light through the quad at (x - 2, 1, z), whose
/// coordinates are (x - 1, z + 1).
std::uint32_t shadowTexel(int px, int py, int side) {
  const double x = 2.0 + 0.5 * (2.0 * (px + 0.5) / side - 1.0), z = -0.5 * (1.0 - 2.0 * (py + 0.5) / side);
  const double u = x - 1.0, v = z + 1.0;
  const auto texel = [](double t) { return std::uint32_t(std::floor((t - std::floor(t)) * kGlassTexels)); };
  return texel(u) + kGlassTexels * texel(v);
}

/// What the floor under texel i gets of the light where the texel is there.
glm::dvec3 glassPass(std::uint32_t i) {
  const double f = dielectricFresnel(1.0 / std::sqrt(5.0), kGlassIor);
  const std::array<std::uint8_t, 4> t = glassTexel(i);
  glm::dvec3 pass;
  for (int c = 0; c < 3; ++c) pass[c] = double(kGlassFactor[c]) * srgbDecoded(t[c] / 255.0) * (1.0 - f);
  return pass;
}

RenderSettings glassSettings(Traversal shadows) {
  RenderSettings s = settings(32, true);
  s.maxBounces = 2;  // a shadow ray from the floor may cross one wall, and nothing else lights it
  s.instancing = Instancing::On;
  s.shadowTraversal = shadows;
  return s;
}

const std::pair<Traversal, const char*> kShadowTraversals[] = {
    {Traversal::kSingle, "single rays"}, {Traversal::kPacket, "packets"}, {Traversal::kStream, "streams"}};

// MASK glass (cutoff 0.3: texels 0 to 19 are holes): shadow rays pass the
// holes whole and the rest of the glass tinted by its texel's colour, read
// in the turned and mirrored instance where they cross it. Every pixel is
// exactly one texel's answer, for shadow rays alone, in packets and in
// streams. Fails when connect reads the wall's texture elsewhere than the
// alpha test does, ignores the texture, or lets no light through the glass.
TEST(AlphaRender, CutOutGlassPassesItsHolesWholeAndTintsTheRest) {
  const Scene scene = glassShadowScene(WT_ALPHA_MASK);
  ASSERT_EQ(SceneBuffers(test::deviceContext(), scene, {.instancing = Instancing::On}).instanceCount(), 2u);
  for (const auto& [traversal, what] : kShadowTraversals) {
    const Image img = render(scene, glassSettings(traversal), 2);
    int bad = 0;
    for (int py = 0; py < img.height; ++py)
      for (int px = 0; px < img.width; ++px) {
        const std::uint32_t texel = shadowTexel(px, py, img.width);
        const glm::dvec3 expected = litRadiance() * (glassTexel(texel)[3] < 0.3 * 255 ? glm::dvec3(1.0) : glassPass(texel));
        for (int c = 0; c < 3; ++c) {
          const double got = img.rgb[3 * (std::size_t(py) * img.width + px) + c];
          // float rounding of the light, the decoded texel and Fresnel
          if (std::abs(got - expected[c]) > 1e-5 * litRadiance()[c] && ++bad <= 5)
            ADD_FAILURE() << what << ": pixel (" << px << ", " << py << ") texel " << texel << " channel " << c
                          << ": " << got << ", expected " << expected[c];
        }
      }
    EXPECT_EQ(bad, 0) << what;
  }
}

// BLEND glass: a texel of alpha a is there for a share a of the shadow
// rays, so the floor under it gets (1 - a) + a x the glass's tint of the
// light on average, within 5 standard errors of each texel's 16 pixels.
TEST(AlphaRender, BlendedGlassPassesItsShareWholeAndTintsTheRest) {
  const Scene scene = glassShadowScene(WT_ALPHA_BLEND);
  const int side = 32, texelPixels = side / int(kGlassTexels);
  const Image img = render(scene, glassSettings(Traversal::kPacket), 16);
  for (int ty = 0; ty < int(kGlassTexels); ++ty)
    for (int tx = 0; tx < int(kGlassTexels); ++tx) {
      const int x0 = tx * texelPixels, y0 = ty * texelPixels;
      const std::uint32_t texel = shadowTexel(x0, y0, side);
      const double a = glassTexel(texel)[3] / 255.0;
      for (int c = 0; c < 3; ++c) {
        const test::BlockStat s = blockStat(img, x0, y0, x0 + texelPixels, y0 + texelPixels, c);
        const double expected = litRadiance()[c] * (1.0 - a + a * glassPass(texel)[c]);
        EXPECT_NEAR(s.mean, expected, 5.0 * std::sqrt(s.varianceOfMean) + 1e-5 * litRadiance()[c])
            << "texel " << texel << " (alpha " << a << "), channel " << c;
      }
    }
}

// Camera rays through the same cut-out glass, looking straight down on the
// floor beside its shadow (x, z in [-0.5, 0.5], lit unshadowed; the glass's
// coordinates there are shadowTexel's): through a hole every sample sees
// the lit floor, through the rest the floor tinted as a shadow ray would
// find it at normal incidence, kGlassFactor x the texel's colour x (1 -
// F(1, 1.5)) on average (a sample reflects to the black sky with
// probability F). Per texel within 5 standard errors of its 16 pixels.
// Fails when the instance's texture is read elsewhere or not at all, or the
// alpha test or the glass's transmission is wrong for camera rays.
TEST(AlphaRender, CameraRaysThroughCutOutGlassSeeTheHolesWholeAndTheRestTinted) {
  Scene scene = glassShadowScene(WT_ALPHA_MASK);
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 0.5f);
  const int side = 32, texelPixels = side / int(kGlassTexels);
  const Image img = render(scene, glassSettings(Traversal::kPacket), 32);
  const double f = dielectricFresnel(1.0, kGlassIor);
  int holes = 0;
  for (int ty = 0; ty < int(kGlassTexels); ++ty)
    for (int tx = 0; tx < int(kGlassTexels); ++tx) {
      const int x0 = tx * texelPixels, y0 = ty * texelPixels;
      const std::uint32_t texel = shadowTexel(x0, y0, side);
      const std::array<std::uint8_t, 4> t = glassTexel(texel);
      if (t[3] < 0.3 * 255) {
        ++holes;
        for (int y = y0; y < y0 + texelPixels; ++y)
          for (int x = x0; x < x0 + texelPixels; ++x)
            for (int c = 0; c < 3; ++c)
              EXPECT_NEAR(img.rgb[3 * (std::size_t(y) * side + x) + c], litRadiance()[c], 1e-5 * litRadiance()[c])
                  << "hole texel " << texel << ", pixel (" << x << ", " << y << ") channel " << c;
        continue;
      }
      for (int c = 0; c < 3; ++c) {
        const test::BlockStat s = blockStat(img, x0, y0, x0 + texelPixels, y0 + texelPixels, c);
        const double expected = litRadiance()[c] * double(kGlassFactor[c]) * srgbDecoded(t[c] / 255.0) * (1.0 - f);
        EXPECT_NEAR(s.mean, expected, 5.0 * std::sqrt(s.varianceOfMean) + 1e-5 * litRadiance()[c])
            << "texel " << texel << ", channel " << c;
      }
    }
  EXPECT_EQ(holes, 20);  // alpha 4 i / 255 below 0.3: texels 0 to 19
}

// The alpha factor alone: MASK 0.4 under the cutoff 0.5 casts no shadow,
// 0.6 a whole one.
TEST(AlphaRender, MaskFactorAloneCastsAllOrNothing) {
  Scene scene = shadowScene(withAlpha(makeMaterial(glm::vec3(0.0f)), WT_ALPHA_MASK, 0.4f), false);
  expectUniform(render(scene, settings(8, true), 2), litRadiance(), 1e-5, 0.0, "alpha 0.4");
  scene.materials[1].alpha = 0.6f;
  expectUniform(render(scene, settings(8, true), 2), glm::dvec3(0.0), 0.0, 0.0, "alpha 0.6");
}

// ---- seen directly ------------------------------------------------------------------

const glm::vec3 kBackground(1.0f, 2.0f, 4.0f), kQuad(4.0f, 2.0f, 1.0f);

/// An emitter facing up at y = -1 (radiance kBackground) under a quad over
/// [-1, 1]^2 at y = 0 that emits kQuad, both black, seen from above by an
/// orthographic camera that sees the quad's square and nothing else.
Scene overBackground(const WtMaterial& quad) {
  Scene scene = test::makeFloor(3.0f, -1.0f, makeMaterial(glm::vec3(0.0f), kBackground));
  WtMaterial m = quad;
  m.emission = {kQuad.x, kQuad.y, kQuad.z, 0.0f};
  appendQuad(scene, 1.0f, 0.0f, m);
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 1.0f);
  return scene;
}

// BLEND alpha 0.3: every pixel's mean is 0.3 of the quad and 0.7 of the
// background; MASK with a checker, at the same sample count: each pixel one
// or the other (a texel covers 2 x 2 pixels), half of them each.
TEST(AlphaRender, BlendAndMaskImagesShowTheirCoverage) {
  const WtMaterial black = makeMaterial(glm::vec3(0.0f));
  const int spp = 64;
  for (bool packets : {true, false}) {
    const std::string what = packets ? "packets" : "single rays";
    Image blend = render(overBackground(withAlpha(black, WT_ALPHA_BLEND, 0.3f)), settings(8, packets), spp);
    expectUniform(blend, 0.3 * glm::dvec3(kQuad) + 0.7 * glm::dvec3(kBackground), 1e-5, 5.0, "BLEND, " + what);

    Scene masked = overBackground(withAlpha(black, WT_ALPHA_MASK, 1.0f));
    setBaseColorTexture(masked, 1, addCheckerTexture(masked));
    Image mask = render(masked, settings(8, packets), spp);
    int quad = 0, background = 0;
    for (std::size_t p = 0; p < mask.samples.size(); ++p) {
      const glm::dvec3 c(mask.rgb[3 * p], mask.rgb[3 * p + 1], mask.rgb[3 * p + 2]);
      quad += glm::length(c - glm::dvec3(kQuad)) < 1e-5;
      background += glm::length(c - glm::dvec3(kBackground)) < 1e-5;
    }
    EXPECT_EQ(quad, 32) << "MASK, " << what;
    EXPECT_EQ(background, 32) << "MASK, " << what;
  }
}

// The alpha factor alone seen directly: MASK 0.4 shows the background
// exactly, 0.6 the quad; BLEND 1 is the quad, BLEND 0 the background.
TEST(AlphaRender, FactorAloneShowsOneOrTheOther) {
  const WtMaterial black = makeMaterial(glm::vec3(0.0f));
  const RenderSettings s = settings(8, true);
  expectUniform(render(overBackground(withAlpha(black, WT_ALPHA_MASK, 0.4f)), s, 2), glm::dvec3(kBackground), 1e-6,
                0.0, "MASK 0.4");
  expectUniform(render(overBackground(withAlpha(black, WT_ALPHA_MASK, 0.6f)), s, 2), glm::dvec3(kQuad), 1e-6, 0.0,
                "MASK 0.6");
  expectUniform(render(overBackground(withAlpha(black, WT_ALPHA_BLEND, 0.0f)), s, 2), glm::dvec3(kBackground), 1e-6,
                0.0, "BLEND 0");
  expectUniform(render(overBackground(withAlpha(black, WT_ALPHA_BLEND, 1.0f)), s, 2), glm::dvec3(kQuad), 1e-6, 0.0,
                "BLEND 1");
}

}  // namespace
}  // namespace wt
