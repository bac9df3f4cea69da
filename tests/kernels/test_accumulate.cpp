// Accumulation precision: 2^20 samples folded into a running mean in each
// mode, against the same sum in double on the host.
#include "device/program.h"
#include "device_fixture.h"
#include "shared/rng.h"
#include "shared/types.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace wt {
namespace {

struct ModeError {
  double worst = 0.0, mean = 0.0;  ///< relative error of the mean over the work-items
};

ModeError accumulateOnDevice(cl_uint mode, cl_uint distribution, cl_uint samples, cl_uint items) {
  Context& ctx = test::deviceContext();
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, items * sizeof(float));
  cl::Kernel k(test::unitTestProgram(), "test_accumulate");
  k.setArg(0, items), k.setArg(1, samples), k.setArg(2, mode), k.setArg(3, distribution), k.setArg(4, out);
  ctx.launch("test_accumulate", k, items, 8);
  std::vector<float> got(items);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, items * sizeof(float), got.data());
  ModeError e;
  for (cl_uint i = 0; i < items; ++i) {
    double sum = 0.0;
    for (cl_uint s = 0; s < samples; ++s)
      sum += distribution == 0 ? double(0.7f) : double(0.5f + rng_uniform(i, s, 0, 0, 3));
    double exact = sum / samples;
    double rel = std::abs(double(got[i]) - exact) / exact;
    e.worst = std::max(e.worst, rel);
    e.mean += rel / items;
  }
  return e;
}

TEST(Accumulate, ConstantInputIsExactInEveryMode) {
  for (cl_uint mode : {WT_ACCUMULATE_SINGLE, WT_ACCUMULATE_KAHAN, WT_ACCUMULATE_DOUBLE}) {
    if (mode == WT_ACCUMULATE_DOUBLE && !test::deviceContext().info().fp64) continue;
    // float(0.7) repeated: every Welford delta after the first is exactly 0
    EXPECT_EQ(accumulateOnDevice(mode, 0, test::testSize(1u << 20, 1u << 8), 8).worst, 0.0) << "mode " << mode;
  }
}

TEST(Accumulate, CompensatedAndDoubleStayAccurateAt2To20Samples) {
  const cl_uint samples = 1u << 20, items = 16;
  ModeError single = accumulateOnDevice(WT_ACCUMULATE_SINGLE, 1, samples, items);
  ModeError kahan = accumulateOnDevice(WT_ACCUMULATE_KAHAN, 1, samples, items);
  RecordProperty("single_worst", std::to_string(single.worst));
  RecordProperty("kahan_worst", std::to_string(kahan.worst));
  std::printf("[ accuracy ] 2^20 samples of 0.5 + U[0,1): relative error of the mean, worst of %u: "
              "single %.3g, kahan %.3g", items, single.worst, kahan.worst);
  // the result is a float: a few ulp (6e-8 each) is the floor
  EXPECT_LT(kahan.worst, 4e-7);
  EXPECT_LE(kahan.worst, single.worst);
  if (test::deviceContext().info().fp64) {
    ModeError dbl = accumulateOnDevice(WT_ACCUMULATE_DOUBLE, 1, samples, items);
    std::printf(", double %.3g", dbl.worst);
    EXPECT_LT(dbl.worst, 1.2e-7);  // only the final rounding to float
  }
  std::printf("\n");
}

// The first fold into never-written buffers (WT_FLAG_BLANK_ACCUMULATION):
// whatever they held, every word comes out as a fold into zeroed buffers
// gives it, a non-finite sample's pixel included.
TEST(Accumulate, BlankFirstFoldWritesWhatAZeroedFoldDoes) {
  Context& ctx = test::deviceContext();
  cl::Program frameProgram = buildFrameProgram(ctx, false);
  const cl_uint items = 70;  // not a multiple of the local size
  std::vector<cl_float4> radiance(items);
  for (cl_uint i = 0; i < items; ++i)
    radiance[i] = {{0.25f + rng_uniform(i, 0, 0, 0, 5), rng_uniform(i, 0, 1, 0, 5), 3.0f * rng_uniform(i, 0, 2, 0, 5), 0.0f}};
  radiance[17].s[1] = std::numeric_limits<float>::quiet_NaN();
  for (cl_uint mode : {WT_ACCUMULATE_SINGLE, WT_ACCUMULATE_KAHAN, WT_ACCUMULATE_DOUBLE}) {
    if (mode == WT_ACCUMULATE_DOUBLE && !ctx.info().fp64) continue;
    auto fold = [&](bool blank) {
      cl::Context& c = ctx.context();
      cl::Buffer in(c, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, items * sizeof(cl_float4), radiance.data());
      cl::Buffer state(c, CL_MEM_READ_WRITE, items * 64), counts(c, CL_MEM_READ_WRITE, items * 4);
      cl::Buffer counters(c, CL_MEM_READ_WRITE, WT_COUNTER_COUNT * 4), aov(c, CL_MEM_READ_WRITE, 64);
      // a blank fold finds all-ones bits (NaN, and counts of 2^32 - 1), the other zeros
      ctx.fill(state, blank ? 0xffffffffu : 0u, 0, items * 64);
      ctx.fill(counts, blank ? 0xffffffffu : 0u, 0, items * 4);
      ctx.fill(counters, 0u, 0, WT_COUNTER_COUNT * 4);
      WtFrameParams frame{};
      frame.width = items;
      frame.height = 1;
      frame.accumulate_mode = mode;
      frame.flags = blank ? WT_FLAG_BLANK_ACCUMULATION : 0u;
      cl::Kernel k(frameProgram, "accumulate");
      k.setArg(0, frame), k.setArg(1, in), k.setArg(2, state), k.setArg(3, counts), k.setArg(4, counters);
      k.setArg(5, aov), k.setArg(6, aov);
      ctx.launch("accumulate", k, items);
      std::vector<std::uint8_t> words(items * 68);
      ctx.queue().enqueueReadBuffer(state, CL_TRUE, 0, items * 64, words.data());
      ctx.queue().enqueueReadBuffer(counts, CL_TRUE, 0, items * 4, words.data() + items * 64);
      cl_uint nonFinite = 0;
      ctx.queue().enqueueReadBuffer(counters, CL_TRUE, WT_COUNTER_NONFINITE * 4, 4, &nonFinite);
      EXPECT_EQ(nonFinite, 1u) << "mode " << mode;
      return words;
    };
    EXPECT_EQ(fold(true), fold(false)) << "mode " << mode;
  }
}

}  // namespace
}  // namespace wt
