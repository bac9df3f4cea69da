// Curves rendered against closed forms: a white round cone and a white
// capsule of collinear segments (both convex) in a uniform sky at several
// scales and far from the origin (every pixel is the sky's radiance unless
// a spawned ray hits the curve it left, or a joint's wall inside the
// capsule stops a ray), and a long emissive tube over a Lambertian floor
// (an infinite cylinder's irradiance), found by BSDF sampling alone: curves
// are not in the light list, so their emission counts with MIS weight 1.
#include "geometry/primitives.h"
#include "render/light_list.h"
#include "render/render_helpers.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <string>

namespace wt {
namespace {

/// A straight curve of `segments` segments from a to b, radii linear from ra to rb.
void addStraightCurve(Scene& scene, glm::vec3 a, glm::vec3 b, float ra, float rb, int segments, std::uint32_t material) {
  Curve c;
  c.firstPoint = std::uint32_t(scene.curvePoints.size());
  c.pointCount = std::uint32_t(segments + 1);
  c.material = material;
  for (int i = 0; i <= segments; ++i) {
    const float f = float(i) / float(segments);
    const glm::vec3 p = a + f * (b - a);
    scene.curvePoints.push_back({p.x, p.y, p.z, ra + f * (rb - ra)});
  }
  scene.curves.push_back(c);
}

struct FurnaceCase {
  float scale;          ///< the curve's size (radius at its thick end)
  float offset;         ///< distance of the curve and camera from the origin
  int segments;         ///< collinear segments (1: a round cone)
  bool minimal = false; ///< the brute-force integrator
  bool packets = true;  ///< camera and their shadow rays in packets
};

class WhiteCurveInUniformSky : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(WhiteCurveInUniformSky, EveryPixelIsTheSky) {
  const FurnaceCase c = GetParam();
  const glm::vec3 center(c.offset, 0.5f * c.offset, -0.25f * c.offset);
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(1.0f)));
  scene.materialNames.push_back("white");
  // a round cone across the view, tilted towards the camera: one segment, or
  // collinear segments whose hulls make the same cone (convex either way)
  const glm::vec3 half = c.scale * glm::vec3(1.6f, 0.5f, 0.8f);
  addStraightCurve(scene, center - half, center + half, c.scale * 0.5f, c.scale * 0.175f, c.segments, 0);
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), center + glm::vec3(0.0f, 0.0f, 4.0f * c.scale));
  scene.camera = camera;

  RenderSettings settings;
  settings.width = settings.height = 24;
  // one bounce: a ray that hits the curve it leaves is cut short there and
  // loses the sky behind it, which shows as a darker pixel
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.integrator = c.minimal ? Integrator::Minimal : Integrator::Path;
  settings.seed = 3;
  settings.packets = c.packets;
  const Image image = test::render(scene, settings, 64);
  // a convex white Lambertian surface returns the uniform sky exactly
  test::expectUniform(image, glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0, "white curve in a uniform sky");
}

INSTANTIATE_TEST_SUITE_P(Scales, WhiteCurveInUniformSky,
                         ::testing::Values(FurnaceCase{1.0f, 0.0f, 1}, FurnaceCase{1.0f, 0.0f, 24},
                                           FurnaceCase{1e-4f, 0.0f, 1}, FurnaceCase{1e-4f, 0.0f, 24},
                                           FurnaceCase{1e4f, 0.0f, 24}, FurnaceCase{1.0f, 1e6f, 1},
                                           FurnaceCase{1e-2f, 1e3f, 1}, FurnaceCase{1.0f, 0.0f, 24, true},
                                           FurnaceCase{1.0f, 0.0f, 24, false, false}),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                           const FurnaceCase& c = info.param;
                           auto exp10 = [](float v) { return v == 0.0f ? std::string("0") : "1e" + std::to_string(int(std::lround(std::log10(v)))); };
                           std::string name = "size" + exp10(c.scale) + "_at" + exp10(c.offset) + "_" +
                                              std::to_string(c.segments) + "segments" + (c.minimal ? "_minimal" : "_path") +
                                              (c.packets ? "" : "_single");
                           for (char& ch : name)
                             if (ch == '-') ch = 'm';
                           return name;
                         });

struct LightCase {
  Integrator integrator;
  bool nee;
  bool mis;
  int spp;
  const char* name;
};

class CurveLightOverFloor : public ::testing::TestWithParam<LightCase> {};

// A floor of albedo rho at y = 0 under a black tube of radius r and
// radiance L along the z axis at height h, 2000 long (as good as infinite
// here): at floor point (x, z) the tube subtends, across its axis, the
// angles beta -+ alpha from the normal (tan beta = x / h, sin alpha = r / D,
// D^2 = x^2 + h^2), so the irradiance is pi L (sin(beta + alpha) -
// sin(beta - alpha)) / 2 = pi L r h / D^2 and the floor's radiance is
// rho L r h / D^2. An orthographic camera between them looks straight down.
TEST_P(CurveLightOverFloor, MatchesTheClosedForm) {
  const LightCase c = GetParam();
  const float rho = 0.5f, r = 0.5f, h = 2.0f;
  const glm::vec3 le(4.0f, 2.0f, 1.0f);
  Scene scene = test::makeFloor(6.0f, 0.0f, makeMaterial(glm::vec3(rho)));
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), le));
  scene.materialNames.push_back("light");
  // 400 segments: the joints along the tube are seams the light must cross
  addStraightCurve(scene, glm::vec3(0.0f, h, -1000.0f), glm::vec3(0.0f, h, 1000.0f), r, r, 400, 1);
  const float ymag = 2.0f;
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 1.0f, 0.0f), ymag);

  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 1;
  settings.integrator = c.integrator;
  settings.useNee = c.nee;
  settings.useMis = c.mis;
  settings.seed = 11;
  const Image image = test::render(scene, settings, c.spp);

  // the closed form averaged over each pixel's footprint (the camera jitters
  // uniformly within it): world x = s_x ymag
  auto radiance = [&](double x) { return rho * double(r) * h / (x * x + double(h) * h); };
  constexpr int kSub = 16;
  int bad = 0;
  const int block = 4;
  for (int by = 0; by < settings.height / block; ++by)
    for (int bx = 0; bx < settings.width / block; ++bx) {
      double expected = 0.0;
      for (int px = bx * block; px < (bx + 1) * block; ++px)
        for (int j = 0; j < kSub; ++j) {
          const double sx = 2.0 * (px + (j + 0.5) / kSub) / settings.width - 1.0;
          expected += radiance(sx * ymag);
        }
      expected /= double(block * kSub);
      for (int ch = 0; ch < 3; ++ch) {
        const test::BlockStat s = test::blockStat(image, bx * block, by * block, (bx + 1) * block, (by + 1) * block, ch);
        const double want = expected * le[ch];
        // 5 standard errors, and 1e-4 of the value for the quadrature and the tube's ends
        const double tol = 5.0 * std::sqrt(s.varianceOfMean) + 1e-4 * want;
        if (std::abs(s.mean - want) > tol && ++bad <= 5)
          ADD_FAILURE() << c.name << ": block (" << bx << ", " << by << ") channel " << ch << ": " << s.mean << " vs "
                        << want << " (tolerance " << tol << ")";
      }
    }
  EXPECT_EQ(bad, 0);
}

INSTANTIATE_TEST_SUITE_P(Integrators, CurveLightOverFloor,
                         ::testing::Values(LightCase{Integrator::Path, true, true, 256, "path"},
                                           LightCase{Integrator::Path, true, false, 256, "path_no_mis"},
                                           LightCase{Integrator::Path, false, false, 256, "path_no_nee"},
                                           LightCase{Integrator::Minimal, false, false, 256, "minimal"}),
                         [](const ::testing::TestParamInfo<LightCase>& info) { return std::string(info.param.name); });

TEST(CurveLight, IsNotInTheLightListAndIsSeenDirectly) {
  // an emissive curve beside an emissive sphere: only the sphere is a light,
  // the curve's emitter slots hold 0; camera rays see the curve's radiance
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(3.0f, 2.0f, 1.0f)));
  scene.materialNames.push_back("light");
  addStraightCurve(scene, glm::vec3(-4.0f, 0.0f, 0.0f), glm::vec3(4.0f, 0.0f, 0.0f), 1.0f, 1.0f, 8, 0);
  scene.spheres.push_back({glm::vec3(0.0f, 5.0f, 0.0f), 0.5f, 0});
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 2.0f));
  camera.yfov = 0.2f;  // the whole frame on the curve
  scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = 8;
  settings.maxBounces = 2;
  Renderer renderer(test::deviceContext(), scene, settings);
  const SceneBuffers& buffers = renderer.sceneBuffers();
  const LightList lights = buildLightList(scene, buffers, 0.0);
  ASSERT_EQ(lights.lights.size(), 1u);
  EXPECT_EQ(lights.lights[0].type, WT_LIGHT_PRIMITIVE);
  EXPECT_EQ(lights.lights[0].triangle, primId(WT_PRIM_SPHERE, 0));
  const std::uint32_t first = buffers.geometry.emitter_first[WT_PRIM_CURVE];
  ASSERT_GE(lights.emitterPdfArea.size(), first + buffers.primitiveCount(WT_PRIM_CURVE));
  for (std::size_t i = 0; i < buffers.primitiveCount(WT_PRIM_CURVE); ++i) EXPECT_EQ(lights.emitterPdfArea[first + i], 0.0f);
  for (int s = 0; s < 4; ++s) renderer.renderSample();
  test::expectUniform(renderer.readImage(), glm::dvec3(3.0, 2.0, 1.0), 1e-5, 5.0, "emissive curve seen directly");
}

}  // namespace
}  // namespace wt
