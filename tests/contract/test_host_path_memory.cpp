// The path state in memory the renderer maps (RenderSettings::hostPathMemory,
// CL_MEM_USE_HOST_PTR on a CPU device) gives the image the device-allocated
// buffers give, bit for bit: the Cornell box with and without AOVs, and the
// example scenes, whose features allocate the optional buffers (instances,
// ray cones, media, thin walls).
#include "device_fixture.h"
#include "core/embedded.h"
#include "render/renderer.h"
#include "scene/default_scene.h"
#include "scene/scene_file.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>

namespace wt {
namespace {

RenderSettings hostMemorySettings() {
  RenderSettings s;
  s.width = 48;
  s.height = 40;
  s.samplesPerPixel = 2;
  s.seed = 11;
  return s;
}

/// Float arrays compared by their bits (NaN == NaN, -0 != +0).
std::size_t hostMemoryDifferingWords(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(float)) != 0;
  return n;
}

void expectHostMemoryChangesNothing(const Scene& scene, RenderSettings settings) {
  Image images[2];
  std::size_t bytes[2] = {0, 0};
  for (bool host : {false, true}) {
    settings.hostPathMemory = host;
    Renderer renderer(test::deviceContext(), scene, settings);
    for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
    images[host] = renderer.readImage();
    bytes[host] = renderer.pathStateBytes();
  }
  EXPECT_EQ(bytes[0], bytes[1]);
  EXPECT_EQ(hostMemoryDifferingWords(images[0].rgb, images[1].rgb), 0u) << "mean";
  EXPECT_EQ(hostMemoryDifferingWords(images[0].rgbVariance, images[1].rgbVariance), 0u) << "variance";
  EXPECT_EQ(images[0].samples, images[1].samples);
  EXPECT_EQ(images[0].srgba, images[1].srgba);
  const Aovs& a = images[0].aovs;
  const Aovs& b = images[1].aovs;
  EXPECT_EQ(hostMemoryDifferingWords(a.albedo, b.albedo), 0u) << "albedo";
  EXPECT_EQ(hostMemoryDifferingWords(a.normal, b.normal), 0u) << "normal";
  EXPECT_EQ(hostMemoryDifferingWords(a.depth, b.depth), 0u) << "depth";
  EXPECT_EQ(a.material, b.material);
  EXPECT_EQ(a.primitive, b.primitive);
  // a black image would pass without showing anything
  double sum = 0.0;
  for (float v : images[1].rgb) sum += v;
  EXPECT_GT(sum, 0.0) << "the test scene renders black";
}

TEST(HostPathMemory, CornellBoxWithAndWithoutAovs) {
  const Scene scene = loadDefaultScene();
  RenderSettings s = hostMemorySettings();
  expectHostMemoryChangesNothing(scene, s);
  s.aovs = true;
  expectHostMemoryChangesNothing(scene, s);
}

TEST(HostPathMemory, ExampleSceneFiles) {
  const std::filesystem::path dir = wt::embedded::sourceDirectory() / "scenes";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().filename().string());
    std::ifstream text(entry.path());
    const std::string contents((std::istreambuf_iterator<char>(text)), std::istreambuf_iterator<char>());
    if (contents.find("shared/assets/") != std::string::npos && !std::filesystem::exists(WT_ASSETS_DIR)) {
      std::cout << "SKIPPED: " << entry.path().filename().string() << " reads ../shared/assets, absent\n";
      continue;
    }
    ++files;
    SceneFile file = loadSceneFile(entry.path().string());
    // the level changes nothing here; level 6's boxes take seconds to build
    for (DisplacedMesh& m : file.scene.displacedMeshes) m.level = m.level < 0 ? 3 : std::min(m.level, 3);
    RenderSettings s = hostMemorySettings();
    if (file.settings.environment && file.settings.environment->color) s.background = *file.settings.environment->color;
    if (file.settings.integrator == "minimal") s.integrator = Integrator::Minimal;
    if (file.settings.maxBounces) s.maxBounces = *file.settings.maxBounces;
    // hit_instance allocated (one scene: each instancing build is a program of its own)
    if (entry.path().stem() == "instances") s.instancing = Instancing::On;
    expectHostMemoryChangesNothing(file.scene, s);
  }
  EXPECT_GE(files, 4) << "scenes/*.json not found in " << dir;
}

}  // namespace
}  // namespace wt
