// Stage 5: exposure (manual, physical or automatic), white balance, the tone
// mapping operator (shared/tonemap.h), the sRGB curve and a dithered 8-bit
// quantisation. The mean image (accumulate_resolve's, or with
// WT_FLAG_MEAN_IN_STATE the accumulation state's) is only read: the EXR
// stays linear. Part of the frame program (frame.cl): reads no compile-time
// switch.
#include "base.h"
#include "shared/tonemap.h"

// Auto exposure, pass 1: work-item i sums log2 of the luminance of pixels
// [i * WT_TONEMAP_CHUNK, (i + 1) * WT_TONEMAP_CHUNK) into partials[i] (no
// float atomics; pass 2 adds the partial sums).
WT_KERNEL void tonemap_log_luminance(WtFrameParams frame, __global const float4* mean, __global float* partials) {
  uint i = get_global_id(0);
  uint pixels = frame.width * frame.height;
  uint count = (pixels + WT_TONEMAP_CHUNK - 1u) / WT_TONEMAP_CHUNK;
  if (i >= count) return;
  uint end = min(pixels, (i + 1u) * WT_TONEMAP_CHUNK);
  const uint stride = (frame.flags & WT_FLAG_MEAN_IN_STATE) != 0u ? 4u : 1u;
  float sum = 0.0f;
  for (uint p = i * WT_TONEMAP_CHUNK; p < end; ++p) {
    float4 c = mean[p * stride];
    float l = tonemap_luminance(tonemap_rgb(c.x, c.y, c.z));
    // NaN and negative luminances count as the floor, not as poison
    sum += log2(l > WT_TONEMAP_MIN_LUMINANCE ? l : WT_TONEMAP_MIN_LUMINANCE);
  }
  partials[i] = sum;
}

// Auto exposure, pass 2 (one work-item): the log-average luminance from the
// partial sums (compensated), and the scale that takes it to middle grey.
WT_KERNEL void tonemap_exposure(WtFrameParams frame, __global const float* partials, __global float* exposure) {
  if (get_global_id(0) != 0) return;
  uint pixels = frame.width * frame.height;
  uint count = (pixels + WT_TONEMAP_CHUNK - 1u) / WT_TONEMAP_CHUNK;
  float sum = 0.0f, compensation = 0.0f;
  for (uint k = 0; k < count; ++k) {
    float y = partials[k] - compensation;
    float t = sum + y;
    compensation = (t - sum) - y;
    sum = t;
  }
  exposure[0] = WT_TONEMAP_MIDDLE_GREY / exp2(sum / (float)pixels);
}

WT_KERNEL void tonemap(WtFrameParams frame, WtTonemapParams tonemap, __global const float* exposure,
                       __global const float4* mean, __global uchar4* pixels) {
  uint i = get_global_id(0);
  if (i >= frame.width * frame.height) return;
  float scale = frame.exposure;
  if (tonemap.flags & WT_TONEMAP_FLAG_AUTO_EXPOSURE) scale *= exposure[0];
  // the state's first float4 is the mean (WT_FLAG_MEAN_IN_STATE)
  float4 m = mean[(frame.flags & WT_FLAG_MEAN_IN_STATE) != 0u ? 4u * i : i];
  TonemapRgb c = tonemap_scale(tonemap_rgb(m.x, m.y, m.z), scale);
  c = tonemap_mat3(c, tonemap.balance_r.x, tonemap.balance_r.y, tonemap.balance_r.z, tonemap.balance_g.x,
                   tonemap.balance_g.y, tonemap.balance_g.z, tonemap.balance_b.x, tonemap.balance_b.y,
                   tonemap.balance_b.z);
  c = tonemap_apply(tonemap.op, c, tonemap.white);
  const bool dither = (tonemap.flags & WT_TONEMAP_FLAG_DITHER) != 0u;
  uchar4 q;
  q.x = (uchar)tonemap_quantise(tonemap_srgb_encode(c.r), dither ? tonemap_dither(i, 0u) : 0.0f);
  q.y = (uchar)tonemap_quantise(tonemap_srgb_encode(c.g), dither ? tonemap_dither(i, 1u) : 0.0f);
  q.z = (uchar)tonemap_quantise(tonemap_srgb_encode(c.b), dither ? tonemap_dither(i, 2u) : 0.0f);
  q.w = (uchar)255;
  pixels[i] = q;
}
