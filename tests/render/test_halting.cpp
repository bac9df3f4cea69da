// Halting criteria, the error estimate and the read-back spacing, on the host.
#include "render/halting.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace wt {
namespace {

Image flatImage(int pixels, float mean, float variance, std::uint32_t samples) {
  Image image;
  image.width = pixels;
  image.height = 1;
  image.rgb.assign(3 * pixels, mean);
  image.rgbVariance.assign(3 * pixels, variance);
  image.samples.assign(pixels, samples);
  return image;
}

TEST(Halting, EstimatedRelMseIsTheMeanOfEachPixelsRelativeVarianceOfItsMean) {
  // Var(mean) = 0.5 / 50 = 0.01 against mean^2 + 0.01 = 1.01
  Image image = flatImage(4, 1.0f, 0.5f, 50);
  EXPECT_NEAR(estimatedRelMse(image), 0.01 / 1.01, 1e-9);
  // one pixel four times as noisy: the mean over pixels and channels
  image.rgbVariance[3] = image.rgbVariance[4] = image.rgbVariance[5] = 2.0f;
  EXPECT_NEAR(estimatedRelMse(image), (3 * 0.01 + 0.04) / 4 / 1.01, 1e-9);
  // a pixel without two samples has no variance yet: no estimate
  image.samples[2] = 1;
  EXPECT_EQ(estimatedRelMse(image), std::numeric_limits<double>::infinity());
}

TEST(Halting, SampleCountTimeAndTargetStopWhicheverComesFirst) {
  Halting spp({10, 0.0, 0.0}, 0);
  EXPECT_EQ(spp.check(9, 1e9), HaltReason::None);  // no time budget given
  EXPECT_EQ(spp.check(10, 0.0), HaltReason::Samples);

  Halting time({kUnboundedSamples, 2.0, 0.0}, 0);
  EXPECT_EQ(time.check(100, 1.99), HaltReason::None);
  EXPECT_EQ(time.check(100, 2.0), HaltReason::Time);

  Halting target({1000, 5.0, 0.05}, 0);
  EXPECT_FALSE(target.wantsErrorEstimate(kMinSamplesForErrorEstimate - 1));
  ASSERT_TRUE(target.wantsErrorEstimate(kMinSamplesForErrorEstimate));
  target.recordError(kMinSamplesForErrorEstimate, 0.06, 0.0, 0.01);
  EXPECT_EQ(target.check(kMinSamplesForErrorEstimate, 0.1), HaltReason::None);
  target.recordError(40, 0.049, 0.0, 0.01);
  EXPECT_EQ(target.check(40, 0.1), HaltReason::TargetError);
  // an estimate of an earlier sample count does not stop a later pass
  EXPECT_EQ(target.check(41, 0.1), HaltReason::None);
  EXPECT_EQ(target.check(41, 5.0), HaltReason::Time);
}

TEST(Halting, ReadBacksCostAtMostTheirShareOfRenderTime) {
  // the first read-back (with the kernel's build in it) says nothing of the cost: the next follows
  Halting h({kUnboundedSamples, 0.0, 0.001}, 0);
  h.recordError(20, 0.5, 0.500, 0.050);
  EXPECT_TRUE(h.wantsErrorEstimate(21));
  // a read-back of 10 ms against 50 ms passes: one every 10 ms / (2% of 50 ms) = 10 passes
  h.recordError(21, 0.5, 0.010, 0.050);
  for (int n = 22; n < 31; ++n) EXPECT_FALSE(h.wantsErrorEstimate(n)) << n;
  EXPECT_TRUE(h.wantsErrorEstimate(31));
  // spaced by the cheapest seen: a slow one (another process on the machine) does not stretch it
  h.recordError(31, 0.5, 0.100, 0.050);
  EXPECT_TRUE(h.wantsErrorEstimate(41));
  // a cheap read-back: every pass
  Halting cheap({kUnboundedSamples, 0.0, 0.001}, 0);
  cheap.recordError(20, 0.5, 1e-6, 0.050);
  EXPECT_TRUE(cheap.wantsErrorEstimate(21));
}

TEST(Halting, TheErrorTrendBringsTheNextEstimateForward) {
  // 0.051 at 100 samples against 0.05: 1/sqrt(n) crosses at 100 * 1.0404 = 105 samples,
  // before the 100 passes the read-back's cost would space
  Halting h({kUnboundedSamples, 0.0, 0.05}, 0);
  h.recordError(99, 0.052, 0.010, 0.005);
  h.recordError(100, 0.051, 0.010, 0.005);
  EXPECT_FALSE(h.wantsErrorEstimate(104));
  EXPECT_TRUE(h.wantsErrorEstimate(105));
  // and the ETA follows the same trend: 4.04 passes of 5 ms
  EXPECT_NEAR(h.eta(100, 1.0, 0.005), 4.04 * 0.005, 1e-9);
}

TEST(Halting, EtaIsTheNearestCriterion) {
  Halting h({200, 10.0, 0.0}, 0);
  EXPECT_NEAR(h.eta(100, 1.0, 0.01), 1.0, 1e-9);   // 100 samples of 10 ms before 9 s left
  EXPECT_NEAR(h.eta(100, 9.5, 0.01), 0.5, 1e-9);   // the budget first
  Halting none({kUnboundedSamples, 0.0, 0.05}, 0);
  EXPECT_LT(none.eta(10, 1.0, 0.01), 0.0);         // no error estimated yet, and no sample limit
}

TEST(Halting, ProgressLineNamesSamplesRateTimeErrorAndEta) {
  Halting h({kUnboundedSamples, 0.0, 0.05}, 0);
  h.recordError(16, 0.1, 0.0, 0.5);
  const std::string line = progressLine(h, 16, 1.5, 8.0, 0.5);
  EXPECT_EQ(line, "sample 16  1.50 Mrays/s  8.0 s  error 0.1000 (target 0.05)  ETA 24.0 s");
  Halting bounded({64, 0.0, 0.0}, 0);
  EXPECT_EQ(progressLine(bounded, 4, 2.0, 130.0, 0.5), "sample 4/64  2.00 Mrays/s  2 min 10 s  ETA 30.0 s");
  EXPECT_EQ(progressLine(bounded, 64, 2.0, 130.0, 0.5, /*final=*/true), "sample 64/64  2.00 Mrays/s  2 min 10 s");
}

}  // namespace
}  // namespace wt
