// Test-only program root: small kernels that expose the environment's device
// functions (lights/environment.cl) to tests/kernels/test_environment_sampling.cpp.
#include "common.h"
#include "lights/environment.cl"
#include "shared/lights.h"

/// Per direction: (radiance, pdf_solid_angle).
WT_KERNEL void test_env_eval_pdf(uint count, WtEnvironment env, __global const float4* texels,
                                 __global const float* marginal_cdf,
                                 __global const float* conditional_cdf,
                                 __global const float4* directions, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 d = directions[i].xyz;
  out[i] = (float4)(environment_eval(env, texels, marginal_cdf, conditional_cdf, d),
                    environment_pdf(env, texels, marginal_cdf, conditional_cdf, d));
}

/// Sample i with uniforms rng_uniform(i, 0, 0, {0,1}, seed): (direction, pdf),
/// (radiance, 0), and what eval and pdf say about the returned direction.
WT_KERNEL void test_env_sample(uint count, uint seed, WtEnvironment env,
                               __global const float4* texels, __global const float* marginal_cdf,
                               __global const float* conditional_cdf, __global float4* direction_pdf,
                               __global float4* radiance, __global float4* eval_pdf) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float u1 = rng_uniform(i, 0u, 0u, 0u, seed), u2 = rng_uniform(i, 0u, 0u, 1u, seed);
  float3 d;
  float pdf;
  float3 l = environment_sample(env, texels, marginal_cdf, conditional_cdf, u1, u2, &d, &pdf);
  direction_pdf[i] = (float4)(d, pdf);
  radiance[i] = (float4)(l, 0.0f);
  eval_pdf[i] = (float4)(environment_eval(env, texels, marginal_cdf, conditional_cdf, d),
                         environment_pdf(env, texels, marginal_cdf, conditional_cdf, d));
}
