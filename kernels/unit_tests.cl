// Small kernels that expose shared device code to the tests, which compare
// them with the host build of the same code (tests/kernels/test_shared_code.cpp).
#include "common.h"
#include "materials/lambert.cl"

__kernel void test_rng(uint count, uint sample, uint bounce, uint dim, uint seed,
                       __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = rng_uniform(i, sample, bounce, dim, seed);
}

__kernel void test_lambert(uint count, float4 normal, __global const float2* u,
                           __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = (float4)(lambert_sample(normal.xyz, u[i].x, u[i].y), 0.0f);
}

__kernel void test_offset(uint count, __global const float4* p, __global const float4* n,
                          __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = (float4)(ray_offset_origin(p[i].xyz, n[i].xyz), 0.0f);
}

#include "lights/light_sampling.cl"

__kernel void test_light_pick(uint count, __global const WtAliasSlot* alias, uint light_count,
                              __global uint* chosen, __global float* pmf) {
  uint i = get_global_id(0);
  if (i >= count) return;
  LightScene ls;
  ls.alias = alias;
  ls.light_count = light_count;
  float p;
  chosen[i] = light_pick(ls, rng_uniform(i, 0u, 0u, 4u, 77u), &p);
  pmf[i] = p;
}

__kernel void test_mis(uint count, __global const float2* pdfs, uint flags, __global float2* weights) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float2 p = pdfs[i];
  weights[i] = (float2)(mis_weight(p.x, p.y, flags), mis_weight(p.y, p.x, flags));
}

#include "shared/sampler.h"

__kernel void test_sobol(uint count, uint pixel, uint bounce, uint dim, uint seed, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = sampler_sobol(pixel, i, bounce, dim, seed);
}
