// The tone mapping operators of shared/tonemap.h as a kernel, for
// tests/kernels/test_tonemap.cpp to compare with their closed forms.
#include "common.h"
#include "shared/tonemap.h"

// out[i] = the display-linear colour operator `op` makes of in[i].
WT_KERNEL void test_tonemap_apply(uint count, uint op, float white, __global const float4* in,
                                  __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 c = in[i];
  TonemapRgb t = tonemap_apply(op, tonemap_rgb(c.x, c.y, c.z), white);
  out[i] = (float4)(t.r, t.g, t.b, 0.0f);
}

// out[i] = the sRGB curve of the float whose bits are first + i.
WT_KERNEL void test_srgb_encode(uint first, uint count, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = tonemap_srgb_encode(as_float(first + i));
}
