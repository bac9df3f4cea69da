// Analytic spheres rendered against closed forms: a white sphere in a
// uniform sky at several scales and far from the origin (every pixel is the
// sky's radiance unless a spawned ray hits the sphere it left), and a sphere
// light over a Lambertian floor (the irradiance of a uniform sphere), with
// and without next-event estimation and MIS.
#include "geometry/primitives.h"
#include "render/render_helpers.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <string>

namespace wt {
namespace {

struct FurnaceCase {
  float scale;       ///< sphere radius
  float offset;      ///< distance of the sphere and camera from the origin
  bool minimal;      ///< the brute-force integrator
  bool packets = true;  ///< camera and their shadow rays in packets (else one by one)
  bool nee = true;
};

class WhiteSphereInUniformSky : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(WhiteSphereInUniformSky, EveryPixelIsTheSky) {
  const FurnaceCase c = GetParam();
  const glm::vec3 center(c.offset, 0.5f * c.offset, -0.25f * c.offset);
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(1.0f)));
  scene.materialNames.push_back("white");
  scene.spheres.push_back({center, c.scale, 0});
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), center + glm::vec3(0.0f, 0.0f, 3.2f * c.scale));
  scene.camera = camera;

  RenderSettings settings;
  settings.width = settings.height = 24;
  // one bounce: a ray that hits the sphere it leaves is cut short there and
  // loses the sky behind it, which shows as a darker pixel
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.integrator = c.minimal ? Integrator::Minimal : Integrator::Path;
  settings.seed = 3;
  settings.packets = c.packets;
  settings.useNee = c.nee;
  const Image image = test::render(scene, settings, 64);
  // a convex white Lambertian surface returns the uniform sky exactly
  test::expectUniform(image, glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0, "white sphere in a uniform sky");
}

INSTANTIATE_TEST_SUITE_P(Scales, WhiteSphereInUniformSky,
                         ::testing::Values(FurnaceCase{1.0f, 0.0f, false}, FurnaceCase{1e-4f, 0.0f, false},
                                           FurnaceCase{1e4f, 0.0f, false}, FurnaceCase{1.0f, 1e6f, false},
                                           FurnaceCase{1e-2f, 1e3f, false}, FurnaceCase{1.0f, 0.0f, true},
                                           FurnaceCase{1.0f, 1e6f, true}, FurnaceCase{1.0f, 0.0f, false, false},
                                           FurnaceCase{1.0f, 0.0f, false, true, false}),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                           const FurnaceCase& c = info.param;
                           auto exp10 = [](float v) { return v == 0.0f ? std::string("0") : "1e" + std::to_string(int(std::lround(std::log10(v)))); };
                           std::string name = "radius" + exp10(c.scale) + "_at" + exp10(c.offset) + (c.minimal ? "_minimal" : "_path") +
                                              (c.packets ? "" : "_single") + (c.nee ? "" : "_no_nee");
                           for (char& ch : name)
                             if (ch == '-') ch = 'm';
                           return name;
                         });

struct LightCase {
  Integrator integrator;
  bool mis;
  int spp;
  const char* name;
};

class SphereLightOverFloor : public ::testing::TestWithParam<LightCase> {};

// A floor of albedo rho at y = 0 lit by a black sphere of radius r and
// radiance L centred at height h: at floor point (x, z), d^2 = x^2 + h^2 + z^2,
// the irradiance is pi L (r/d)^2 (h/d), so the floor's radiance is
// rho L r^2 h / d^3. An orthographic camera between them looks straight down.
TEST_P(SphereLightOverFloor, MatchesTheClosedForm) {
  const LightCase c = GetParam();
  const float rho = 0.5f, r = 0.5f, h = 2.0f;
  const glm::vec3 le(4.0f, 2.0f, 1.0f);
  Scene scene = test::makeFloor(6.0f, 0.0f, makeMaterial(glm::vec3(rho)));
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), le));
  scene.materialNames.push_back("light");
  scene.spheres.push_back({glm::vec3(0.0f, h, 0.0f), r, 1});
  const float ymag = 2.0f;
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 1.0f, 0.0f), ymag);

  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 1;
  settings.integrator = c.integrator;
  settings.useMis = c.mis;
  settings.seed = 11;
  const Image image = test::render(scene, settings, c.spp);

  // the closed form averaged over each pixel's footprint (the camera jitters
  // uniformly within it): world x = s_x ymag, z = -s_y ymag
  auto radiance = [&](double x, double z) {
    const double d = std::sqrt(x * x + double(h) * h + z * z);
    return rho * double(r) * r * h / (d * d * d);
  };
  constexpr int kSub = 8;
  int bad = 0;
  const int block = 4;
  for (int by = 0; by < settings.height / block; ++by)
    for (int bx = 0; bx < settings.width / block; ++bx) {
      double expected = 0.0;
      for (int py = by * block; py < (by + 1) * block; ++py)
        for (int px = bx * block; px < (bx + 1) * block; ++px)
          for (int j = 0; j < kSub * kSub; ++j) {
            const double sx = 2.0 * (px + (j % kSub + 0.5) / kSub) / settings.width - 1.0;
            const double sy = 1.0 - 2.0 * (py + (j / kSub + 0.5) / kSub) / settings.height;
            expected += radiance(sx * ymag, -sy * ymag);
          }
      expected /= double(block * block * kSub * kSub);
      for (int ch = 0; ch < 3; ++ch) {
        const test::BlockStat s = test::blockStat(image, bx * block, by * block, (bx + 1) * block, (by + 1) * block, ch);
        const double want = expected * le[ch];
        // 5 standard errors, and 1e-4 of the value for the footprint's quadrature
        const double tol = 5.0 * std::sqrt(s.varianceOfMean) + 1e-4 * want;
        if (std::abs(s.mean - want) > tol && ++bad <= 5)
          ADD_FAILURE() << c.name << ": block (" << bx << ", " << by << ") channel " << ch << ": " << s.mean << " vs "
                        << want << " (tolerance " << tol << ")";
      }
    }
  EXPECT_EQ(bad, 0);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SphereLightOverFloor,
                         ::testing::Values(LightCase{Integrator::Path, true, 64, "path"},
                                           LightCase{Integrator::Path, false, 64, "path_no_mis"},
                                           LightCase{Integrator::Minimal, false, 1024, "minimal"}),
                         [](const ::testing::TestParamInfo<LightCase>& info) { return std::string(info.param.name); });

TEST(SphereLight, SeenDirectlyIsItsRadianceAndNothingBehindIt) {
  // camera rays meet the emitter's outside; its inside, seen from within,
  // does not emit (single-sided) and is black
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(3.0f, 2.0f, 1.0f)));
  scene.materialNames.push_back("light");
  scene.spheres.push_back({glm::vec3(0.0f), 1.0f, 0});
  CameraDesc outside;
  outside.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 1.5f));
  outside.yfov = 0.2f;  // the whole frame on the sphere
  scene.camera = outside;
  RenderSettings settings;
  settings.width = settings.height = 8;
  settings.maxBounces = 2;
  test::expectUniform(test::render(scene, settings, 4), glm::dvec3(3.0, 2.0, 1.0), 1e-5, 5.0, "emitter seen from outside");
  CameraDesc inside;
  inside.cameraToWorld = glm::mat4(1.0f);
  scene.camera = inside;
  test::expectUniform(test::render(scene, settings, 4), glm::dvec3(0.0), 0.0, 5.0, "emitter seen from inside");
}

}  // namespace
}  // namespace wt

namespace wt {
namespace {

TEST(SphereVersusTessellation, SameImageWithinNoise) {
  // a metallic-roughness sphere on a floor under a sphere light, once
  // analytic and once as an icosphere of 81 920 triangles (its facets stray
  // from the sphere by 3e-5 of the radius, far below the noise)
  const WtMaterial ball = makePbrMaterial(glm::vec3(0.8f, 0.5f, 0.3f), 0.0f, 0.4f);
  const Scene analytic = test::ballOnFloor([&](Scene& s) {
    s.materials.push_back(ball);
    s.materialNames.push_back("ball");
    s.spheres.push_back({glm::vec3(0.0f), 1.0f, 1});
  });
  const Scene tessellated =
      test::ballOnFloor([&](Scene& s) { appendScene(s, makeIcosphere(6, glm::vec3(0.0f), 1.0f, ball)); });
  test::expectSameBallImage(analytic, tessellated, "analytic sphere against an icosphere");
}

}  // namespace
}  // namespace wt
