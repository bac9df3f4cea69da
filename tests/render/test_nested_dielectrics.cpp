// Nested dielectrics end to end (kernels/shared/media.h): a volume inside a
// volume of higher priority is not there; a boundary between two media of
// one index is no interface; a glass slab over water that overlaps it passes
// the closed form of Fresnel at its three real interfaces with Beer-Lambert
// between them.
#include "render/render_helpers.h"
#include "shared/media.h"
#include "test_util.h"

#include <cmath>

namespace wt {
namespace {

using test::expectUniform;
using test::render;

/// Reflectance at normal incidence between indices a and b.
double normalFresnel(double a, double b) { return std::pow((a - b) / (a + b), 2.0); }

WtMaterial glass(float ior, glm::vec3 sigma, std::uint32_t priority, float roughness = 0.0f) {
  return withPriority(withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, roughness), 1.0f, ior, false, sigma),
                      priority);
}

/// The unit glass ball of test::ballOnFloor (an analytic sphere), with
/// whatever `inner` adds inside it.
Scene glassBall(const WtMaterial& outer, const std::function<void(Scene&)>& inner) {
  return test::ballOnFloor([&](Scene& s) {
    s.materials.push_back(outer);
    s.materialNames.push_back("glass");
    s.spheres.push_back({glm::vec3(0.0f), 1.0f, std::uint32_t(s.materials.size() - 1)});
    inner(s);
  });
}

void addSphere(Scene& s, glm::vec3 center, float radius, const WtMaterial& m, const char* name) {
  s.materials.push_back(m);
  s.materialNames.push_back(name);
  s.spheres.push_back({center, radius, std::uint32_t(s.materials.size() - 1)});
}

/// Two renders within noise, block by block (fewer samples in the sanitizer
/// pass: the z-test scales with them).
void expectSameRender(const Scene& a, const Scene& b, const std::string& what, int maxBounces = 24,
                      Integrator integrator = Integrator::Path) {
  RenderSettings s;
  s.width = s.height = 32;
  s.maxBounces = maxBounces;
  s.integrator = integrator;
  s.background = glm::vec3(0.05f);
  s.seed = 5;
  const int spp = int(test::testSize(256, 96));
  const Image first = render(a, s, spp);
  s.seed = 6;
  const Image second = render(b, s, spp);
  test::expectSameImage(first, second, 4, 4.5, what);
}

const glm::vec3 kGlassSigma(0.3f, 0.6f, 1.0f);

// A volume of lower priority inside the glass (another index, another
// absorption, off centre) lies where the glass outranks it: the ball renders
// as solid glass.
TEST(NestedDielectrics, AVolumeOfLowerPriorityInsideGlassIsNotThere) {
  const WtMaterial outer = glass(1.5f, kGlassSigma, 1);
  const Scene solid = glassBall(outer, [](Scene&) {});
  const Scene nested = glassBall(outer, [](Scene& s) {
    addSphere(s, glm::vec3(0.1f, 0.2f, 0.0f), 0.6f, glass(1.33f, glm::vec3(3.0f, 0.1f, 2.0f), 0), "water");
  });
  expectSameRender(solid, nested, "a lower-priority sphere inside the glass");
}

// False hits are no bounces: at a bounce limit of 3 the floor seen through
// the ball (glass in, glass out, the floor's light sample) is as bright with
// the lower-priority sphere inside as without it, though that sphere adds
// two hits on the way (four when the camera ray passes it and the floor
// does not light it). Counting them as bounces leaves the floor black
// behind the ball.
TEST(NestedDielectrics, FalseHitsDoNotCountAsBounces) {
  const WtMaterial outer = glass(1.5f, kGlassSigma, 1);
  const Scene solid = glassBall(outer, [](Scene&) {});
  const Scene nested = glassBall(outer, [](Scene& s) {
    addSphere(s, glm::vec3(0.0f, -0.1f, 0.0f), 0.7f, glass(1.33f, glm::vec3(3.0f, 0.1f, 2.0f), 0), "water");
  });
  expectSameRender(solid, nested, "path, 3 bounces", 3);
  expectSameRender(solid, nested, "minimal, 3 bounces", 3, Integrator::Minimal);
}

// The cap on free false hits (WT_MAX_FALSE_HITS, 16): ten nested shells of
// lower priority inside the ball put up to twenty false hits on a path
// through its middle. With bounces to spare the ball still renders as solid
// glass (what the cap charges fits the limit); at a bounce limit of 3 the
// false hits past the 16th are bounces and end the paths through the middle
// before they reach the floor: the image is darker than the solid ball's.
TEST(NestedDielectrics, FalseHitsPastTheCapCountAsBounces) {
  const WtMaterial outer = glass(1.5f, kGlassSigma, 1);
  const Scene solid = glassBall(outer, [](Scene&) {});
  const Scene shells = glassBall(outer, [](Scene& s) {
    for (int k = 0; k < 10; ++k)
      addSphere(s, glm::vec3(0.0f), 0.95f - 0.05f * float(k), glass(1.33f, glm::vec3(0.5f), 0), "shell");
  });
  expectSameRender(solid, shells, "24 bounces", 24);
  RenderSettings s;
  s.width = s.height = 32;
  s.maxBounces = 3;
  s.background = glm::vec3(0.05f);
  s.seed = 5;
  const int spp = int(test::testSize(256, 96));
  const Image a = render(solid, s, spp);
  s.seed = 6;
  const Image b = render(shells, s, spp);
  // Red, in the ball's middle where the paths cut short lie: the glass
  // absorbs red least, so there the loss is largest against the noise (about
  // 10 sigma at 96 spp; blue, absorbed most, loses about 3 sigma there).
  const test::BlockStat x = test::blockStat(a, 8, 8, 24, 24, 0), y = test::blockStat(b, 8, 8, 24, 24, 0);
  EXPECT_LT(y.mean, x.mean - 5.0 * std::sqrt(x.varianceOfMean + y.varianceOfMean)) << "red, the ball's middle";
}

// An inner volume of the glass's own index and absorption but higher
// priority is a boundary between equal media: no reflection, no bending.
TEST(NestedDielectrics, ABoundaryBetweenMediaOfOneIndexIsNoInterface) {
  for (float roughness : {0.0f, 0.4f}) {
    const WtMaterial outer = glass(1.5f, kGlassSigma, 0, roughness);
    const Scene solid = glassBall(outer, [](Scene&) {});
    const Scene nested = glassBall(outer, [&](Scene& s) {
      addSphere(s, glm::vec3(0.0f, 0.1f, 0.1f), 0.55f, glass(1.5f, kGlassSigma, 1, roughness), "inner glass");
    });
    expectSameRender(solid, nested, "roughness " + std::to_string(roughness));
  }
}

// A glass slab (y in [0.5, 1], index 1.5, priority 1) over water (index
// 1.33, priority 0) modelled overlapping it (y in [0, 0.55]), seen from
// above at normal incidence with an emitter below: the interfaces are air to
// glass, glass to water (at y = 0.5: the water's top face lies inside the
// glass and is passed) and water to air, light bouncing between them, each
// layer absorbing on every crossing. Two interfaces a and b over a layer of
// transmittance tau pass T_a tau T_b / (1 - R_a R_b tau^2) and reflect,
// from b's side, R_b + T_b^2 tau^2 R_a / (1 - R_a R_b tau^2).
TEST(NestedDielectrics, GlassOverOverlappingWaterPassesTheStackedSlabsClosedForm) {
  const glm::vec3 emitted(1.0f, 2.0f, 4.0f), glassSigma(0.2f, 0.4f, 0.8f), waterSigma(0.6f, 0.3f, 0.1f);
  Scene scene = test::makeFloor(3.0f, -1.0f, makeMaterial(glm::vec3(0.0f), emitted));
  appendScene(scene, makeBox(glm::vec3(-2.0f, 0.5f, -2.0f), glm::vec3(2.0f, 1.0f, 2.0f), glass(1.5f, glassSigma, 1)));
  appendScene(scene, makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, 0.55f, 2.0f), glass(1.33f, waterSigma, 0)));
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 1.0f);
  const double r1 = normalFresnel(1.0, 1.5), r2 = normalFresnel(1.5, 1.33), r3 = normalFresnel(1.33, 1.0);
  glm::dvec3 expected;
  for (int c = 0; c < 3; ++c) {
    const double tauGlass = std::exp(-0.5 * glassSigma[c]), tauWater = std::exp(-0.5 * waterSigma[c]);
    const double d12 = 1.0 - r1 * r2 * tauGlass * tauGlass;
    const double t12 = (1.0 - r1) * tauGlass * (1.0 - r2) / d12;
    const double r12 = r2 + (1.0 - r2) * (1.0 - r2) * tauGlass * tauGlass * r1 / d12;
    expected[c] = emitted[c] * t12 * tauWater * (1.0 - r3) / (1.0 - r12 * r3 * tauWater * tauWater);
  }
  RenderSettings s;
  s.width = s.height = 8;
  s.maxBounces = 64;
  s.seed = 5;
  for (Integrator integrator : {Integrator::Path, Integrator::Minimal}) {
    s.integrator = integrator;
    expectUniform(render(scene, s, 256), expected, 1e-4, 5.0, integrator == Integrator::Path ? "path" : "minimal");
  }
}

// The camera inside a volume starts its paths in it (host/render/camera_media.h):
// under water (y in [0, 3], index 1.33, priority 0), looking straight down
// at y = 2 through a submerged block of another absorption and the water's
// index (y in [0.5, 1], priority 1) onto an emitter below the water. The
// only interfaces are the water's faces (reflectance R each way) and the
// column absorbs everywhere: the upward radiance at the camera is
// n^2 tau_up (1 - R) E / (1 - R^2 tau^2), tau_up the column below the
// camera, tau the whole column and n^2 the squared index radiance gains
// entering water (bsdf.cl scales it so). A camera taken to start in air
// sees a glass face of index ratio 1.33 on the way in and out, no water
// above it, and misses the factor exp(-sigma_water) of it.
TEST(NestedDielectrics, ACameraUnderWaterStartsInTheWater) {
  const glm::vec3 emitted(1.0f, 2.0f, 4.0f), waterSigma(0.6f, 0.3f, 0.1f), blockSigma(0.2f, 0.4f, 0.8f);
  Scene scene = test::makeFloor(3.0f, -1.0f, makeMaterial(glm::vec3(0.0f), emitted));
  appendScene(scene, makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, 3.0f, 2.0f), glass(1.33f, waterSigma, 0)));
  appendScene(scene,
              makeBox(glm::vec3(-1.5f, 0.5f, -1.5f), glm::vec3(1.5f, 1.0f, 1.5f), glass(1.33f, blockSigma, 1)));
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 2.0f, 0.0f), 1.0f);
  const double r = normalFresnel(1.33, 1.0);
  glm::dvec3 expected;
  for (int c = 0; c < 3; ++c) {
    const double tauUp = std::exp(-1.5 * waterSigma[c] - 0.5 * blockSigma[c]);
    const double tau = tauUp * std::exp(-1.0 * waterSigma[c]);
    expected[c] = 1.33 * 1.33 * emitted[c] * tauUp * (1.0 - r) / (1.0 - r * r * tau * tau);
  }
  RenderSettings s;
  s.width = s.height = 8;
  s.maxBounces = 64;
  s.seed = 7;
  // the image's mean (a pixel whose paths all crossed the water's face has no variance to test against)
  for (Integrator integrator : {Integrator::Path, Integrator::Minimal}) {
    s.integrator = integrator;
    const Image img = render(scene, s, 256);
    for (int c = 0; c < 3; ++c) {
      const test::BlockStat all = test::blockStat(img, 0, 0, img.width, img.height, c);
      EXPECT_NEAR(all.mean, expected[c], 5.0 * std::sqrt(all.varianceOfMean) + 1e-4 * expected[c])
          << (integrator == Integrator::Path ? "path" : "minimal") << ", channel " << c;
    }
  }
}

// KHR_materials_dispersion: a slab at normal incidence passes (1 - F)^2
// tau / (1 - F^2 tau^2) in each channel with F from that channel's index.
// Each path carries one channel, picked at the first interface, three times
// as strong: over the image the channel means must be the three closed
// forms (their differences are many standard errors at this exaggerated
// dispersion), and without dispersion the slab is one index in all three.
TEST(NestedDielectrics, DispersionGivesEachChannelItsOwnIndexUnbiased) {
  const glm::vec3 emitted(1.0f, 2.0f, 4.0f), sigma(0.3f, 0.2f, 0.1f);
  const float ior = 1.5f, dispersion = 20.0f, d = 0.5f;
  auto slabScene = [&](float dispersionOfSlab) {
    Scene scene = test::makeFloor(3.0f, -1.0f, makeMaterial(glm::vec3(0.0f), emitted));
    appendScene(scene, makeBox(glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, d, 2.0f),
                               withDispersion(glass(ior, sigma, 0), dispersionOfSlab)));
    scene.camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 1.0f);
    return scene;
  };
  auto closedForm = [&](int c, float n) {
    const double f = normalFresnel(1.0, n), tau = std::exp(-double(sigma[c]) * d);
    return emitted[c] * (1.0 - f) * (1.0 - f) * tau / (1.0 - f * f * tau * tau);
  };
  RenderSettings s;
  s.width = s.height = 16;
  s.maxBounces = 32;
  s.seed = 9;
  const Image img = render(slabScene(dispersion), s, 512);
  for (int c = 0; c < 3; ++c) {
    const double expected = closedForm(c, media_channel_ior(ior, dispersion, std::uint32_t(c)));
    const double plain = closedForm(c, ior);
    const test::BlockStat all = test::blockStat(img, 0, 0, img.width, img.height, c);
    const double se = std::sqrt(all.varianceOfMean);
    EXPECT_NEAR(all.mean, expected, 4.0 * se) << "channel " << c;
    if (c != 1) {
      EXPECT_GT(std::abs(plain - expected), 6.0 * se) << "channel " << c << ": the test cannot tell";
    }
  }
  // no dispersion: the slab's own index in every channel, within each
  // pixel's noise (enough samples that every pixel sees a reflection: a
  // pixel without one has no variance to test against)
  glm::dvec3 plain;
  for (int c = 0; c < 3; ++c) plain[c] = closedForm(c, ior);
  expectUniform(render(slabScene(0.0f), s, 256), plain, 1e-4, 5.0, "dispersion 0");
}

}  // namespace
}  // namespace wt
