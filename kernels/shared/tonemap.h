// Tone mapping operators, exposure and the 8-bit encoding, plain C for the
// host (tests, host/render/tonemap.cpp) and the tonemap stage
// (kernels/tonemap.cl): scene-linear Rec.709 radiance in, display-linear
// Rec.709 in [0, 1] out, then the sRGB curve and a dithered quantisation.
// The operators and their constants are described in docs/tonemapping.md.
#ifndef WT_SHARED_TONEMAP_H
#define WT_SHARED_TONEMAP_H

#include "shared/rng.h"
#include "shared/types.h"

#ifdef __OPENCL_C_VERSION__
#define WT_TONEMAP_INLINE inline
#define WT_TONEMAP_TABLE __constant
#define WT_TONEMAP_FMA(a, b, c) fma(a, b, c)
#define WT_TONEMAP_FLOAT_BITS(x) as_uint(x)
#define WT_TONEMAP_BITS_FLOAT(x) as_float(x)
#else
#include <bit>
#include <cmath>
#define WT_TONEMAP_INLINE static inline
#define WT_TONEMAP_TABLE static const
#define WT_TONEMAP_FMA(a, b, c) std::fma(a, b, c)
#define WT_TONEMAP_FLOAT_BITS(x) std::bit_cast<wt_uint>(x)
#define WT_TONEMAP_BITS_FLOAT(x) std::bit_cast<float>(x)
#endif

/// Operators (WtTonemapParams::op); names as --tonemap spells them.
#define WT_TONEMAP_LINEAR 0u             ///< "linear": clamp to [0, 1]
#define WT_TONEMAP_REINHARD 1u           ///< "reinhard": L / (1 + L) on luminance
#define WT_TONEMAP_REINHARD_MODIFIED 2u  ///< "reinhard-modified": Reinhard 2002 eq. 4, luminance `white` maps to 1
#define WT_TONEMAP_HABLE 3u              ///< "hable": Uncharted 2 filmic, Falcor's constants, linear white `white`
#define WT_TONEMAP_ACES 4u               ///< "aces": Hill's fit of the ACES RRT+ODT with its AP1 matrices
#define WT_TONEMAP_ACES_NARKOWICZ 5u     ///< "aces-narkowicz": Narkowicz's luminance fit, as Falcor's ToneMapper "Aces"
#define WT_TONEMAP_AGX 6u                ///< "agx": Blender's AgX base (inset, log2 sigmoid, outset)
#define WT_TONEMAP_PBR_NEUTRAL 7u        ///< "pbr-neutral": the Khronos PBR Neutral tone mapper
#define WT_TONEMAP_COUNT 8u

/// WtTonemapParams::flags.
#define WT_TONEMAP_FLAG_AUTO_EXPOSURE 1u  ///< scale by the device's auto exposure (exposure[0])
#define WT_TONEMAP_FLAG_DITHER 2u         ///< add the per-pixel dither before quantising

/// Middle grey: --exposure auto maps the image's log-average luminance here.
#define WT_TONEMAP_MIDDLE_GREY 0.18f
/// Luminances below this count as this in the log-average (no log2(0)).
#define WT_TONEMAP_MIN_LUMINANCE 1e-4f
/// Pixels one work-item of the log-luminance pass sums (tonemap_log_luminance).
#define WT_TONEMAP_CHUNK 256u

/// Settings of the tonemap stage that are not the frame's exposure scale
/// (WtFrameParams::exposure: 2^stops times the physical camera's scale).
typedef struct WtTonemapParams {
  wt_uint op;          ///< WT_TONEMAP_*
  wt_uint flags;       ///< WT_TONEMAP_FLAG_*
  float white;         ///< reinhard-modified: luminance mapped to 1; hable: linear white (after the bias of 2)
  wt_uint pad0;
  WtVec4 balance_r;    ///< white balance, row 0 of the 3x3 Rec.709 matrix (w unused); identity without it
  WtVec4 balance_g;    ///< row 1
  WtVec4 balance_b;    ///< row 2
} WtTonemapParams;

/// Three floats by value: a colour inside one evaluation (not a buffer layout).
typedef struct TonemapRgb {
  float r, g, b;
} TonemapRgb;

WT_TONEMAP_INLINE TonemapRgb tonemap_rgb(float r, float g, float b) {
  TonemapRgb c;
  c.r = r, c.g = g, c.b = b;
  return c;
}

WT_TONEMAP_INLINE TonemapRgb tonemap_scale(TonemapRgb c, float s) { return tonemap_rgb(c.r * s, c.g * s, c.b * s); }

WT_TONEMAP_INLINE TonemapRgb tonemap_mat3(TonemapRgb c, float m00, float m01, float m02, float m10, float m11,
                                          float m12, float m20, float m21, float m22) {
  return tonemap_rgb(m00 * c.r + m01 * c.g + m02 * c.b, m10 * c.r + m11 * c.g + m12 * c.b,
                     m20 * c.r + m21 * c.g + m22 * c.b);
}

WT_TONEMAP_INLINE float tonemap_saturate(float x) { return fmin(fmax(x, 0.0f), 1.0f); }

WT_TONEMAP_INLINE TonemapRgb tonemap_saturate_rgb(TonemapRgb c) {
  return tonemap_rgb(tonemap_saturate(c.r), tonemap_saturate(c.g), tonemap_saturate(c.b));
}

/// Rec.709 luminance of linear RGB.
WT_TONEMAP_INLINE float tonemap_luminance(TonemapRgb c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// reinhard: the colour scaled so that its luminance L becomes L / (1 + L)
WT_TONEMAP_INLINE TonemapRgb tonemap_reinhard(TonemapRgb c) {
  float l = tonemap_luminance(c);
  return l > 0.0f ? tonemap_scale(c, 1.0f / (1.0f + l)) : tonemap_rgb(0.0f, 0.0f, 0.0f);
}

// modified reinhard: L (1 + L / white^2) / (1 + L), so luminance `white` maps to 1
WT_TONEMAP_INLINE TonemapRgb tonemap_reinhard_modified(TonemapRgb c, float white) {
  float l = tonemap_luminance(c);
  if (!(l > 0.0f)) return tonemap_rgb(0.0f, 0.0f, 0.0f);
  return tonemap_scale(c, (1.0f + l / (white * white)) / (1.0f + l));
}

// Hable's Uncharted 2 curve with the constants Falcor's ToneMapper uses:
// shoulder 0.22, linear 0.3, linear angle 0.1, toe 0.2, toe numerator 0.01
// and denominator 0.3; f(0) = 0
WT_TONEMAP_INLINE float tonemap_hable_curve(float x) {
  const float a = 0.22f, b = 0.3f, c = 0.1f, d = 0.2f, e = 0.01f, f = 0.3f;
  return (x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f) - e / f;
}

// hable: curve(2 x) / curve(white); the bias of 2 is Falcor's (and Hable's)
WT_TONEMAP_INLINE TonemapRgb tonemap_hable(TonemapRgb c, float white) {
  float w = 1.0f / tonemap_hable_curve(white);
  return tonemap_rgb(tonemap_hable_curve(2.0f * c.r) * w, tonemap_hable_curve(2.0f * c.g) * w,
                     tonemap_hable_curve(2.0f * c.b) * w);
}

// Hill's fit of the ACES reference rendering and sRGB output transforms
// (RRT+ODT), per channel in ACES AP1 after the sRGB -> AP1 (with the RRT's
// saturation) matrix, and back
WT_TONEMAP_INLINE float tonemap_aces_rrt_odt(float v) {
  return (v * (v + 0.0245786f) - 0.000090537f) / (v * (0.983729f * v + 0.4329510f) + 0.238081f);
}

WT_TONEMAP_INLINE TonemapRgb tonemap_aces(TonemapRgb c) {
  c = tonemap_mat3(c, 0.59719f, 0.35458f, 0.04823f, 0.07600f, 0.90834f, 0.01566f, 0.02840f, 0.13383f, 0.83777f);
  c = tonemap_rgb(tonemap_aces_rrt_odt(c.r), tonemap_aces_rrt_odt(c.g), tonemap_aces_rrt_odt(c.b));
  c = tonemap_mat3(c, 1.60475f, -0.53108f, -0.07367f, -0.10208f, 1.10813f, -0.00605f, -0.00327f, -0.07276f,
                   1.07602f);
  return tonemap_saturate_rgb(c);
}

// Narkowicz's fit x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), with the
// 0.6 that undoes the exposure built into it, as Falcor's ToneMapper has it
WT_TONEMAP_INLINE float tonemap_aces_narkowicz_curve(float x) {
  x *= 0.6f;
  return tonemap_saturate((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f));
}

WT_TONEMAP_INLINE TonemapRgb tonemap_aces_narkowicz(TonemapRgb c) {
  return tonemap_rgb(tonemap_aces_narkowicz_curve(c.r), tonemap_aces_narkowicz_curve(c.g),
                     tonemap_aces_narkowicz_curve(c.b));
}

// AgX (Sobotka; EaryChow's Blender 4 version): log2 encoding from 10 stops
// below to 6.5 stops above middle grey, and Jed Smith's tunable sigmoid
// through (x_pivot, y_pivot) = (10 / 16.5, 0.18^(1/2.4)) with slope 2.4,
// toe and shoulder powers 1.5 and limits (0, 0) and (1, 1); its output is
// encoded with power 2.4. TONEMAP_AGX_TOE and _SHOULDER are the sigmoid's
// scales for those limits (tests/kernels/test_tonemap.cpp derives them).
#define WT_TONEMAP_AGX_X_PIVOT 0.60606060606060606f
#define WT_TONEMAP_AGX_Y_PIVOT 0.48943708957387834f
#define WT_TONEMAP_AGX_TOE (-0.56567560665437460f)
#define WT_TONEMAP_AGX_SHOULDER 0.71519828627904440f

WT_TONEMAP_INLINE float tonemap_agx_sigmoid(float x) {
  float scale = x < WT_TONEMAP_AGX_X_PIVOT ? WT_TONEMAP_AGX_TOE : WT_TONEMAP_AGX_SHOULDER;
  float t = 2.4f * (x - WT_TONEMAP_AGX_X_PIVOT) / scale;  // >= 0 on both sides
  return scale * t / pow(1.0f + pow(t, 1.5f), 1.0f / 1.5f) + WT_TONEMAP_AGX_Y_PIVOT;
}

WT_TONEMAP_INLINE float tonemap_agx_channel(float v) {
  // normalised log2 exposure in [0, 1]; log2(0.18) = -2.4739311883324122
  float x = tonemap_saturate((log2(v) + 2.4739311883324122f + 10.0f) / 16.5f);
  return pow(tonemap_agx_sigmoid(x), 2.4f);
}

WT_TONEMAP_INLINE TonemapRgb tonemap_agx(TonemapRgb c) {
  // no log2(0) below: negative and zero channels clamp to a tiny positive value
  c = tonemap_rgb(fmax(c.r, 1e-10f), fmax(c.g, 1e-10f), fmax(c.b, 1e-10f));
  // Rec.709 -> Rec.2020, then AgX's inset matrix (rotate 3, -1, -2; inset 0.4, 0.22, 0.13)
  c = tonemap_mat3(c, 0.54481474648824520f, 0.37378739837269653f, 0.08139785513905834f, 0.14041694846405340f,
                   0.75413755456739420f, 0.10544549696855228f, 0.08881041961490976f, 0.17887175642085748f,
                   0.73231782396423210f);
  c = tonemap_rgb(tonemap_agx_channel(c.r), tonemap_agx_channel(c.g), tonemap_agx_channel(c.b));
  // the inverse of the outset matrix (inset 0.4, 0.22, 0.04), then Rec.2020 -> Rec.709
  c = tonemap_mat3(c, 1.96488741169488470f, -0.85598849569021450f, -0.10889891600467203f, -0.29931336490474190f,
                   1.32639796461979940f, -0.02708459971505772f, -0.16435274252839290f, -0.23818396942808817f,
                   1.40253671195648000f);
  return tonemap_saturate_rgb(c);
}

// Khronos PBR Neutral (the specification's formula): a toe that takes
// 0.04 off, compression of the peak channel from 0.76, desaturation 0.15
WT_TONEMAP_INLINE TonemapRgb tonemap_pbr_neutral(TonemapRgb c) {
  const float start = 0.8f - 0.04f, desaturation = 0.15f;
  float x = fmin(c.r, fmin(c.g, c.b));
  float offset = x < 0.08f ? x - 6.25f * x * x : 0.04f;
  c = tonemap_rgb(c.r - offset, c.g - offset, c.b - offset);
  float peak = fmax(c.r, fmax(c.g, c.b));
  if (peak < start) return c;
  const float d = 1.0f - start;
  float new_peak = 1.0f - d * d / (peak + d - start);
  c = tonemap_scale(c, new_peak / peak);
  float g = 1.0f - 1.0f / (desaturation * (peak - new_peak) + 1.0f);
  return tonemap_rgb(c.r + (new_peak - c.r) * g, c.g + (new_peak - c.g) * g, c.b + (new_peak - c.b) * g);
}

/// Display-linear colour in [0, 1] of scene-linear `c` (already exposed).
WT_TONEMAP_INLINE TonemapRgb tonemap_apply(wt_uint op, TonemapRgb c, float white) {
  // negative radiance (a filter's or the compensated sum's) is not light
  c = tonemap_rgb(fmax(c.r, 0.0f), fmax(c.g, 0.0f), fmax(c.b, 0.0f));
  switch (op) {
    case WT_TONEMAP_REINHARD: c = tonemap_reinhard(c); break;
    case WT_TONEMAP_REINHARD_MODIFIED: c = tonemap_reinhard_modified(c, white); break;
    case WT_TONEMAP_HABLE: c = tonemap_hable(c, white); break;
    case WT_TONEMAP_ACES: c = tonemap_aces(c); break;
    case WT_TONEMAP_ACES_NARKOWICZ: c = tonemap_aces_narkowicz(c); break;
    case WT_TONEMAP_AGX: c = tonemap_agx(c); break;
    case WT_TONEMAP_PBR_NEUTRAL: c = tonemap_pbr_neutral(c); break;
    default: break;
  }
  return tonemap_saturate_rgb(c);
}

/// 1.055 * 2^(5e/12) for e = 0, -1, ..., -9: the sRGB curve's power of the
/// exponent of c = m 2^e, for every c above its linear segment (c > 2^-9).
WT_TONEMAP_TABLE float kTonemapSrgbOctave[10] = {1.05499995f, 0.790356994f, 0.592098713f, 0.443572849f,
                                                 0.332304180f, 0.248946846f, 0.186499417f, 0.139716700f,
                                                 0.104669258f, 0.0784133449f};

/// The sRGB transfer function of a display-linear value in [0, 1].
WT_TONEMAP_INLINE float tonemap_srgb_encode(float c) {
  c = tonemap_saturate(c);
  // c^(1/2.4) = (2^e)^(5/12) m^(5/12), the mantissa's power by a degree-7
  // fit on [1, 2): branch-free, where exp2(log2) are library calls that keep
  // the stage scalar; within 3e-7 of the curve (test_tonemap.cpp checks every
  // float), closer than exp2(log2) at their 3-ulp bounds
  const wt_uint bits = WT_TONEMAP_FLOAT_BITS(c);
  const wt_uint biased = bits >> 23u;  // 127 + e (a set sign bit: the linear segment's -0)
  const wt_uint below = biased < 127u ? 127u - biased : 0u;
  const wt_uint octave = below < 9u ? below : 9u;
  const float t = WT_TONEMAP_BITS_FLOAT((bits & 0x007fffffu) | 0x3f800000u) - 1.0f;
  float p = WT_TONEMAP_FMA(0.00148556032f, t, -0.00791556574f);
  p = WT_TONEMAP_FMA(p, t, 0.0205341093f);
  p = WT_TONEMAP_FMA(p, t, -0.0377859958f);
  p = WT_TONEMAP_FMA(p, t, 0.0632809028f);
  p = WT_TONEMAP_FMA(p, t, -0.121420048f);
  p = WT_TONEMAP_FMA(p, t, 0.416660875f);
  p = WT_TONEMAP_FMA(p, t, 1.00000012f);
  const float encoded = WT_TONEMAP_FMA(kTonemapSrgbOctave[octave], p, -0.055f);
  return c <= 0.0031308f ? 12.92f * c : encoded;
}

/// Dither of `pixel`'s `channel`, in [-0.5, 0.5) of the last bit: a hash of
/// the two, so the same image always quantises the same way.
WT_TONEMAP_INLINE float tonemap_dither(wt_uint pixel, wt_uint channel) {
  wt_uint h = rng_hash(pixel * 3u + channel + 0x9e3779b9u);
  return (float)(h >> 8u) * (1.0f / 16777216.0f) - 0.5f;
}

/// An sRGB-encoded value in [0, 1] as 8 bits, rounded after adding `dither`
/// (in units of the last bit): 0 stays 0 and 1 stays 255 whatever the dither.
WT_TONEMAP_INLINE wt_uint tonemap_quantise(float encoded, float dither) {
  float q = floor(encoded * 255.0f + 0.5f + dither);
  return (wt_uint)fmin(fmax(q, 0.0f), 255.0f);
}

#endif  // WT_SHARED_TONEMAP_H
