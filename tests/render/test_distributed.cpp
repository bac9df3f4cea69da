// A render shared over devices (render/distributed.h), on the device: the
// chunked image is the same bit for bit however many renderers take the
// chunks, and equals the one-pass render to the accumulation's precision.
#include "device_fixture.h"
#include "render/distributed.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <thread>
#include <utility>

namespace wt {
namespace {

RenderSettings tinyMergeSettings(std::uint32_t accumulation) {
  RenderSettings s;
  s.width = 16;
  s.height = 12;
  s.maxBounces = 4;
  s.seed = 5;
  s.accumulation = accumulation;
  return s;
}

/// Render samples [0, spp) in chunks on the renderers, one thread each
/// taking chunks as it frees (the order they are taken varies run to run).
Moments renderChunked(std::vector<Renderer*> renderers, int spp, int chunkSpp) {
  const bool aovs = renderers[0]->settings().aovs;
  const std::size_t pixels = std::size_t(renderers[0]->settings().width) * renderers[0]->settings().height;
  ChunkPlan plan(0, spp, chunkSpp);
  PlanSource source(plan);
  ResultQueue results;
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  for (Renderer* r : renderers)
    threads.emplace_back([&, r] { runDeviceWorker(*r, source, results, stop, "test device"); });
  for (std::thread& t : threads) t.join();
  OrderedMerge merge(emptyMoments(pixels, 0, aovs));
  while (std::optional<ChunkResult> r = results.pop(0.0)) {
    EXPECT_EQ(r->error, "");
    merge.add(r->chunk.index, std::move(r->moments));
  }
  EXPECT_EQ(merge.waiting(), 0u);
  return merge.merged();
}

bool sameBits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// The host's resolvedImage of the merged moments is what the device's
/// resolve of the restored accumulation gave, bit for bit (all but srgba):
/// what a job's periodic image is written from, without a device.
void expectResolvedOnHost(const Moments& m, const Image& device) {
  const Image host = resolvedImage(m, device.width, device.height);
  EXPECT_EQ(host.samplesDone, device.samplesDone);
  EXPECT_EQ(host.samples, device.samples);
  EXPECT_TRUE(sameBits(host.rgb, device.rgb));
  EXPECT_TRUE(sameBits(host.rgbVariance, device.rgbVariance));
  const Aovs &a = host.aovs, &b = device.aovs;
  for (auto [x, y] : {std::pair{&a.albedo, &b.albedo}, {&a.normal, &b.normal}, {&a.position, &b.position},
                      {&a.uv, &b.uv}, {&a.depth, &b.depth}, {&a.bounces, &b.bounces}, {&a.bvhCost, &b.bvhCost}})
    EXPECT_TRUE(sameBits(*x, *y));
  EXPECT_EQ(a.material, b.material);
  EXPECT_EQ(a.instance, b.instance);
  EXPECT_EQ(a.primitive, b.primitive);
}

// Two renderers (two contexts on the test device) taking chunks as they
// free give the moments one renderer gives alone: the merge order is the
// chunk order, whichever renderer rendered which chunk.
TEST(DistributedRender, TwoDevicesEqualOneBitwise) {
  Context& context = test::deviceContext();
  Context second(context.info());
  const Scene scene = loadDefaultScene();
  const RenderSettings settings = tinyMergeSettings(WT_ACCUMULATE_KAHAN);
  Renderer a(context, scene, settings), b(second, scene, settings);
  const Moments one = renderChunked({&a}, 24, 4);
  const Moments two = renderChunked({&a, &b}, 24, 4);
  EXPECT_EQ(one.sampleEnd, 24);
  EXPECT_EQ(two.count, one.count);
  EXPECT_TRUE(sameBits(two.mean, one.mean));
  EXPECT_TRUE(sameBits(two.m2, one.m2));
}

// Chunked and merged in double vs one pass on the device: in double mode
// both hold the exact moments to about 2^-50 (a few roundings per sample of
// a double), so their float images agree to one float ulp; in kahan mode
// the compensated float sums each stay within a few roundings of the
// exact value per harmonic step, bounded by 8 * 2^-24 * (1 + ln n) of
// |mean| + sqrt(M2) (any sample is within sqrt(M2) of the mean) and of
// the sum of squares M2 + n * mean^2 for M2.
TEST(DistributedRender, ChunkedEqualsOnePassToTheAccumulationPrecision) {
  Context& context = test::deviceContext();
  for (std::uint32_t mode : {WT_ACCUMULATE_DOUBLE, WT_ACCUMULATE_KAHAN}) {
    if (mode == WT_ACCUMULATE_DOUBLE && !context.info().fp64) continue;
    const Scene scene = loadDefaultScene();
    const RenderSettings settings = tinyMergeSettings(mode);
    const int spp = 32;
    Renderer straight(context, scene, settings);
    for (int s = 0; s < spp; ++s) straight.renderSample();
    const Image expected = straight.readImage();

    Renderer chunked(context, scene, settings);
    const Moments m = renderChunked({&chunked}, spp, 5);
    chunked.restoreAccumulation(accumulationFromMoments(m, mode));
    const Image got = chunked.readImage();
    ASSERT_EQ(got.samples, expected.samples);
    EXPECT_EQ(got.samplesDone, spp);
    expectResolvedOnHost(m, got);
    int over = 0;
    const double eps = 0x1p-24, n = spp, harmonic = 1.0 + std::log(n);
    for (std::size_t k = 0; k < got.rgb.size(); ++k) {
      const double mean = expected.rgb[k], m2 = double(expected.rgbVariance[k]) * (n - 1.0);
      const double tolMean = mode == WT_ACCUMULATE_DOUBLE ? 2.0 * eps * std::fabs(mean)
                                                          : 8.0 * eps * harmonic * (std::fabs(mean) + std::sqrt(m2));
      const double tolVar = mode == WT_ACCUMULATE_DOUBLE ? 4.0 * eps * expected.rgbVariance[k]
                                                         : 8.0 * eps * harmonic * (m2 + n * mean * mean) / (n - 1.0);
      const bool bad = std::fabs(got.rgb[k] - mean) > tolMean ||
                       std::fabs(double(got.rgbVariance[k]) - expected.rgbVariance[k]) > tolVar;
      if (bad && over < 5)
        ADD_FAILURE() << "mode " << mode << " value " << k << ": mean " << got.rgb[k] << " vs " << mean << ", variance "
                      << got.rgbVariance[k] << " vs " << expected.rgbVariance[k];
      over += bad;
    }
    EXPECT_EQ(over, 0) << "mode " << mode;
    // the tone-mapped image is read from the merged state like any other
    EXPECT_EQ(got.srgba.size(), expected.srgba.size());
  }
}

// The AOVs of a render shared over two renderers: the per-pixel sums merged
// in double equal the one-pass float sums to float rounding (each of the n
// additions rounds by at most 2^-24 of a sum no larger than n times the
// largest sample), and the ids are those of sample 0 exactly, whichever
// renderer rendered chunk 0 (the other's id buffer never saw sample 0).
TEST(DistributedRender, AovsMergedEqualOnePass) {
  Context& context = test::deviceContext();
  Context second(context.info());
  const Scene scene = loadDefaultScene();
  RenderSettings settings = tinyMergeSettings(WT_ACCUMULATE_KAHAN);
  settings.aovs = true;
  const int spp = 24;
  Renderer straight(context, scene, settings);
  for (int s = 0; s < spp; ++s) straight.renderSample();
  const Image expected = straight.readImage();
  Renderer a(context, scene, settings), b(second, scene, settings);
  const Moments m = renderChunked({&a, &b}, spp, 3);
  ASSERT_TRUE(m.hasAovs());
  b.restoreAccumulation(accumulationFromMoments(m, settings.accumulation));
  const Image got = b.readImage();
  expectResolvedOnHost(m, got);
  const Aovs &x = got.aovs, &y = expected.aovs;
  EXPECT_EQ(x.material, y.material);
  EXPECT_EQ(x.instance, y.instance);
  EXPECT_EQ(x.primitive, y.primitive);
  const double tol = 2.0 * spp * 0x1p-24;
  auto near = [&](const std::vector<float>& p, const std::vector<float>& q, const char* name) {
    ASSERT_EQ(p.size(), q.size()) << name;
    float largest = 0.0f;
    for (float v : q)
      if (std::isfinite(v)) largest = std::max(largest, std::fabs(v));
    int bad = 0;
    for (std::size_t k = 0; k < p.size(); ++k) {
      const bool same = (std::isinf(p[k]) && p[k] == q[k]) || std::fabs(double(p[k]) - q[k]) <= tol * 2.0 * largest;
      if (!same && bad++ < 3) ADD_FAILURE() << name << " " << k << ": " << p[k] << " vs " << q[k];
    }
    EXPECT_GT(largest, 0.0f) << name << " is all zero: nothing compared";
  };
  near(x.albedo, y.albedo, "albedo");
  near(x.normal, y.normal, "normal");
  near(x.position, y.position, "position");
  near(x.depth, y.depth, "depth");
  near(x.uv, y.uv, "uv");
  near(x.bounces, y.bounces, "bounces");
}

}  // namespace
}  // namespace wt
