// SDF grids rendered: a white SDF sphere in a uniform sky at several scales
// and far from the origin (every pixel is the sky's radiance unless a
// spawned ray finds the surface it left), and an SDF sphere against the
// analytic sphere of the same radius, the same image within noise once the
// grid's discretisation error is bounded.
#include "geometry/primitives.h"
#include "render/render_helpers.h"
#include "scene/sdf_volume.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <random>
#include <string>

namespace wt {
namespace {

/// A sphere of radius 0.8 in [-1, 1]^3 at `resolution` cells, scaled by
/// `radius` / 0.8 and moved to `center`: an SDF sphere of radius `radius`.
SdfGrid sdfSphere(std::uint32_t resolution, glm::dvec3 center, double radius, std::uint32_t material) {
  SdfShapeParams params;
  params.radius = 0.8;
  SdfVolume v = makeSdfShape(SdfShape::kSphere, params, resolution);
  SdfGrid g;
  g.cells = v.cells;
  g.values = std::move(v.values);
  g.latticeToScene = glm::scale(glm::translate(glm::dmat4(1.0), center), glm::dvec3(radius / 0.8)) * v.latticeToObject();
  g.material = material;
  return g;
}

struct FurnaceCase {
  float scale;   ///< sphere radius
  float offset;  ///< distance of the sphere and camera from the origin
};

class WhiteSdfSphereInUniformSky : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(WhiteSdfSphereInUniformSky, EveryPixelIsTheSky) {
  const FurnaceCase c = GetParam();
  const glm::vec3 center(c.offset, 0.5f * c.offset, -0.25f * c.offset);
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(1.0f)));
  scene.materialNames.push_back("white");
  scene.sdfGrids.push_back(sdfSphere(32, glm::dvec3(center), c.scale, 0));
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), center + glm::vec3(0.0f, 0.0f, 3.2f * c.scale));
  scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = 24;
  // one bounce: a ray that meets the surface it leaves loses the sky behind it
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.seed = 3;
  const Image image = test::render(scene, settings, 64);
  // a white Lambertian surface that nothing else occludes returns the uniform sky
  test::expectUniform(image, glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0, "white SDF sphere in a uniform sky");
}

INSTANTIATE_TEST_SUITE_P(Scales, WhiteSdfSphereInUniformSky,
                         ::testing::Values(FurnaceCase{1.0f, 0.0f}, FurnaceCase{1e-4f, 0.0f}, FurnaceCase{1e4f, 0.0f},
                                           FurnaceCase{1.0f, 1e6f}),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                           const FurnaceCase& c = info.param;
                           auto exp10 = [](float v) {
                             return v == 0.0f ? std::string("0") : "1e" + std::to_string(int(std::lround(std::log10(v))));
                           };
                           std::string name = "radius" + exp10(c.scale) + "_at" + exp10(c.offset);
                           for (char& ch : name)
                             if (ch == '-') ch = 'm';
                           return name;
                         });

/// The grid's interpolant (double) at lattice point p.
double interpolate(const SdfGrid& g, glm::dvec3 p) {
  const glm::dvec3 cell = glm::clamp(glm::floor(p), glm::dvec3(0.0), glm::dvec3(g.cells) - 1.0);
  const glm::dvec3 q = p - cell;
  const std::size_t sx = g.cells.x + 1, sxy = sx * (g.cells.y + 1);
  const std::size_t i = std::size_t(cell.x) + std::size_t(cell.y) * sx + std::size_t(cell.z) * sxy;
  double v = 0.0;
  for (int k = 0; k < 8; ++k) {
    const int x = k & 1, y = (k >> 1) & 1, z = k >> 2;
    v += g.values[i + x + y * sx + z * sxy] * (x ? q.x : 1 - q.x) * (y ? q.y : 1 - q.y) * (z ? q.z : 1 - q.z);
  }
  return v;
}

TEST(SdfVersusAnalyticSphere, SameImageWithinNoiseAndDiscretisation) {
  // a metallic-roughness sphere of radius 1 on a floor under a sphere light,
  // once analytic and once as a 64^3 SDF grid
  const WtMaterial ball = makePbrMaterial(glm::vec3(0.8f, 0.5f, 0.3f), 0.0f, 0.4f);
  const SdfGrid grid = sdfSphere(64, glm::dvec3(0.0), 1.0, 1);
  // the stated discretisation error: the grid's surface lies within 1e-3 of
  // the radius (the trilinear interpolant of |p| - r strays by about
  // h^2 / 8r, h = 2.5 / 64), checked along 4000 random radii
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss;
  const glm::dmat4 toLattice = glm::inverse(grid.latticeToScene);
  double worst = 0.0;
  for (int i = 0; i < 4000; ++i) {
    const glm::dvec3 dir = glm::normalize(glm::dvec3(gauss(rng), gauss(rng), gauss(rng)));
    double lo = 0.5, hi = 1.2;  // inside at 0.5, outside at 1.2
    for (int k = 0; k < 60; ++k) {
      const double m = 0.5 * (lo + hi);
      (interpolate(grid, glm::dvec3(toLattice * glm::dvec4(m * dir, 1.0))) < 0.0 ? lo : hi) = m;
    }
    worst = std::max(worst, std::abs(0.5 * (lo + hi) - 1.0));
  }
  EXPECT_LT(worst, 1e-3) << "the SDF sphere's surface strays from the radius";
  auto withBall = [&](bool analytic) {
    return test::ballOnFloor([&](Scene& s) {
      s.materials.push_back(ball);
      s.materialNames.push_back("ball");
      if (analytic) s.spheres.push_back({glm::vec3(0.0f), 1.0f, 1});
      else s.sdfGrids.push_back(grid);
    });
  };
  // a shift of 1e-3 of the radius moves the silhouette by 0.01 pixel here: below the noise
  test::expectSameBallImage(withBall(true), withBall(false), "analytic sphere against an SDF grid of it");
}

}  // namespace
}  // namespace wt
