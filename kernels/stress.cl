// The stress suite's kernels (`wavetrace stress`, host/stress/stress.cpp): a
// program of its own, so the render program carries none of them and the
// test kernels need not ship in the binary. kernels/unit_tests.cl includes it.
#ifndef WT_STRESS_CL
#define WT_STRESS_CL

#include "common.h"
#include "accumulate.cl"

// `samples` running-mean updates per work-item of values keyed like the
// renderer's samples; distribution 0: the constant 0.7, 1: 0.5 + uniform.
WT_KERNEL void test_accumulate(uint count, uint samples, uint mode, uint distribution,
                               __global float* out_mean) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 mean = (float4)(0.0f), m2 = (float4)(0.0f), c_mean = (float4)(0.0f), c_m2 = (float4)(0.0f);
#if WT_HAS_FP64
  double4 mean_d = (double4)(0.0), m2_d = (double4)(0.0);
#endif
  for (uint s = 0u; s < samples; ++s) {
    float v = distribution == 0u ? 0.7f : 0.5f + rng_uniform(i, s, 0u, 0u, 3u);
    float4 x = (float4)(v, v, v, 0.0f);
    float n = (float)(s + 1u);
    if (mode == WT_ACCUMULATE_KAHAN) accumulate_kahan(x, n, &mean, &m2, &c_mean, &c_m2);
#if WT_HAS_FP64
    else if (mode == WT_ACCUMULATE_DOUBLE) accumulate_double(x, (double)(s + 1u), &mean_d, &m2_d);
#endif
    else accumulate_single(x, n, &mean, &m2);
  }
#if WT_HAS_FP64
  if (mode == WT_ACCUMULATE_DOUBLE) mean = convert_float4(mean_d);
#endif
  out_mean[i] = mean.x;
}

#endif
