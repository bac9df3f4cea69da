// The Owen-scrambled Sobol sampler: each dimension pair is a (0,m,2)-net,
// the device computes exactly what the host build of the header does, and
// the closed form of the second dimension is its definition.
#include "device/program.h"
#include "device_fixture.h"
#include "shared/sampler.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>

namespace wt {
namespace {

/// The first 2^m points of dims (d0, d1) put exactly one point in every
/// elementary interval of area 2^-m (all 2^a x 2^(m-a) shapes).
void expectNet(int m, wt_uint pixel, wt_uint bounce, wt_uint d0, wt_uint d1, wt_uint seed) {
  const wt_uint n = 1u << m;
  for (int a = 0; a <= m; ++a) {
    const wt_uint cols = 1u << a, rows = 1u << (m - a);
    std::vector<int> cells(n, 0);
    for (wt_uint i = 0; i < n; ++i) {
      float x = sampler_sobol(pixel, i, bounce, d0, seed), y = sampler_sobol(pixel, i, bounce, d1, seed);
      ASSERT_GE(x, 0.0f);
      ASSERT_LT(x, 1.0f);
      wt_uint cx = wt_uint(x * cols), cy = wt_uint(y * rows);
      ++cells[cy * cols + cx];
    }
    for (wt_uint c = 0; c < n; ++c)
      ASSERT_EQ(cells[c], 1) << "m=" << m << " shape " << cols << "x" << rows << " cell " << c
                             << " dims " << d0 << "," << d1 << " pixel " << pixel;
  }
}

TEST(Sampler, SobolProjectionsAreNets) {
  for (wt_uint pixel : {0u, 1u, 12345u})
    for (int m : {2, 5, 8}) {
      expectNet(m, pixel, 0, 0, 1, 7);  // pixel jitter
      expectNet(m, pixel, 3, 2, 3, 7);  // a bounce's BSDF pair
      expectNet(m, pixel, 1, 4, 5, 7);  // a point on a light
    }
}

// The five-step form of the second dimension is the direction-number
// definition bit for bit (the first 2^20 indices, then spread over all 32
// bits), and the sampler is the Owen scramble of the definition's points.
TEST(Sampler, PascalFormIsTheDirectionNumberDefinition) {
  int mismatches = 0;
  for (wt_uint i = 0; i < (1u << 20); ++i) {
    for (wt_uint index : {i, i * 4099u + 0x9e3779b9u})
      mismatches += sampler_sobol_pascal(index) != sampler_reverse_bits(sampler_sobol_bits(index, 1u));
  }
  EXPECT_EQ(mismatches, 0);
  for (wt_uint sample = 0; sample < 4096; ++sample)
    for (wt_uint dim : {0u, 1u, 6u, 7u}) {
      const wt_uint group_seed = rng_hash(5u ^ rng_hash(77u ^ rng_hash((2u << 8u) + (dim >> 1u) + 0x9e3779b9u)));
      const wt_uint index = sampler_owen_scramble(sample, group_seed);
      const wt_uint v = sampler_owen_scramble(sampler_sobol_bits(index, dim & 1u), rng_hash(group_seed + (dim & 1u) + 1u));
      ASSERT_EQ(sampler_sobol(77u, sample, 2u, dim, 5u), float(v >> 8u) * (1.0f / 16777216.0f)) << sample << " " << dim;
    }
}

// sampler_get2 (kernels/sampler.cl), which shade and generate draw their
// pairs with, gives what sampler_get gives for each dimension, bit for bit,
// for both samplers and every pair shade uses.
TEST(Sampler, PairsAreTheSingleValues) {
  Context& ctx = test::deviceContext();
  const cl_uint n = test::testSize(6 * 4096, 6 * 64);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(test::unitTestProgram(), "test_sampler_pairs");
  for (cl_uint flags : {0u, cl_uint(WT_FLAG_SOBOL)}) {
    WtFrameParams frame{};
    frame.sample = 37, frame.bounce = 3, frame.seed = 11, frame.flags = flags;
    k.setArg(0, n), k.setArg(1, frame), k.setArg(2, out);
    ctx.launch("test_sampler_pairs", k, n);
    std::vector<cl_float4> got(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float4), got.data());
    for (cl_uint i = 0; i < n; ++i) {
      ASSERT_EQ(got[i].s[0], got[i].s[2]) << "flags " << flags << ", item " << i;
      ASSERT_EQ(got[i].s[1], got[i].s[3]) << "flags " << flags << ", item " << i;
    }
  }
}

TEST(Sampler, PixelsAreDecorrelated) {
  // the same sample index in two pixels gives unrelated values
  int equal = 0;
  for (wt_uint i = 0; i < 1024; ++i) equal += sampler_sobol(1, i, 0, 2, 0) == sampler_sobol(2, i, 0, 2, 0);
  EXPECT_LT(equal, 3);
}

TEST(Sampler, DeviceMatchesHost) {
  Context& ctx = test::deviceContext();
  const cl_uint n = test::testSize(4096, 512);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * 4);
  cl::Kernel k(test::unitTestProgram(), "test_sobol");
  for (cl_uint dim : {0u, 3u, 6u}) {
    k.setArg(0, n), k.setArg(1, cl_uint(77)), k.setArg(2, cl_uint(2)), k.setArg(3, dim), k.setArg(4, cl_uint(5)), k.setArg(5, out);
    ctx.launch("test_sobol", k, n);
    std::vector<float> got(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 4, got.data());
    for (cl_uint i = 0; i < n; ++i) ASSERT_EQ(got[i], sampler_sobol(77, i, 2, dim, 5)) << i;
  }
}

}  // namespace
}  // namespace wt
