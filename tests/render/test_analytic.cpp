// The integrator against closed forms. The camera sits inside a closed
// diffuse sphere of albedo a that emits radiance Le; every path hits the
// sphere at every bounce, so with B bounces each pixel converges to
// Le * (1 - a^(B+1)) / (1 - a).
#include "device_fixture.h"
#include "render/renderer.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <cmath>

namespace wt {
namespace {

struct FurnaceCase {
  float albedo;
  float emission;
  int maxBounces;
};

class EmissiveSphere : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(EmissiveSphere, ConvergesToGeometricSeries) {
  const FurnaceCase c = GetParam();
  Scene scene = makeIcosphere(3, glm::vec3(0.0f), 1.0f,
                              makeMaterial(glm::vec3(c.albedo), glm::vec3(c.emission), /*twoSided=*/true));
  // Flat normals: with cosine sampling about the geometric normal the
  // estimator weight is exactly the albedo, so no direction is absorbed.
  for (WtVec4& n : scene.normals) n = {0, 0, 0, 0};
  CameraDesc camera;
  camera.cameraToWorld = glm::mat4(1.0f);
  scene.camera = camera;

  RenderSettings settings;
  settings.width = 24;
  settings.height = 16;
  settings.maxBounces = c.maxBounces;
  settings.seed = 7;
  const int spp = 32;
  Renderer renderer(test::deviceContext(), scene, settings);
  for (int s = 0; s < spp; ++s) renderer.renderSample();
  Image image = renderer.readImage();

  const double expected =
      c.emission * (1.0 - std::pow(double(c.albedo), c.maxBounces + 1)) / (1.0 - c.albedo);
  // Tolerance from the data: 5 standard errors of each pixel's mean (from its
  // own sample variance), plus float rounding of the sums (a few ulp per term).
  const double rounding = 8.0 * (c.maxBounces + 2) * 1.2e-7 * expected;
  double sum = 0.0, sumVar = 0.0;
  int bad = 0;
  for (std::size_t p = 0; p < image.samples.size(); ++p) {
    ASSERT_EQ(image.samples[p], std::uint32_t(spp));
    for (int ch = 0; ch < 3; ++ch) {
      double mean = image.rgb[3 * p + ch];
      double var = image.rgbVariance[3 * p + ch];
      double tol = 5.0 * std::sqrt(var / spp) + rounding;
      if (std::abs(mean - expected) > tol && ++bad <= 5)
        ADD_FAILURE() << "pixel " << p << " channel " << ch << ": " << mean << " vs " << expected
                      << " (tolerance " << tol << ")";
      sum += mean;
      sumVar += var;
    }
  }
  EXPECT_EQ(bad, 0);
  const double n = 3.0 * image.samples.size();
  const double imageMean = sum / n;
  const double imageTol = 5.0 * std::sqrt(sumVar / n / (spp * n)) + rounding;
  EXPECT_NEAR(imageMean, expected, imageTol);
  EXPECT_EQ(renderer.stats().nonFiniteSamples, 0u);
}

INSTANTIATE_TEST_SUITE_P(Cases, EmissiveSphere,
                         ::testing::Values(FurnaceCase{0.5f, 1.0f, 0}, FurnaceCase{0.5f, 1.0f, 3},
                                           FurnaceCase{0.8f, 2.0f, 8}, FurnaceCase{0.0f, 1.0f, 4},
                                           FurnaceCase{0.95f, 0.5f, 20}),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                           const FurnaceCase& c = info.param;
                           return "albedo" + std::to_string(int(c.albedo * 100)) + "_emission" +
                                  std::to_string(int(c.emission * 10)) + "_bounces" +
                                  std::to_string(c.maxBounces);
                         });

}  // namespace
}  // namespace wt
