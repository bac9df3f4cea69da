// The default scene through the whole pipeline at low resolution.
#include "device_fixture.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace wt {
namespace {

Image renderCornell(std::uint32_t seed, int spp = 4) {
  Scene scene = loadDefaultScene();
  RenderSettings settings;
  settings.width = 48;
  settings.height = 48;
  settings.maxBounces = 4;
  settings.seed = seed;
  Renderer renderer(test::deviceContext(), scene, settings);
  for (int s = 0; s < spp; ++s) renderer.renderSample();
  return renderer.readImage();
}

TEST(EndToEnd, DefaultSceneLoads) {
  Scene scene = loadDefaultScene();
  EXPECT_EQ(scene.triangles.size(), 32u);
  ASSERT_TRUE(scene.camera.has_value());
  EXPECT_EQ(scene.materials.size(), 4u);
}

TEST(EndToEnd, CornellIsFiniteAndLit) {
  Image image = renderCornell(1);
  double sum = 0.0;
  for (float v : image.rgb) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.0f);
    sum += v;
  }
  double mean = sum / image.rgb.size();
  EXPECT_GT(mean, 0.05);  // lit walls, not a black frame
  // the light itself is seen directly: the brightest pixel is near its radiance
  float peak = *std::max_element(image.rgb.begin(), image.rgb.end());
  EXPECT_GT(peak, 10.0f);
  // red wall on the left, green on the right (the Cornell convention)
  auto channelMean = [&](int x0, int x1, int ch) {
    double s = 0;
    int n = 0;
    for (int y = 16; y < 32; ++y)
      for (int x = x0; x < x1; ++x, ++n) s += image.rgb[3 * (y * image.width + x) + ch];
    return s / n;
  };
  EXPECT_GT(channelMean(0, 5, 0), 1.5 * channelMean(0, 5, 1));
  EXPECT_GT(channelMean(43, 48, 1), 1.5 * channelMean(43, 48, 0));
}

TEST(EndToEnd, DeterministicForASeed) {
  Image a = renderCornell(3), b = renderCornell(3), c = renderCornell(4);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.srgba, b.srgba);
  EXPECT_NE(a.rgb, c.rgb);
}

}  // namespace
}  // namespace wt
