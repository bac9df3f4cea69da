// Accumulation precision: 2^20 samples folded into a running mean in each
// mode, against the same sum in double on the host.
#include "device_fixture.h"
#include "shared/rng.h"
#include "shared/types.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace wt
