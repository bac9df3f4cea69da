// The PNG-only read (Renderer::readDisplayImage: tone mapping reads the
// accumulation state's mean in place, WT_FLAG_MEAN_IN_STATE, no resolve)
// gives the 8-bit pixels and counts the full read gives, bit for bit: every
// accumulation mode, fixed and automatic exposure, a dithered operator.
#include "device_fixture.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <gtest/gtest.h>

namespace wt {
namespace {

void expectDisplayReadMatchesFullRead(RenderSettings s) {
  const Scene scene = loadDefaultScene();
  Renderer renderer(test::deviceContext(), scene, s);
  for (int k = 0; k < s.samplesPerPixel; ++k) renderer.renderSample();
  const Image display = renderer.readDisplayImage();
  const Image full = renderer.readImage();
  ASSERT_EQ(display.srgba.size(), full.srgba.size());
  std::size_t differing = 0, lit = 0;
  for (std::size_t i = 0; i < full.srgba.size(); ++i) {
    differing += display.srgba[i] != full.srgba[i];
    lit += full.srgba[i] != 0 && i % 4 != 3;
  }
  EXPECT_EQ(differing, 0u);
  EXPECT_EQ(display.samples, full.samples);
  EXPECT_TRUE(display.rgb.empty());
  // an image of zeros would pass without showing anything
  EXPECT_GT(lit, full.srgba.size() / 8);
}

TEST(DisplayRead, SamePixelsAsTheFullReadInEveryAccumulationMode) {
  RenderSettings s;
  s.width = 40;
  s.height = 36;
  s.samplesPerPixel = 3;
  s.seed = 5;
  for (std::uint32_t mode : {WT_ACCUMULATE_SINGLE, WT_ACCUMULATE_KAHAN, WT_ACCUMULATE_DOUBLE}) {
    if (mode == WT_ACCUMULATE_DOUBLE && !test::deviceContext().info().fp64) continue;
    SCOPED_TRACE("accumulation mode " + std::to_string(mode));
    s.accumulation = mode;
    s.tonemap.autoExposure = false;
    expectDisplayReadMatchesFullRead(s);
    SCOPED_TRACE("auto exposure");
    s.tonemap.autoExposure = true;
    expectDisplayReadMatchesFullRead(s);
  }
}

}  // namespace
}  // namespace wt
