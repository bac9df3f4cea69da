// Stage skipping (RenderSettings::skipUnusedStages) leaves every image
// unchanged, bit for bit: the example scenes, the integrator switches that
// remove the connect stage, an environment map and a shared glTF asset with
// alpha, each rendered with every stage and buffer, and with the unused ones
// left out.
#include "device_fixture.h"
#include "core/embedded.h"
#include "render/renderer.h"
#include "scene/default_scene.h"
#include "scene/scene_file.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <utility>

namespace wt {
namespace {

RenderSettings smallSettings() {
  RenderSettings s;
  s.width = 48;
  s.height = 40;
  s.samplesPerPixel = 2;
  s.seed = 7;
  return s;
}

/// The image with and without skipping, which must be the same bits.
void expectSkippingChangesNothing(const Scene& scene, RenderSettings settings) {
  Image images[2];
  for (bool skip : {false, true}) {
    settings.skipUnusedStages = skip;
    Renderer renderer(test::deviceContext(), scene, settings);
    for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
    images[skip] = renderer.readImage();
  }
  ASSERT_EQ(images[0].rgb.size(), images[1].rgb.size());
  std::size_t differing = 0, first = images[0].rgb.size();
  for (std::size_t i = 0; i < images[0].rgb.size(); ++i) {
    if (std::memcmp(&images[0].rgb[i], &images[1].rgb[i], sizeof(float)) != 0) {
      ++differing;
      first = std::min(first, i);
    }
  }
  EXPECT_EQ(differing, 0u) << "first at pixel " << first / 3 << " channel " << first % 3 << ": "
                           << images[0].rgb[first] << " with every stage, " << images[1].rgb[first]
                           << " with skipping";
  EXPECT_EQ(images[0].samples, images[1].samples);
  EXPECT_EQ(images[0].rgbVariance, images[1].rgbVariance);
  // a black image would pass without showing anything
  double sum = 0.0;
  for (float v : images[1].rgb) sum += v;
  EXPECT_GT(sum, 0.0) << "the test scene renders black";
}

TEST(StageSkipping, CornellBoxWithEveryIntegratorSwitch) {
  const Scene scene = loadDefaultScene();
  RenderSettings s = smallSettings();
  {
    SCOPED_TRACE("path, NEE: connect runs but for the last bounce");
    expectSkippingChangesNothing(scene, s);
  }
  {
    SCOPED_TRACE("path without NEE: no connect stage, no shadow buffers");
    RenderSettings n = s;
    n.useNee = false;
    expectSkippingChangesNothing(scene, n);
  }
  {
    SCOPED_TRACE("minimal without analytic lights: no connect stage");
    RenderSettings m = s;
    m.integrator = Integrator::Minimal;
    expectSkippingChangesNothing(scene, m);
  }
  {
    SCOPED_TRACE("camera rays traced one by one (no packets)");
    RenderSettings p = s;
    p.packets = false;
    expectSkippingChangesNothing(scene, p);
  }
}

/// Launches of `stage` while rendering `settings`' samples of `scene`, and
/// the bytes of its per-pixel buffers.
std::pair<std::size_t, std::size_t> launchesAndBytes(const Scene& scene, const RenderSettings& settings,
                                                     const std::string& stage) {
  Context& ctx = test::deviceContext();
  ctx.finish();
  ctx.resetStageTimes();
  Renderer renderer(ctx, scene, settings);
  for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
  ctx.finish();
  const auto& launches = ctx.stageTimes().launches;
  return {launches.count(stage) ? launches.at(stage) : 0u, renderer.pathStateBytes()};
}

TEST(StageSkipping, NoConnectStageOrShadowBuffersWithoutLightSampling) {
  const Scene scene = loadDefaultScene();
  RenderSettings s = smallSettings();
  s.packets = false;  // every bounce's shadow rays through `connect`
  s.maxBounces = 3;
  const auto [withNee, bytesWithNee] = launchesAndBytes(scene, s, "connect");
  // one launch per bounce that can make shadow rays: all but the last
  EXPECT_EQ(withNee, std::size_t(s.samplesPerPixel * s.maxBounces));
  s.useNee = false;
  const auto [withoutNee, bytesWithoutNee] = launchesAndBytes(scene, s, "connect");
  EXPECT_EQ(withoutNee, 0u);
  std::size_t shadowBytesPerPixel = 0;
  for (const PathBufferDesc& b : PathState::kBuffers)
    if (b.need == PathNeed::Shadows) shadowBytesPerPixel += b.elementBytes;
  const std::size_t pixels = std::size_t(s.width) * std::size_t(s.height);
  // each shadow buffer shrinks to one element
  EXPECT_EQ(bytesWithNee - bytesWithoutNee, shadowBytesPerPixel * (pixels - 1));
}

TEST(StageSkipping, ExampleSceneFiles) {
  const std::filesystem::path dir = wt::embedded::sourceDirectory() / "scenes";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().filename().string());
    ++files;
    std::ifstream text(entry.path());
    const std::string contents((std::istreambuf_iterator<char>(text)), std::istreambuf_iterator<char>());
    if (contents.find("shared/assets/") != std::string::npos && !std::filesystem::exists(WT_ASSETS_DIR)) {
      std::cout << "SKIPPED: " << entry.path().filename().string() << " reads ../shared/assets, absent\n";
      continue;
    }
    SceneFile file = loadSceneFile(entry.path().string());
    // the level changes nothing skipping touches; level 6's boxes take seconds to build
    for (DisplacedMesh& m : file.scene.displacedMeshes) m.level = m.level < 0 ? 3 : std::min(m.level, 3);
    RenderSettings s = smallSettings();
    if (file.settings.environment && file.settings.environment->color)
      s.background = *file.settings.environment->color;
    if (file.settings.integrator == "minimal") s.integrator = Integrator::Minimal;
    if (file.settings.maxBounces) s.maxBounces = *file.settings.maxBounces;
    expectSkippingChangesNothing(file.scene, s);
  }
  EXPECT_GE(files, 4) << "scenes/*.json not found in " << dir;
}

TEST(StageSkippingAssets, AlphaBlendedGltfUnderAnEnvironmentMap) {
  WT_REQUIRE_ASSET(model, "gltf/AlphaBlendModeTest/glTF/AlphaBlendModeTest.gltf");
  WT_REQUIRE_ASSET(envmap, "envmaps/studio.hdr");
  const Scene scene = loadScene(model.string());
  RenderSettings s = smallSettings();
  s.environmentMap = envmap.string();
  expectSkippingChangesNothing(scene, s);
  s.useNee = false;
  expectSkippingChangesNothing(scene, s);
}

}  // namespace
}  // namespace wt
