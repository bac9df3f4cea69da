// Stage 5: exposure, the sRGB transfer function and 8-bit quantisation.
#include "common.h"

inline float tonemap_srgb(float linear) {
  float c = clamp(linear, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * pow(c, 1.0f / 2.4f) - 0.055f;
}

WT_KERNEL void tonemap(WtFrameParams frame, __global const float4* mean, __global uchar4* pixels) {
  uint i = get_global_id(0);
  if (i >= frame.width * frame.height) return;
  float3 c = mean[i].xyz * frame.exposure;
  float4 srgb = (float4)(tonemap_srgb(c.x), tonemap_srgb(c.y), tonemap_srgb(c.z), 1.0f);
  pixels[i] = convert_uchar4_sat_rte(srgb * 255.0f);
}
