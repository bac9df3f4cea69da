// Shared device code run as tiny kernels and checked against the host build
// of the same header, or against what it must satisfy.
#include "device/program.h"
#include "device_fixture.h"
#include "shared/rng.h"
#include "test_util.h"

#include <glm/glm.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace wt {
namespace {

TEST(SharedCode, RngMatchesTheHostBuildBitForBit) {
  Context& ctx = test::deviceContext();
  const cl_uint n = 4096;
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
  cl::Kernel k(test::unitTestProgram(), "test_rng");
  for (auto [sample, bounce, dim, seed] : {std::array<cl_uint, 4>{0, 0, 0, 0}, {17, 3, 2, 99}, {1u << 20, 7, 3, 12345}}) {
    k.setArg(0, n), k.setArg(1, sample), k.setArg(2, bounce), k.setArg(3, dim), k.setArg(4, seed), k.setArg(5, out);
    ctx.launch("test_rng", k, n);
    std::vector<float> got(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float), got.data());
    double sum = 0.0;
    for (cl_uint i = 0; i < n; ++i) {
      ASSERT_EQ(got[i], rng_uniform(i, sample, bounce, dim, seed)) << "pixel " << i;
      ASSERT_GE(got[i], 0.0f);
      ASSERT_LT(got[i], 1.0f);
      sum += got[i];
    }
    // mean of n uniforms: standard error 1/sqrt(12 n); allow 5 of them
    EXPECT_NEAR(sum / n, 0.5, 5.0 / std::sqrt(12.0 * n));
  }
}

TEST(SharedCode, LambertSamplesAreCosineDistributed) {
  Context& ctx = test::deviceContext();
  const cl_uint n = test::testSize(1 << 16, 1 << 12);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<cl_float2> us(n);
  for (auto& v : us) v = {{u(rng), u(rng)}};
  glm::vec3 normal = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float2), us.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(test::unitTestProgram(), "test_lambert");
  k.setArg(0, n), k.setArg(1, cl_float4{{normal.x, normal.y, normal.z, 0}}), k.setArg(2, in), k.setArg(3, out);
  ctx.launch("test_lambert", k, n);
  std::vector<cl_float4> dirs(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float4), dirs.data());
  // Chi-square over 8 bins of cos(theta)^2, which is uniform under a cosine
  // distribution (pdf of c = cos(theta) is 2c, so c^2 ~ U(0,1)).
  const int kBins = 8;
  std::vector<double> counts(kBins, 0.0);
  for (const cl_float4& d : dirs) {
    glm::vec3 v(d.s[0], d.s[1], d.s[2]);
    ASSERT_NEAR(glm::length(v), 1.0f, 1e-5f);
    float c = glm::dot(v, normal);
    ASSERT_GE(c, 0.0f);
    counts[std::min(kBins - 1, int(c * c * kBins))] += 1.0;
  }
  double chi2 = 0.0, expected = double(n) / kBins;
  for (double c : counts) chi2 += (c - expected) * (c - expected) / expected;
  // 7 degrees of freedom: P(chi2 > 24.3) = 0.001
  EXPECT_LT(chi2, 24.3) << "histogram of cos^2: " << ::testing::PrintToString(counts);
}

TEST(SharedCode, RayOffsetLeavesTheSurfaceOnTheNormalSide) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<cl_float4> p, nrm;
  for (float scale : {1e-6f, 1e-2f, 1.0f, 1e3f, 1e5f})
    for (int i = 0; i < 200; ++i) {
      glm::vec3 n = glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
      p.push_back({{scale * u(rng), scale * u(rng), scale * u(rng), 0}});
      nrm.push_back({{n.x, n.y, n.z, 0}});
    }
  const cl_uint n = cl_uint(p.size());
  cl::Buffer bp(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 16, p.data());
  cl::Buffer bn(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 16, nrm.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * 16);
  cl::Kernel k(test::unitTestProgram(), "test_offset");
  k.setArg(0, n), k.setArg(1, bp), k.setArg(2, bn), k.setArg(3, out);
  ctx.launch("test_offset", k, n);
  std::vector<cl_float4> got(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 16, got.data());
  for (cl_uint i = 0; i < n; ++i) {
    glm::dvec3 before(p[i].s[0], p[i].s[1], p[i].s[2]), after(got[i].s[0], got[i].s[1], got[i].s[2]);
    glm::dvec3 normal(nrm[i].s[0], nrm[i].s[1], nrm[i].s[2]);
    double moved = glm::dot(after - before, normal);
    EXPECT_GT(moved, 0.0) << "point " << i;
    // a few thousand ULPs of the largest coordinate at most, never a world-space jump
    double ulp = std::max(std::ldexp(1.0, -23) * glm::length(before), 1.0 / 65536.0);
    EXPECT_LT(glm::length(after - before), 2048.0 * ulp) << "point " << i;
  }
}

}  // namespace
}  // namespace wt
