// Light selection and MIS on the device: the alias table reproduces its
// pmf (chi-square), and the MIS weights of the two strategies sum to one.
#include "device/program.h"
#include "device_fixture.h"
#include "render/light_list.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <random>

namespace wt {
namespace {

TEST(LightSampling, AliasTableReproducesItsPmf) {
  Context& ctx = test::deviceContext();
  // uneven weights, zeros included: a zero-weight light is never chosen
  std::vector<double> weights = {5.0, 0.0, 1.0, 0.25, 12.0, 3.0, 0.0, 0.5, 7.5, 2.0, 1e-3};
  std::vector<WtAliasSlot> table = buildAliasTable(weights);
  double sum = 0.0;
  for (double w : weights) sum += w;
  for (std::size_t i = 0; i < weights.size(); ++i) EXPECT_FLOAT_EQ(table[i].pmf, float(weights[i] / sum));

  // the rarest light (1e-3 of the weight) still expects 2 picks at the small size
  const cl_uint n = test::testSize(1 << 20, 1 << 16);
  cl::Buffer alias(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, table.size() * sizeof(WtAliasSlot), table.data());
  cl::Buffer chosen(ctx.context(), CL_MEM_WRITE_ONLY, n * 4), pmf(ctx.context(), CL_MEM_WRITE_ONLY, n * 4);
  cl::Kernel k(test::unitTestProgram(), "test_light_pick");
  k.setArg(0, n), k.setArg(1, alias), k.setArg(2, cl_uint(table.size())), k.setArg(3, chosen), k.setArg(4, pmf);
  ctx.launch("test_light_pick", k, n);
  std::vector<cl_uint> picks(n);
  std::vector<float> pmfs(n);
  ctx.queue().enqueueReadBuffer(chosen, CL_TRUE, 0, n * 4, picks.data());
  ctx.queue().enqueueReadBuffer(pmf, CL_TRUE, 0, n * 4, pmfs.data());

  std::vector<double> counts(weights.size(), 0.0);
  for (cl_uint i = 0; i < n; ++i) {
    ASSERT_LT(picks[i], weights.size());
    ASSERT_EQ(pmfs[i], table[picks[i]].pmf);  // the pmf returned is the chosen light's
    counts[picks[i]] += 1.0;
  }
  double chi2 = 0.0;
  int dof = -1;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    double expected = n * weights[i] / sum;
    if (weights[i] == 0.0) {
      EXPECT_EQ(counts[i], 0.0) << "light " << i << " has zero weight";
      continue;
    }
    chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
    ++dof;
  }
  // 8 degrees of freedom: P(chi2 > 26.1) = 0.001
  EXPECT_EQ(dof, 8);
  EXPECT_LT(chi2, 26.1) << "counts: " << ::testing::PrintToString(counts);
}

TEST(LightSampling, AliasTableOfOneAndOfNone) {
  std::vector<double> one = {3.0};
  std::vector<WtAliasSlot> t = buildAliasTable(one);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_FLOAT_EQ(t[0].pmf, 1.0f);
  EXPECT_FLOAT_EQ(t[0].threshold, 1.0f);
  std::vector<double> none = {0.0, 0.0};
  for (const WtAliasSlot& s : buildAliasTable(none)) EXPECT_EQ(s.pmf, 0.0f);
}

TEST(LightSampling, MisWeightsSumToOne) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> logu(-20.0f, 20.0f);
  std::vector<cl_float2> pdfs(4096);
  for (auto& p : pdfs) p = {{std::exp2(logu(rng)), std::exp2(logu(rng))}};
  pdfs[0] = {{1.0f, 0.0f}};  // one strategy cannot sample the direction
  const cl_uint n = cl_uint(pdfs.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 8, pdfs.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * 8);
  cl::Kernel k(test::unitTestProgram(), "test_mis");
  for (cl_uint flags : {0u, cl_uint(WT_FLAG_POWER_HEURISTIC)}) {
    k.setArg(0, n), k.setArg(1, in), k.setArg(2, flags), k.setArg(3, out);
    ctx.launch("test_mis", k, n);
    std::vector<cl_float2> w(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 8, w.data());
    for (cl_uint i = 0; i < n; ++i) {
      EXPECT_NEAR(w[i].s[0] + w[i].s[1], 1.0f, 2e-6f) << "pdfs " << pdfs[i].s[0] << ", " << pdfs[i].s[1];
      EXPECT_GE(w[i].s[0], 0.0f);
    }
    EXPECT_EQ(w[0].s[0], 1.0f);
  }
}

}  // namespace
}  // namespace wt
