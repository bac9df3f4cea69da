// The default scene through the whole pipeline at low resolution.
#include "device_fixture.h"
#include "render/renderer.h"
#include "render/render_helpers.h"
#include "scene/default_scene.h"

#include <glm/gtc/matrix_transform.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <string>

namespace wt {
namespace {

Image renderCornell(std::uint32_t seed, int spp = 4, bool packets = true, int packetWidth = 0,
                    std::optional<Traversal> shadows = std::nullopt,
                    std::optional<Traversal> extend = std::nullopt) {
  Scene scene = loadDefaultScene();
  RenderSettings settings;
  settings.width = 48;
  settings.height = 48;
  settings.maxBounces = 4;
  settings.seed = seed;
  settings.packets = packets;
  settings.packetWidth = packetWidth;
  settings.shadowTraversal = shadows;
  settings.extendTraversal = extend;
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

/// A floor whose albedo is NaN in red (the loader would refuse it), filling
/// the lower half of a 16x16 view under a grey sky: every path that bounces
/// off it turns NaN.
Scene nanFloor(RenderSettings* s) {
  Scene scene = test::makeFloor(50.0f, 0.0f, makeMaterial(glm::vec3(std::nanf(""), 0.5f, 0.5f)));
  CameraDesc cam;
  cam.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  scene.camera = cam;
  s->width = 16, s->height = 16, s->maxBounces = 2;
  s->background = glm::vec3(0.25f);
  return scene;
}

TEST(EndToEnd, NonFiniteSamplesAreCountedNotAccumulated) {
  RenderSettings s;
  Scene scene = nanFloor(&s);
  s.stopOnNonFinite = false;  // counting is what is tested (debug builds stop by default)
  const int spp = 4;
  Renderer renderer(test::deviceContext(), scene, s);
  for (int i = 0; i < spp; ++i) renderer.renderSample();
  Image img = renderer.readImage();
  std::size_t lost = 0, kept = 0, discarded = 0;
  for (std::size_t p = 0; p < img.samples.size(); ++p) {
    for (int c = 0; c < 3; ++c) ASSERT_TRUE(std::isfinite(img.rgb[3 * p + c])) << "pixel " << p;
    discarded += std::uint32_t(spp) - img.samples[p];
    lost += img.samples[p] == 0;
    kept += img.samples[p] == std::uint32_t(spp);
  }
  // the sky half keeps every sample, the floor half loses every one (pixels
  // on the horizon some of each); every discarded sample is counted
  EXPECT_GT(lost, img.samples.size() / 4);
  EXPECT_GT(kept, img.samples.size() / 4);
  EXPECT_EQ(renderer.stats().nonFiniteSamples, discarded);
}

TEST(EndToEnd, StopOnNonFiniteNamesThePixelSampleAndBounce) {
  // the NaN floor again: the first NaN is made at the camera ray's hit
  // (bounce 0) of sample 0, in the bottom half
  RenderSettings s;
  Scene scene = nanFloor(&s);
  s.stopOnNonFinite = true;
  Renderer renderer(test::deviceContext(), scene, s);
  try {
    renderer.renderSample();
    FAIL() << "expected a NonFiniteSampleError";
  } catch (const NonFiniteSampleError& e) {
    EXPECT_EQ(e.sample, 0);
    EXPECT_EQ(e.bounce, 0);
    EXPECT_GE(e.y, 8) << e.what();
    EXPECT_NE(std::string(e.what()).find("sample 0, bounce 0"), std::string::npos) << e.what();
  }
  // without the switch the same render counts and discards instead
  s.stopOnNonFinite = false;
  Renderer counting(test::deviceContext(), scene, s);
  counting.renderSample();
  counting.readImage();
  EXPECT_GT(counting.stats().nonFiniteSamples, 0u);
}

// A PNG-only render reads the 8-bit pixels alone: the same pixels and counts
// as the full read, without the float channels.
TEST(EndToEnd, DisplayImageIsTheFullReadsPixels) {
  Scene scene = loadDefaultScene();
  RenderSettings settings;
  settings.width = 40;
  settings.height = 24;
  settings.maxBounces = 3;
  Renderer renderer(test::deviceContext(), scene, settings);
  for (int s = 0; s < 2; ++s) renderer.renderSample();
  const Image display = renderer.readDisplayImage();
  const Image full = renderer.readImage();
  EXPECT_EQ(display.width, 40);
  EXPECT_EQ(display.height, 24);
  ASSERT_EQ(display.srgba.size(), std::size_t(40 * 24 * 4));
  EXPECT_TRUE(display.srgba == full.srgba) << "the tone-mapped pixels differ";
  EXPECT_TRUE(display.samples == full.samples);
  EXPECT_EQ(display.samplesDone, 2);
  EXPECT_TRUE(display.rgb.empty() && display.rgbVariance.empty());
  EXPECT_NE(std::count(full.srgba.begin(), full.srgba.end(), std::uint8_t(0)), std::ptrdiff_t(full.srgba.size()))
      << "a black image would pass anything";
}

TEST(EndToEnd, DeterministicForASeed) {
  Image a = renderCornell(3), b = renderCornell(3), c = renderCornell(4);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.srgba, b.srgba);
  EXPECT_NE(a.rgb, c.rgb);
}

TEST(EndToEnd, ShadowTraversalIsChosenFromTheRaysInTheFirstSample) {
  // at 256x256 the shadow rays of neighbouring camera hits to the Cornell
  // box's one small light point nearly one way: packets, whatever order
  // the device's threads appended them in (the probe reads them in path
  // order); after a diffuse bounce they point every way, streams on a CPU
  // (else single rays)
  Scene scene = loadDefaultScene();
  RenderSettings settings;
  settings.width = settings.height = 256;
  settings.maxBounces = 4;
  Renderer renderer(test::deviceContext(), scene, settings);
  EXPECT_FALSE(renderer.shadowTraversal(0).has_value());
  renderer.renderSample();
  EXPECT_EQ(renderer.shadowTraversal(0), Traversal::kPacket);
  const Traversal incoherent = test::deviceContext().info().isCpu ? Traversal::kStream : Traversal::kSingle;
  EXPECT_EQ(renderer.shadowTraversal(1), incoherent);
  EXPECT_EQ(renderer.shadowTraversal(2), incoherent);
  EXPECT_FALSE(renderer.shadowTraversal(5).has_value());
  // --traversal single: nothing chosen
  settings.packets = false;
  Renderer single(test::deviceContext(), scene, settings);
  single.renderSample();
  EXPECT_FALSE(single.shadowTraversal(0).has_value());
}

TEST(EndToEnd, ShadowProbeSeesTheSamePathsWhateverTheAppendOrder) {
  // the dense shadow queue's order is the device threads' interleaving: the
  // probe's sample must not depend on it
  std::vector<std::uint32_t> queue;
  for (std::uint32_t i = 0; i < 5000; ++i)
    if (i % 3 != 1) queue.push_back(i * 7);
  const std::vector<std::uint32_t> inOrder = shadowProbeEntries(queue, 1000);
  ASSERT_EQ(inOrder.size(), 1000u);
  EXPECT_TRUE(std::is_sorted(inOrder.begin(), inOrder.end()));
  EXPECT_EQ(inOrder.front(), 0u);
  EXPECT_EQ(inOrder.back(), 1499u * 7u);  // the 1000th path index not skipped
  std::mt19937 rng(7);
  for (int shuffle = 0; shuffle < 4; ++shuffle) {
    std::shuffle(queue.begin(), queue.end(), rng);
    EXPECT_EQ(shadowProbeEntries(queue, 1000), inOrder);
  }
  EXPECT_EQ(shadowProbeEntries({9, 3, 5}, 1000), (std::vector<std::uint32_t>{3, 5, 9}));
}

TEST(EndToEnd, PacketsGiveTheSameImageAsSingleRays) {
  // Camera rays and their shadow rays in packets (extend_packet,
  // connect_packet), and the later bounces' shadow rays in streams
  // (connect_stream, ShadowTraversalIsChosenFromTheRaysInTheFirstSample),
  // find the same hits as one ray per work-item. Only a camera ray through a
  // shared edge at exactly the same distance on both triangles may take the
  // other one, changing that one pixel.
  // Both packet widths, whatever this device would pick.
  // Every bounce's shadow rays forced into packets, into streams, and as chosen.
  Image single = renderCornell(5, 4, false);
  for (int width : {8, 16})
    for (std::optional<Traversal> shadows : {std::optional<Traversal>(Traversal::kPacket),
                                             std::optional<Traversal>(Traversal::kStream), std::optional<Traversal>()}) {
      const std::string how = std::string(!shadows ? "chosen" : *shadows == Traversal::kPacket ? "packet" : "stream") +
                              "_" + std::to_string(width);
      Image packets = renderCornell(5, 4, true, width, shadows);
      ASSERT_EQ(packets.rgb.size(), single.rgb.size());
      int differ = 0;
      for (std::size_t i = 0; i < packets.rgb.size(); i += 3)
        differ += packets.rgb[i] != single.rgb[i] || packets.rgb[i + 1] != single.rgb[i + 1] ||
                  packets.rgb[i + 2] != single.rgb[i + 2];
      RecordProperty("pixels_differing_" + how, differ);
      EXPECT_LE(differ, 2) << differ << " of " << packets.rgb.size() / 3 << " pixels differ, shadow rays " << how;
    }
}

TEST(EndToEnd, ExtendTraversalAfterTheFirstBounceLeavesTheImage) {
  // Later bounces' closest hits in packets (each lane its own axis
  // permutation) and one ray per work-item, forced each way and as the timed
  // trials pick (samples 1-6 alternate, the choice is kept from sample 7):
  // the same image bit for bit, at both packet widths. The shadow rays are
  // traced one way throughout, so extend is all that differs.
  const int spp = 8;
  const auto single = std::optional<Traversal>(Traversal::kSingle);
  for (int width : {8, 16}) {
    Image reference = renderCornell(7, spp, true, width, single, single);
    for (std::optional<Traversal> extend : {std::optional<Traversal>(Traversal::kPacket), std::optional<Traversal>()}) {
      SCOPED_TRACE(std::string(extend ? "packets" : "timed") + " at width " + std::to_string(width));
      Image image = renderCornell(7, spp, true, width, single, extend);
      ASSERT_EQ(image.rgb.size(), reference.rgb.size());
      EXPECT_TRUE(image.rgb == reference.rgb) << "the images differ";
    }
  }
  // the trials (samples 1-6) decide every bounce that reached them, and only after them
  Scene scene = loadDefaultScene();
  RenderSettings settings;
  settings.width = settings.height = 48;
  settings.maxBounces = 4;
  Renderer renderer(test::deviceContext(), scene, settings);
  for (int s = 0; s < 6; ++s) {
    renderer.renderSample();
    EXPECT_FALSE(renderer.extendTraversal(1).has_value()) << "after sample " << s;
  }
  renderer.renderSample();
  EXPECT_TRUE(renderer.extendTraversal(1).has_value());
  EXPECT_FALSE(renderer.extendTraversal(0).has_value());
}

}  // namespace
}  // namespace wt
