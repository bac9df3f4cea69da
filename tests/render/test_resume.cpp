// Resuming a saved accumulation, and the error estimate --target-error
// stops on, on the device.
#include "device_fixture.h"
#include "render/halting.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <gtest/gtest.h>

#include <cmath>

namespace wt {
namespace {

RenderSettings tinySettings(std::uint32_t seed, std::uint32_t accumulation = WT_ACCUMULATE_KAHAN) {
  RenderSettings s;
  s.width = 16;
  s.height = 12;
  s.maxBounces = 4;
  s.seed = seed;
  s.accumulation = accumulation;
  return s;
}

class Resume : public ::testing::TestWithParam<std::uint32_t> {};

// The accumulation is per pixel in sample order and the random numbers a
// pure function of (pixel, sample, bounce, dimension, seed): a render saved
// after 10 samples and continued by a fresh renderer is the uninterrupted
// render, bit for bit, in every precision.
TEST_P(Resume, SavedAndContinuedEqualsUninterruptedBitwise) {
  const std::uint32_t mode = GetParam();
  Context& context = test::deviceContext();
  if (mode == WT_ACCUMULATE_DOUBLE && !context.info().fp64) GTEST_SKIP() << "the device has no fp64";
  const Scene scene = loadDefaultScene();
  const RenderSettings settings = tinySettings(3, mode);

  Renderer straight(context, scene, settings);
  for (int s = 0; s < 24; ++s) straight.renderSample();
  const Image expected = straight.readImage();

  Accumulation saved;
  {
    Renderer first(context, scene, settings);
    for (int s = 0; s < 10; ++s) first.renderSample();
    saved = first.saveAccumulation();
  }
  EXPECT_EQ(saved.samplesDone, 10);
  Renderer resumed(context, scene, settings);
  resumed.restoreAccumulation(saved);
  for (int s = 0; s < 14; ++s) resumed.renderSample();
  EXPECT_EQ(resumed.stats().samplesDone, 24);
  const Image got = resumed.readImage();
  EXPECT_EQ(got.samples, expected.samples);
  ASSERT_EQ(got.rgb.size(), expected.rgb.size());
  int differing = 0;
  for (std::size_t i = 0; i < got.rgb.size(); ++i)
    differing += got.rgb[i] != expected.rgb[i] || got.rgbVariance[i] != expected.rgbVariance[i];
  EXPECT_EQ(differing, 0) << "of " << got.rgb.size() << " channel values";
}

INSTANTIATE_TEST_SUITE_P(Accumulation, Resume,
                         ::testing::Values(WT_ACCUMULATE_SINGLE, WT_ACCUMULATE_KAHAN, WT_ACCUMULATE_DOUBLE));

// The AOVs' sums and first-sample ids resume exactly as the image does.
TEST(Resume, AovsSavedAndContinuedEqualUninterruptedBitwise) {
  Context& context = test::deviceContext();
  const Scene scene = loadDefaultScene();
  RenderSettings settings = tinySettings(4);
  settings.aovs = true;
  Renderer straight(context, scene, settings);
  for (int s = 0; s < 9; ++s) straight.renderSample();
  const Aovs expected = straight.readImage().aovs;

  Accumulation saved;
  {
    Renderer first(context, scene, settings);
    for (int s = 0; s < 4; ++s) first.renderSample();
    saved = first.saveAccumulation();
  }
  EXPECT_EQ(saved.aovs.size(), std::size_t(16 * 12) * (kAovSumBytes + kAovIdBytes));
  Renderer resumed(context, scene, settings);
  resumed.restoreAccumulation(saved);
  for (int s = 0; s < 5; ++s) resumed.renderSample();
  const Aovs got = resumed.readImage().aovs;
  EXPECT_EQ(got.albedo, expected.albedo);
  EXPECT_EQ(got.normal, expected.normal);
  EXPECT_EQ(got.depth, expected.depth);
  EXPECT_EQ(got.position, expected.position);
  EXPECT_EQ(got.uv, expected.uv);
  EXPECT_EQ(got.bounces, expected.bounces);
  EXPECT_EQ(got.material, expected.material);
  EXPECT_EQ(got.instance, expected.instance);
  EXPECT_EQ(got.primitive, expected.primitive);

  // an accumulation without AOVs does not restore into a render that records them
  Accumulation plain = saved;
  plain.aovs.clear();
  Renderer other(context, scene, settings);
  EXPECT_THROW(other.restoreAccumulation(plain), std::invalid_argument);
}

TEST(ResumeErrors, AnAccumulationOfAnotherSizeIsRefused) {
  const Scene scene = loadDefaultScene();
  Renderer renderer(test::deviceContext(), scene, tinySettings(1));
  Accumulation wrong;
  wrong.state.resize(7 * kAccumulationStateBytes);
  wrong.samples.resize(7);
  EXPECT_THROW(renderer.restoreAccumulation(wrong), std::invalid_argument);
}

// --target-error's estimate against the error measured on an independent
// converged reference: both estimate the same relMSE (the mean over pixels
// and channels of Var(mean) / (mean^2 + 0.01)), so their per-pixel
// difference has mean 0, and its own spread bounds how far the two may be
// apart.
TEST(TargetError, EstimateAtTheStopAgreesWithTheMeasuredError) {
  Context& context = test::deviceContext();
  const Scene scene = loadDefaultScene();
  Renderer referenceRenderer(context, scene, tinySettings(1000));
  for (int s = 0; s < 1024; ++s) referenceRenderer.renderSample();
  const Image reference = referenceRenderer.readImage();

  const double target = 0.08;
  Renderer renderer(context, scene, tinySettings(1));
  Halting halting({4096, 0.0, target}, 0);
  HaltReason reason = HaltReason::None;
  while ((reason = halting.check(renderer.stats().samplesDone, 0.0)) == HaltReason::None) {
    renderer.renderSample();
    const int n = renderer.stats().samplesDone;
    if (halting.wantsErrorEstimate(n)) halting.recordError(n, std::sqrt(estimatedRelMse(renderer.readRadiance())), 0.0, 1.0);
  }
  ASSERT_EQ(reason, HaltReason::TargetError) << "no stop by the target in 4096 samples";
  EXPECT_LT(halting.lastError(), target);
  const Image image = renderer.readRadiance();
  const double estimated = estimatedRelMse(image);
  EXPECT_NEAR(std::sqrt(estimated), halting.lastError(), 1e-12);

  // per pixel: measured squared relative error (less the reference's own
  // noise) minus the estimate, summed over channels
  const std::size_t pixels = image.samples.size();
  double sum = 0.0, sumSq = 0.0;
  for (std::size_t p = 0; p < pixels; ++p) {
    double d = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double x = image.rgb[3 * p + c], r = reference.rgb[3 * p + c];
      const double refNoise = reference.rgbVariance[3 * p + c] / reference.samples[p];
      d += ((x - r) * (x - r) - refNoise) / (r * r + 0.01) -
           image.rgbVariance[3 * p + c] / image.samples[p] / (x * x + 0.01);
    }
    sum += d;
    sumSq += d * d;
  }
  const double mean = sum / pixels;
  const double standardError = std::sqrt((sumSq / pixels - mean * mean) / (pixels - 1));
  const double measured = imageError(image, reference).relMse;
  EXPECT_NEAR(mean * pixels / (3.0 * pixels), measured - estimated, 1e-9);  // the same two quantities
  // 4.5 standard errors: a false alarm about once in 150 000 seeds
  EXPECT_LT(std::abs(mean), 4.5 * standardError)
      << "estimated relMSE " << estimated << ", measured " << measured << " (relative errors " << std::sqrt(estimated)
      << ", " << std::sqrt(std::max(0.0, measured)) << "), after " << renderer.stats().samplesDone << " samples";
  std::printf("target %.3f: stopped after %d samples, estimated relative error %.4f, measured %.4f\n", target,
              renderer.stats().samplesDone, std::sqrt(estimated), std::sqrt(std::max(0.0, measured)));
}

}  // namespace
}  // namespace wt
