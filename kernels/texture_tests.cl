// Test-only program root: small kernels that expose the texture sampler
// (materials/texture.cl) to tests/kernels/test_texture_sample.cpp.
#include "common.h"
#include "materials/texture.cl"

/// Per query (u, v, lod, texture index as uint bits): texture_sample.
WT_KERNEL void test_texture_sample(uint count, __global const WtTexture* textures,
                                   __global const WtTextureLevel* levels, __global const uint* texels,
                                   __global const float4* queries, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 q = queries[i];
  out[i] = texture_sample(textures, levels, texels, as_uint(q.w), q.xy, q.z);
}

/// Per query (footprint_uv, texture index as uint bits): texture_lod.
WT_KERNEL void test_texture_lod(uint count, __global const WtTexture* textures,
                                __global const WtTextureLevel* levels, __global const float2* queries,
                                __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = texture_lod(textures, levels, as_uint(queries[i].y), queries[i].x);
}
