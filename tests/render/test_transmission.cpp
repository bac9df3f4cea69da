// Transmission end to end (KHR_materials_transmission, _ior, _volume):
// closed forms through slabs and thin walls -- Fresnel at both faces, the
// light bouncing between them, Beer-Lambert absorption inside -- the
// transmission bounce limit, and `path` against `minimal` through rough and
// smooth glass.
#include "render/render_helpers.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <cmath>

namespace wt {
namespace {

using test::expectUniform;
using test::render;

/// Reflectance of a dielectric interface at normal incidence.
double normalFresnel(double ior) { return std::pow((ior - 1.0) / (ior + 1.0), 2.0); }


const glm::vec3 kEmitted(1.0f, 2.0f, 4.0f);

/// An emitter facing up at y = -1 (black elsewhere), seen from above by an
/// orthographic camera through whatever `between` holds: every camera ray
/// meets it at normal incidence.
Scene throughTo(const Scene& between) {
  Scene scene = test::makeFloor(3.0f, -1.0f, makeMaterial(glm::vec3(0.0f), kEmitted));
  appendScene(scene, between);
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 1.0f);
  return scene;
}

RenderSettings settings(Integrator integrator = Integrator::Path) {
  RenderSettings s;
  s.width = s.height = 8;
  s.integrator = integrator;
  s.maxBounces = 64;
  s.seed = 5;
  return s;
}

// A slab of glass (ior 1.5, thickness d, absorbing sigma per unit length):
// light crosses the first face with 1 - F, is absorbed by tau = exp(-sigma
// d) per crossing of the inside, and bounces between the faces, so the
// slab passes (1 - F)^2 tau / (1 - F^2 tau^2) in all (the incoherent sum).
TEST(Transmission, SlabPassesFresnelAndBeerLambertWithInterreflections) {
  const double ior = 1.5, d = 0.5;
  const glm::vec3 sigma(0.2f, 1.0f, 3.0f);
  for (float roughness : {0.0f}) {
    Scene scene = throughTo(makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, float(d), 2.0f),
                                    withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, roughness), 1.0f,
                                                     float(ior), false, sigma)));
    double f = normalFresnel(ior);
    glm::dvec3 expected;
    for (int c = 0; c < 3; ++c) {
      double tau = std::exp(-double(sigma[c]) * d);
      expected[c] = kEmitted[c] * (1.0 - f) * (1.0 - f) * tau / (1.0 - f * f * tau * tau);
    }
    for (Integrator integrator : {Integrator::Path, Integrator::Minimal})
      expectUniform(render(scene, settings(integrator), 256), expected, 1e-4, 5.0,
                    integrator == Integrator::Path ? "path" : "minimal");
  }
}

// Russian roulette inside glass: the throughput carries 1/n^2 there (the
// radiance scaling), which the crossing out gives back, so survival must
// look at beta n^2. Through a clear smooth slab at normal incidence from
// bounce 0 on, every roulette then survives with 0.95 and a sample is L /
// 0.95^(2 + 2j) with probability (1 - F)^2 F^(2j) (j reflections inside),
// else 0: its relative variance is known. Survival by beta alone (0.44 in
// the glass) gives 7.5x that (1.51 against 0.20).
TEST(Transmission, RouletteInsideGlassUndoesTheRadianceScaling) {
  const double ior = 1.5, f = normalFresnel(ior), q = 0.95;
  Scene scene = throughTo(makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, 1.0f, 2.0f),
                                  withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, float(ior))));
  double mean = 0.0, square = 0.0;  // E[X] and E[X^2] over L
  for (int j = 0; j < 30; ++j) {
    double p = (1.0 - f) * (1.0 - f) * std::pow(f, 2.0 * j), x = std::pow(q, -2.0 - 2.0 * j);
    mean += p, square += p * x;  // it survives with 1 / x, then counts x^2
  }
  const double expected = square / (mean * mean) - 1.0;
  for (bool lanes : {true, false}) {
    RenderSettings s = settings();
    s.width = s.height = 64;
    s.rrMinDepth = 0;
    s.sobol = false;
    s.shadeLanes = lanes;
    Image img = render(scene, s, 1);  // a pixel is one sample
    // the relative variance of the samples (blue: the brightest) and its standard error by the delta method
    const int n = img.width * img.height;
    double m1 = 0.0, m2 = 0.0, m3 = 0.0, m4 = 0.0;
    for (int i = 0; i < n; ++i) {
      double x = img.rgb[3 * i + 2] / kEmitted.z;
      m1 += x / n, m2 += x * x / n, m3 += x * x * x / n, m4 += x * x * x * x / n;
    }
    const double rel = m2 / (m1 * m1) - 1.0;
    const double g1 = -2.0 * m2 / (m1 * m1 * m1), g2 = 1.0 / (m1 * m1);  // d rel / d m1, d rel / d m2
    const double se = std::sqrt((g1 * g1 * (m2 - m1 * m1) + 2.0 * g1 * g2 * (m3 - m1 * m2) + g2 * g2 * (m4 - m2 * m2)) / n);
    EXPECT_NEAR(m1, mean, 5.0 * std::sqrt((m2 - m1 * m1) / n)) << (lanes ? "lanes" : "one path per work-item");
    EXPECT_NEAR(rel, expected, 5.0 * se) << (lanes ? "lanes" : "one path per work-item");
  }
}

// ior 1 bends and reflects nothing at any roughness: what is left is the
// absorption alone, exactly (no sample varies). One render per test, so
// that scripts/oclgrind can run one of them (renders in sequence under
// Oclgrind report uninitialised values, docs/stability.md).
void expectIndexOneSlabIsPureBeerLambert(float roughness) {
  const double d = 0.75;
  const glm::vec3 sigma(0.1f, 0.5f, 2.0f);
  Scene scene = throughTo(makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, float(d), 2.0f),
                                  withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, roughness), 1.0f, 1.0f, false,
                                                   sigma)));
  glm::dvec3 expected;
  for (int c = 0; c < 3; ++c) expected[c] = kEmitted[c] * std::exp(-double(sigma[c]) * d);
  Image img = render(scene, settings(), 4);
  expectUniform(img, expected, 2e-6, 0.0, "roughness " + std::to_string(roughness));
}

TEST(Transmission, IndexOneSlabIsPureBeerLambert) { expectIndexOneSlabIsPureBeerLambert(0.0f); }
TEST(Transmission, RoughIndexOneSlabIsPureBeerLambert) { expectIndexOneSlabIsPureBeerLambert(0.6f); }

// A thin wall is one interface that light crosses unbent: 1 - F of it,
// tinted by the base colour, and nothing from between two faces.
TEST(Transmission, ThinWallPassesOneMinusFresnelTintedByTheBaseColour) {
  const glm::vec3 tint(0.9f, 0.5f, 0.25f);
  Scene wall = test::makeFloor(2.0f, 0.0f, withTransmission(makePbrMaterial(tint, 0.0f, 0.0f), 1.0f, 1.5f, true));
  Scene scene = throughTo(wall);
  double f = normalFresnel(1.5);
  glm::dvec3 expected = glm::dvec3(kEmitted) * glm::dvec3(tint) * (1.0 - f);
  expectUniform(render(scene, settings(), 256), expected, 1e-4, 5.0, "thin wall");
}

// --max-transmission-bounces counts crossings: a slab takes two (in and
// out), a thin wall one; below that the emitter is not seen through them.
TEST(Transmission, TheBounceLimitCountsCrossings) {
  const glm::vec3 sigma(0.5f);
  Scene slab = throughTo(makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, 1.0f, 2.0f),
                                 withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.0f, false, sigma)));
  Scene wall = throughTo(test::makeFloor(2.0f, 0.0f, withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f),
                                                                       1.0f, 1.0f, true)));
  auto limited = [](int limit) {
    RenderSettings s = settings();
    s.maxTransmissionBounces = limit;
    return s;
  };
  const glm::dvec3 black(0.0), through = glm::dvec3(kEmitted) * std::exp(-0.5);
  expectUniform(render(slab, limited(1), 2), black, 0.0, 0.0, "slab, 1 crossing allowed");
  expectUniform(render(slab, limited(2), 2), through, 2e-6, 0.0, "slab, 2 crossings allowed");
  expectUniform(render(wall, limited(0), 2), black, 0.0, 0.0, "thin wall, none allowed");
  expectUniform(render(wall, limited(1), 2), glm::dvec3(kEmitted), 2e-6, 0.0, "thin wall, 1 allowed");
  // and --max-bounces stays the bound over all: 1 bounce cannot leave the slab
  RenderSettings one = settings();
  one.maxBounces = 1;
  expectUniform(render(slab, one, 2), black, 0.0, 0.0, "slab, 1 bounce in all");
}

// `path` (NEE through transmitting surfaces towards lights on their far
// side, MIS against BSDF sampling through rough glass, the light tree with
// its receiver bound switched off there) against `minimal` (no NEE for
// emitters): a floor with rough and smooth glass spheres, an absorbing
// rough glass box, a thin rough pane and a glass-metal mix, lit by an
// emissive quad, a point light and the sky.
TEST(Transmission, PathMatchesMinimalThroughGlass) {
  Scene scene = test::makeFloor(2.0f, 0.0f, makePbrMaterial(glm::vec3(0.7f, 0.6f, 0.5f), 0.0f, 0.6f));
  appendScene(scene, makeIcosphere(2, glm::vec3(-0.55f, 0.45f, 0.0f), 0.45f,
                                   withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.3f), 1.0f, 1.5f)));
  appendScene(scene, makeIcosphere(2, glm::vec3(0.5f, 0.35f, 0.3f), 0.35f,
                                   withTransmission(makePbrMaterial(glm::vec3(0.9f, 1.0f, 0.9f), 0.0f, 0.0f), 1.0f,
                                                    1.33f)));
  appendScene(scene, makeBox(glm::vec3(0.2f, 0.0f, -0.9f), glm::vec3(0.8f, 0.5f, -0.4f),
                             withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.5f), 1.0f, 1.5f, false,
                                              glm::vec3(0.3f, 0.8f, 1.5f))));
  appendScene(scene, makeIcosphere(1, glm::vec3(-0.2f, 0.2f, 0.75f), 0.2f,
                                   withTransmission(makePbrMaterial(glm::vec3(0.8f), 0.4f, 0.4f), 0.6f, 1.5f)));
  Scene pane = test::makeFloor(0.5f, 0.0f, withTransmission(makePbrMaterial(glm::vec3(0.8f, 0.8f, 1.0f), 0.0f, 0.25f),
                                                            1.0f, 1.5f, true));
  for (WtVec4& p : pane.positions) std::swap(p.y, p.z), p.y += 0.5f, p.x -= 0.9f, p.z += 0.6f;  // standing up
  appendScene(scene, pane);
  appendScene(scene, test::makeFloor(0.35f, 1.7f, makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f)), /*faceDown=*/true));
  PunctualLight point;
  point.type = WT_LIGHT_POINT;
  point.position = {1.0f, 2.2f, 1.5f};
  point.intensity = {3.0f, 3.0f, 2.5f};
  scene.lights = {point};
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.3f, 2.8f), glm::vec3(0.0f, 0.35f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = cam;
  // 32x32 pixels at a quarter of 16x16's samples: each of the 4x4 blocks
  // compared holds as many samples as at 16x16, in a quarter of the launches
  // (whose host side the sanitizers slow)
  RenderSettings s = settings(Integrator::Minimal);
  s.width = s.height = 32;
  s.maxBounces = 8;
  s.background = glm::vec3(0.2f, 0.3f, 0.45f);
  Image reference = render(scene, s, 1024);
  for (LightSampler sampler : {LightSampler::Power, LightSampler::Tree}) {
    RenderSettings p = s;
    p.integrator = Integrator::Path;
    p.lightSampler = sampler;
    Image img = render(scene, p, 256);
    test::expectSameImage(reference, img, 4, 5.0, sampler == LightSampler::Tree ? "path, light tree" : "path, by power");
  }
  // power: a 5% bias over the image would be many standard errors
  test::BlockStat all = test::blockStat(reference, 0, 0, reference.width, reference.height, 1);
  EXPECT_LT(std::sqrt(all.varianceOfMean), 0.01 * all.mean);
}

// Light reaching a frosted thin pane from its far side: the camera below
// sees the pane lit from above through it. `path` estimates that mostly by
// NEE through the pane (a shadow ray from the pane's far side), MIS-weighted
// against BSDF sampling through it; `minimal` by BSDF sampling alone.
// Without NEE through the surface the MIS weights lose the light's share
// (measured: a corner block 40x darker).
TEST(Transmission, NextEventEstimationReachesLightsThroughAThinWall) {
  Scene scene = test::makeFloor(1.0f, 0.0f, withTransmission(makePbrMaterial(glm::vec3(0.9f), 0.0f, 0.8f), 1.0f, 1.5f, true));
  appendScene(scene, test::makeFloor(0.3f, 0.6f, makeMaterial(glm::vec3(0.0f), glm::vec3(5.0f)), /*faceDown=*/true));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, -1.5f, 0.3f), glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(0, 0, -1)));
  cam.yfov = 0.9f;
  scene.camera = cam;
  RenderSettings s = settings(Integrator::Minimal);
  s.width = s.height = 16;
  s.maxBounces = 4;
  // (the z test scales with the renders' variances: a quarter of the samples in the sanitizer pass)
  Image reference = render(scene, s, test::testSize(2048, 512));
  s.integrator = Integrator::Path;
  Image img = render(scene, s, test::testSize(512, 128));
  test::expectSameImage(reference, img, 4, 5.0, "frosted pane lit from behind");
  test::BlockStat all = test::blockStat(img, 0, 0, img.width, img.height, 1);
  EXPECT_GT(all.mean, 0.05) << "the pane is lit";
}

// Shadow rays cross smooth thin walls (connect.cl): a white Lambertian
// floor lit by a quad light through a tinted smooth thin sheet wider than
// the floor, seen from below the sheet, so the light reaches the floor only
// through the sheet. NEE through the sheet (alone, and MIS-weighted against
// the paths that shade continues straight through it from the floor) must
// give what BSDF sampling alone gives, at --max-bounces 1 (no light through
// the sheet: the shadow ray may cross no wall) and 4. Fails (|z| 11 to 110)
// when the crossing is not tinted, when a path through the sheet is weighed
// as if NEE had not reached its light, or when the budget lets a shadow ray
// cross a wall that the path could not.
TEST(Transmission, ShadowRaysThroughASmoothThinWallChangeNothingButTheNoise) {
  Scene scene = test::makeFloor(1.0f, 0.0f, makeMaterial(glm::vec3(0.8f)));
  appendScene(scene, test::makeFloor(1.2f, 0.4f, withTransmission(makePbrMaterial(glm::vec3(0.9f, 0.6f, 0.3f), 0.0f, 0.0f),
                                                                   1.0f, 1.5f, true)));
  appendScene(scene, test::makeFloor(0.5f, 1.0f, makeMaterial(glm::vec3(0.0f), glm::vec3(4.0f)), /*faceDown=*/true));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 0.3f, 1.6f), glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(0, 1, 0)));
  cam.yfov = 0.8f;
  scene.camera = cam;
  // 32x32 pixels, few samples each: 4x4 blocks of 64 pixels, in few
  // launches; BSDF sampling alone is `path` without NEE (the program of the
  // thin-wall tests above, where `minimal` would compile one more)
  RenderSettings s = settings();
  s.width = s.height = 32;
  for (int bounces : {1, 4}) {
    s.maxBounces = bounces;
    s.useNee = false;
    Image reference = render(scene, s, bounces == 1 ? 16 : 256);
    if (bounces > 1) {
      EXPECT_GT(test::blockStat(reference, 0, 16, 32, 32, 2).mean, 0.05) << "the floor is lit";
    }
    s.useNee = true;
    s.useMis = true;
    const std::string at = " at --max-bounces " + std::to_string(bounces);
    test::expectSameImage(reference, render(scene, s, 32), 4, 5.0, "NEE and MIS through the sheet" + at);
    s.useMis = false;
    test::expectSameImage(reference, render(scene, s, 32), 4, 5.0, "NEE alone through the sheet" + at);
  }
}

/// An n x n texture (nearest, no mips: every footprint reads the same texel)
/// whose texel (x, y) is rgba(x, y); sRGB for colour, else linear.
template <class Texel>
std::uint32_t addTexelTexture(Scene& scene, std::uint32_t n, bool srgb, Texel rgba) {
  DecodedImage image;
  image.width = image.height = n;
  image.name = srgb ? "tint" : "transmission";
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x)
      for (std::uint8_t c : rgba(x, y)) image.rgba8.push_back(c);
  return scene.textures.addTexture(scene.textures.addImage(image, srgb), -1, -1, test::kNearest, test::kNearest);
}

// The same through smooth thin panes whose tint varies over them: shadow
// rays read it where they cross (connect.cl), as shade does for a path
// through the pane. Left, a pane tinted by a base colour texture (a 4x4
// checker of colours) and a transmission texture (a 2x2 one, down to 0.25);
// right, one tinted by COLOR_0 (a different colour at each corner). NEE
// (with MIS, and alone) against BSDF sampling alone, block by block; and
// the noise under the panes must be lower with NEE at 32 samples than
// without it at 256, which it is not when the textured or vertex-coloured
// panes block shadow rays (their light is then found by BSDF sampling
// alone, the same estimator at an eighth of the samples: a standard error
// sqrt(8) times larger). The blocks fail when connect weighs a pane by its
// factors alone, ignores COLOR_0, or reads the pane at the wrong point.
TEST(Transmission, ShadowRaysReadATexturedOrVertexColouredPanesTintWhereTheyCross) {
  const WtMaterial glass = withTransmission(makePbrMaterial(glm::vec3(0.95f, 0.9f, 0.85f), 0.0f, 0.0f), 1.0f, 1.5f, true);
  auto pane = [&](float x0, float x1) {
    Scene half = test::makeFloor(1.2f, 0.4f, glass);
    for (std::size_t v = 0; v < half.positions.size(); ++v) {
      WtVec4& p = half.positions[v];
      p.x = p.x < 0.0f ? x0 : x1;
      half.texcoords[v] = glm::vec2((p.x - x0) / (x1 - x0), (p.z + 1.2f) / 2.4f);
    }
    return half;
  };
  Scene scene = test::makeFloor(1.0f, 0.0f, makeMaterial(glm::vec3(0.8f)));
  appendScene(scene, pane(-1.2f, 0.0f));  // material 1: textured
  Scene coloured = pane(0.0f, 1.2f);      // material 2: COLOR_0
  coloured.colors = {{1.0f, 0.3f, 0.2f, 1.0f}, {0.2f, 1.0f, 0.3f, 1.0f}, {0.3f, 0.2f, 1.0f, 1.0f}, {1.0f, 1.0f, 1.0f, 1.0f}};
  appendScene(scene, coloured);
  // a lamp small enough that BSDF sampling finds it rarely from the floor
  appendScene(scene, test::makeFloor(0.35f, 1.0f, makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f)), /*faceDown=*/true));
  ASSERT_EQ(scene.colors.size(), scene.positions.size());
  const std::uint32_t tint = addTexelTexture(scene, 4, true, [](std::uint32_t x, std::uint32_t y) {
    return std::array<std::uint8_t, 4>{std::uint8_t(80 + 50 * x), std::uint8_t(255 - 50 * y), std::uint8_t((x + y) % 2 ? 60 : 230), 255};
  });
  const std::uint32_t share = addTexelTexture(scene, 2, false, [](std::uint32_t x, std::uint32_t y) {
    std::uint8_t r = x + y == 1 ? (x ? 128 : 64) : 255;
    return std::array<std::uint8_t, 4>{r, r, r, 255};
  });
  test::setBaseColorTexture(scene, 1, tint);
  test::setMaterialTexture(scene, 1, WT_TEXTURE_SLOT_TRANSMISSION, share);
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 0.3f, 1.6f), glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(0, 1, 0)));
  cam.yfov = 0.8f;
  scene.camera = cam;
  RenderSettings s = settings();
  s.width = s.height = 32;
  s.maxBounces = 4;
  s.useNee = false;
  const int referenceSpp = 256, neeSpp = 32;
  Image reference = render(scene, s, referenceSpp);
  // the floor under each pane: its left and right halves of the image's lower half
  auto floorStat = [](const Image& img, int side, int channel) {
    return test::blockStat(img, side * 16, 16, side * 16 + 16, 32, channel);
  };
  for (int side : {0, 1}) {
    EXPECT_GT(floorStat(reference, side, 1).mean, 0.05) << "the floor is lit, side " << side;
  }
  s.useNee = true;
  for (bool mis : {true, false}) {
    s.useMis = mis;
    const std::string what = mis ? "NEE and MIS through the panes" : "NEE alone through the panes";
    Image img = render(scene, s, neeSpp);
    test::expectSameImage(reference, img, 4, 5.0, what);
    for (int side : {0, 1})
      for (int c = 0; c < 3; ++c)
        EXPECT_LT(floorStat(img, side, c).varianceOfMean, floorStat(reference, side, c).varianceOfMean)
            << what << ": the floor under the " << (side ? "vertex-coloured" : "textured") << " pane, channel " << c;
  }
}

// Shadow rays inside an absorbing volume (shade.cl): a floor and a lamp
// inside a large box of absorbing index-1 glass, the camera inside too.
// Light reaching the floor crosses the medium either way, so NEE (with MIS,
// and alone) must give what BSDF sampling alone gives, which absorbs along
// every segment; without absorption along its shadow rays NEE is brighter.
TEST(Transmission, ShadowRaysInsideAnAbsorbingVolumeAreAbsorbed) {
  Scene scene = test::makeFloor(1.0f, 0.0f, makeMaterial(glm::vec3(0.8f)));
  appendScene(scene, test::makeFloor(0.35f, 1.0f, makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f)), /*faceDown=*/true));
  appendScene(scene, makeBox(glm::vec3(-1.5f, -0.5f, -1.5f), glm::vec3(1.5f, 1.5f, 2.5f),
                             withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.0f, false,
                                              glm::vec3(0.2f, 0.6f, 1.2f))));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 0.3f, 1.6f), glm::vec3(0.0f, 0.0f, 0.0f), glm::vec3(0, 1, 0)));
  cam.yfov = 0.8f;
  scene.camera = cam;
  RenderSettings s = settings();
  s.width = s.height = 32;
  s.maxBounces = 4;
  s.useNee = false;
  Image reference = render(scene, s, 256);
  EXPECT_GT(test::blockStat(reference, 0, 16, 32, 32, 0).mean, 0.05) << "the floor is lit";
  s.useNee = true;
  for (bool mis : {true, false}) {
    s.useMis = mis;
    test::expectSameImage(reference, render(scene, s, 32), 4, 5.0,
                          mis ? "NEE and MIS inside the medium" : "NEE alone inside the medium");
  }
}

// NEE through a rough volume boundary (shade.cl): a lamp inside a box of
// rough absorbing glass (index 1.5), over a smooth tinted thin pane and a
// floor inside the box too, the camera outside facing the box under a sky.
// At the box's outer face NEE samples the lamp through the face (the shadow
// ray is absorbed by the medium on the far side, and crosses the pane
// inside it), at its inner faces the sky beyond (unabsorbed: the path was
// absorbed on its way there) and the lamp on the near side; MIS weighs
// these against the paths that refract into and out of the box. NEE with
// MIS must give what BSDF sampling alone gives; it fails (worst |z| 10)
// when the far or the near side's medium does not absorb. (NEE without MIS
// is unbiased here too, but at a rough refracting boundary its rare large
// samples make 32 samples' variance an underestimate; 2048 samples agree,
// docs/lab/2026-12-06-rough-boundary-nee.md.) The pane makes this the
// program of the thin-wall test above.
TEST(Transmission, NextEventEstimationThroughARoughBoundaryIsAbsorbedOnTheFarSide) {
  Scene scene = makeBox(glm::vec3(-0.6f, 0.05f, -0.6f), glm::vec3(0.6f, 1.05f, 0.6f),
                        withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.6f), 1.0f, 1.5f, false,
                                         glm::vec3(0.3f, 0.9f, 2.0f)));
  appendScene(scene, test::makeFloor(0.5f, 0.95f, makeMaterial(glm::vec3(0.0f), glm::vec3(3.0f)), /*faceDown=*/true));
  appendScene(scene, test::makeFloor(0.4f, 0.55f, withTransmission(makePbrMaterial(glm::vec3(0.9f, 0.7f, 0.5f), 0.0f, 0.0f),
                                                                    1.0f, 1.5f, true)));
  appendScene(scene, test::makeFloor(0.55f, 0.1f, makeMaterial(glm::vec3(0.8f))));
  CameraDesc cam;
  cam.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 0.5f, 2.2f), glm::vec3(0.0f, 0.5f, 0.0f), glm::vec3(0, 1, 0)));
  cam.yfov = 0.75f;
  scene.camera = cam;
  RenderSettings s = settings();
  s.width = s.height = 32;
  s.maxBounces = 4;
  s.background = glm::vec3(0.2f, 0.3f, 0.45f);
  s.useNee = false;
  Image reference = render(scene, s, 256);
  EXPECT_GT(test::blockStat(reference, 8, 8, 24, 24, 2).mean, 0.02) << "the box is lit";
  s.useNee = true;
  s.useMis = true;
  test::expectSameImage(reference, render(scene, s, 32), 4, 5.0, "NEE and MIS through the rough boundary");
}

}  // namespace
}  // namespace wt
