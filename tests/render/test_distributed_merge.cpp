// The host side of a render shared over devices and ranks
// (render/distributed.h): the chunk plan, the pairwise merge of moments in
// double, and the conversion to and from the device's accumulation state.
#include "render/distributed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <thread>

namespace wt {
namespace {

/// The moments of samples [first, end) of `values` (per sample, rgb per pixel), by Welford in double.
Moments welford(const std::vector<std::vector<double>>& values, std::size_t pixels, int first, int end) {
  Moments m = emptyMoments(pixels, first);
  for (int s = first; s < end; ++s) {
    for (std::size_t i = 0; i < pixels; ++i) {
      const double n = double(++m.count[i]);
      for (int c = 0; c < 3; ++c) {
        const double x = values[std::size_t(s)][3 * i + c];
        const double delta = x - m.mean[3 * i + c];
        m.mean[3 * i + c] += delta / n;
        m.m2[3 * i + c] += delta * (x - m.mean[3 * i + c]);
      }
    }
  }
  m.sampleEnd = end;
  return m;
}

std::vector<std::vector<double>> heavyTailedSamples(std::size_t pixels, int samples, unsigned seed) {
  std::mt19937 rng(seed);
  std::lognormal_distribution<double> dist(0.0, 1.5);  // fireflies: a heavy right tail
  std::vector<std::vector<double>> v(std::size_t(samples), std::vector<double>(3 * pixels));
  for (auto& s : v)
    for (double& x : s) x = dist(rng);
  return v;
}

// Chan's pairwise update of chunks equals one pass over all samples to
// double rounding: a few ulps of double, relative to the mean and to M2.
TEST(DistributedMerge, ChunkMergeEqualsOnePassInDouble) {
  const std::size_t pixels = 50;
  const int samples = 300;
  const auto v = heavyTailedSamples(pixels, samples, 7);
  const Moments all = welford(v, pixels, 0, samples);
  Moments merged = emptyMoments(pixels, 0);
  for (int first = 0; first < samples; first += 37) mergeMoments(merged, welford(v, pixels, first, std::min(samples, first + 37)));
  EXPECT_EQ(merged.sampleEnd, samples);
  EXPECT_EQ(merged.count, all.count);
  for (std::size_t k = 0; k < 3 * pixels; ++k) {
    // each of the ~300 updates rounds once or twice: 1e-12 leaves a wide margin over 300 * 2^-52
    EXPECT_NEAR(merged.mean[k], all.mean[k], 1e-12 * std::fabs(all.mean[k])) << k;
    EXPECT_NEAR(merged.m2[k], all.m2[k], 1e-12 * all.m2[k]) << k;
  }
}

// Chunks that arrive out of order are merged in chunk order: the result is
// the in-order merge, bit for bit.
TEST(DistributedMerge, OutOfOrderArrivalMergesInChunkOrder) {
  const std::size_t pixels = 20;
  const auto v = heavyTailedSamples(pixels, 40, 3);
  std::vector<Moments> chunks;
  for (int first = 0; first < 40; first += 8) chunks.push_back(welford(v, pixels, first, first + 8));
  OrderedMerge inOrder(emptyMoments(pixels, 0)), shuffled(emptyMoments(pixels, 0));
  for (int c = 0; c < 5; ++c) inOrder.add(c, chunks[std::size_t(c)]);
  bool zeroIn = false;
  for (int c : {3, 1, 4, 0, 2}) {
    shuffled.add(c, chunks[std::size_t(c)]);
    zeroIn = zeroIn || c == 0;
    if (!zeroIn) {
      EXPECT_EQ(shuffled.samplesDone(), 0) << "chunk 0 not there yet";
    }
  }
  EXPECT_EQ(shuffled.samplesDone(), 40);
  EXPECT_EQ(shuffled.waiting(), 0u);
  EXPECT_EQ(std::memcmp(shuffled.merged().mean.data(), inOrder.merged().mean.data(), 3 * pixels * sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(shuffled.merged().m2.data(), inOrder.merged().m2.data(), 3 * pixels * sizeof(double)), 0);
}

TEST(DistributedMerge, RefusesAGapOrAnotherImageSize) {
  Moments a = emptyMoments(4, 0);
  a.sampleEnd = 8;
  Moments gap = emptyMoments(4, 9);
  EXPECT_THROW(mergeMoments(a, gap), std::invalid_argument);
  Moments other = emptyMoments(5, 8);
  EXPECT_THROW(mergeMoments(a, other), std::invalid_argument);
}

// A pixel without finite samples in a chunk leaves the merged pixel as it was.
TEST(DistributedMerge, PixelWithoutSamplesInAChunkIsUnchanged) {
  Moments a = emptyMoments(1, 0), b = emptyMoments(1, 4);
  a.sampleEnd = 4, a.count[0] = 4, a.mean = {1.0, 2.0, 3.0}, a.m2 = {0.5, 0.5, 0.5};
  b.sampleEnd = 8, b.nonFiniteSamples = 4;
  mergeMoments(a, b);
  EXPECT_EQ(a.count[0], 4u);
  EXPECT_EQ(a.mean, (std::vector<double>{1.0, 2.0, 3.0}));
  EXPECT_EQ(a.sampleEnd, 8);
  EXPECT_EQ(a.nonFiniteSamples, 4u);
}

// The device state written from moments reads back as the same moments:
// exactly in double mode; in kahan mode the float and its compensation hold
// the double to about 2^-48 of its value; single keeps the float.
TEST(DistributedMerge, AccumulationStateRoundTrip) {
  const std::size_t pixels = 30;
  const auto v = heavyTailedSamples(pixels, 50, 11);
  const Moments m = welford(v, pixels, 0, 50);
  for (std::uint32_t mode : {WT_ACCUMULATE_DOUBLE, WT_ACCUMULATE_KAHAN, WT_ACCUMULATE_SINGLE}) {
    const Accumulation a = accumulationFromMoments(m, mode);
    EXPECT_EQ(a.samplesDone, 50);
    EXPECT_EQ(a.state.size(), pixels * kAccumulationStateBytes);
    const Moments back = momentsFromAccumulation(a, mode, 0);
    EXPECT_EQ(back.count, m.count);
    const double tolerance = mode == WT_ACCUMULATE_DOUBLE ? 0.0 : mode == WT_ACCUMULATE_KAHAN ? 0x1p-46 : 0x1p-23;
    for (std::size_t k = 0; k < 3 * pixels; ++k) {
      EXPECT_LE(std::fabs(back.mean[k] - m.mean[k]), tolerance * std::fabs(m.mean[k])) << "mode " << mode << " " << k;
      EXPECT_LE(std::fabs(back.m2[k] - m.m2[k]), tolerance * m.m2[k]) << "mode " << mode << " " << k;
    }
  }
}

// Every sample of [first, spp) is in exactly one chunk, in order; the
// default chunk size depends on the sample count alone.
TEST(DistributedMerge, ChunkPlanCoversEverySampleOnce) {
  ChunkPlan plan(5, 70, 8);
  EXPECT_EQ(plan.chunkCount(), 9);
  int expectFirst = 5, index = 0;
  while (std::optional<SampleChunk> c = plan.next()) {
    EXPECT_EQ(c->index, index++);
    EXPECT_EQ(c->firstSample, expectFirst);
    expectFirst += c->sampleCount;
  }
  EXPECT_EQ(expectFirst, 70);
  ChunkPlan closed(0, 64, 4);
  closed.next();
  closed.close();
  EXPECT_FALSE(closed.next());
  EXPECT_EQ(defaultChunkSpp(1), 1);
  EXPECT_EQ(defaultChunkSpp(256), 4);
  EXPECT_EQ(defaultChunkSpp(1 << 20), 64);
}

// AOV sums add up; the ids are those of the run that holds sample 0, not
// of a later run (whose device's id buffer holds whatever it last wrote).
TEST(DistributedMerge, AovSumsAddAndIdsComeFromSampleZero) {
  const std::size_t pixels = 3;
  Moments merged = emptyMoments(pixels, 0, true);
  for (int chunk = 0; chunk < 3; ++chunk) {
    Moments m = emptyMoments(pixels, 4 * chunk, true);
    m.sampleEnd = 4 * chunk + 4;
    for (std::size_t k = 0; k < m.aovSum.size(); ++k) m.aovSum[k] = double(k + 1) * (chunk + 1);
    for (std::size_t k = 0; k < m.aovIds.size(); ++k) m.aovIds[k] = std::uint32_t(100 * chunk + k);
    mergeMoments(merged, m);
  }
  for (std::size_t k = 0; k < merged.aovSum.size(); ++k) EXPECT_EQ(merged.aovSum[k], double(k + 1) * 6.0) << k;
  for (std::size_t k = 0; k < merged.aovIds.size(); ++k) EXPECT_EQ(merged.aovIds[k], std::uint32_t(k)) << k;
  // through the device state and back: the float sums and the ids kept
  const Moments back = momentsFromAccumulation(accumulationFromMoments(merged, WT_ACCUMULATE_KAHAN), WT_ACCUMULATE_KAHAN, 0);
  EXPECT_EQ(back.aovSum, merged.aovSum);
  EXPECT_EQ(back.aovIds, merged.aovIds);
  // a run without AOVs cannot be merged into one with them
  Moments plain = emptyMoments(pixels, merged.sampleEnd);
  EXPECT_THROW(mergeMoments(merged, plain), std::invalid_argument);
}

// A chunk given back (its rank was lost) is handed out again before any new
// one; a chunk merged twice (the lost rank answered late) is dropped; the
// waiting hand-out ends (the plan is settled) when every chunk out is complete.
TEST(DistributedMerge, GivenBackChunksGoOutAgainAndDuplicatesAreDropped) {
  ChunkPlan plan(0, 16, 4);
  std::atomic<bool> stop{false};
  const SampleChunk c0 = *plan.next(), c1 = *plan.next();
  EXPECT_EQ(c1.index, 1);
  plan.giveBack(c0.index);
  EXPECT_EQ(plan.next()->index, 0);  // before chunk 2
  EXPECT_EQ(plan.next()->index, 2);
  EXPECT_EQ(plan.nextOrWait(stop)->index, 3);
  // all four out: next() has none; nextOrWait waits until one is given back
  EXPECT_FALSE(plan.next());
  EXPECT_FALSE(plan.settled());  // chunks out may still come back: a waiting rank is not told to stop
  std::thread giver([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    plan.giveBack(2);
  });
  EXPECT_EQ(plan.nextOrWait(stop)->index, 2);
  giver.join();
  for (int i = 0; i < 3; ++i) plan.complete(i);
  EXPECT_FALSE(plan.settled());
  plan.complete(3);
  EXPECT_TRUE(plan.settled());
  EXPECT_FALSE(plan.nextOrWait(stop));  // nothing out, nothing left
  ChunkPlan cancelled(0, 16, 4);
  cancelled.next();
  cancelled.cancel();
  EXPECT_TRUE(cancelled.settled());  // a chunk still out is never merged after a cancel

  OrderedMerge merge(emptyMoments(1, 0));
  Moments a = emptyMoments(1, 0);
  a.sampleEnd = 4;
  EXPECT_TRUE(merge.add(0, a));
  EXPECT_FALSE(merge.add(0, a));
  EXPECT_EQ(merge.samplesDone(), 4);
}

}  // namespace
}  // namespace wt
