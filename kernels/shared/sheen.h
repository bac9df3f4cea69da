// The sheen lobe of KHR_materials_sheen in the local shading frame, scalars
// only so the host (which tabulates its albedo, host/render/material_tables.cpp)
// and the kernels share one definition: the "Charlie" distribution of
// micro-fibres and its Smith-style visibility with the fitted Lambda of
// Estevez and Kulla 2017 ("Production Friendly Microfacet Sheen BRDF"), as
// the extension's implementation notes give them, with alpha = roughness^2
// as for every other glTF roughness.
#ifndef WT_SHARED_SHEEN_H
#define WT_SHARED_SHEEN_H

#include "shared/ggx.h"

#ifdef __OPENCL_C_VERSION__
#define WT_SHEEN_INLINE inline
#else
#include <cmath>
#define WT_SHEEN_INLINE static inline
#endif

/// Sheen roughness is clamped to [WT_SHEEN_MIN_ROUGHNESS, 1], alpha to
/// [0.07, 1]: below that the fitted Lambda no longer masks the ever sharper
/// fibres enough, and the lobe's albedo at grazing angles exceeds 1 (measured
/// by host/render/material_tables.cpp's integration: 0.99 at alpha 0.07,
/// 1.04 at 0.06, 1.33 at 0.03, 2.5 at 0.0049). Rasterisers clamp the
/// visibility to 1 instead; a smoother sheen than asked differs from theirs
/// only at silhouettes, where either is all there is to see of it.
#define WT_SHEEN_MIN_ROUGHNESS 0.26457513f

/// x^y for x >= 0, y > 0. On the device as exp2(y log2 x) (0 at x = 0):
/// PoCL's pow and powr are slow enough to dominate a sheen-covered frame
/// (docs/materials.md, "Cost"), so the power is exp2(y log2 x).
#ifdef __OPENCL_C_VERSION__
#define WT_SHEEN_POWR(x, y) exp2((y) * log2(x))
#else
#define WT_SHEEN_POWR(x, y) pow(x, y)
#endif

/// D(h) for cos(theta_h) and alpha: (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi),
/// normalised so that its projected area is 1.
WT_SHEEN_INLINE float sheen_d(float cos_h, float alpha) {
  float sin2 = fmax(1.0f - cos_h * cos_h, 0.0f);
  float inv = 1.0f / alpha;
  return (2.0f + inv) * WT_SHEEN_POWR(sin2, 0.5f * inv) / (2.0f * WT_GGX_PI);
}

/// The fitted exponent of Lambda for one alpha, a / (1 + b x^c) + d x + e,
/// its coefficients blended by (1 - alpha)^2, and its value at 1/2 (about
/// which Lambda is mirrored): what a material computes once and every
/// direction reuses (a scalar value type, not a buffer layout).
typedef struct SheenFit {
  float a, b, c, d, e;
  float l_half;  ///< the exponent at x = 1/2
} SheenFit;

WT_SHEEN_INLINE float sheen_fit_exponent(SheenFit f, float x) {
  return f.a / (1.0f + f.b * WT_SHEEN_POWR(x, f.c)) + f.d * x + f.e;
}

WT_SHEEN_INLINE SheenFit sheen_fit(float alpha) {
  float t = (1.0f - alpha) * (1.0f - alpha);
  SheenFit f;
  f.a = 21.5473f + t * (25.3245f - 21.5473f);
  f.b = 3.82987f + t * (3.32435f - 3.82987f);
  f.c = 0.19823f + t * (0.16801f - 0.19823f);
  f.d = -1.97760f + t * (-1.27393f + 1.97760f);
  f.e = -4.32054f + t * (-4.85967f + 4.32054f);
  f.l_half = sheen_fit_exponent(f, 0.5f);
  return f;
}

/// Lambda of one direction with cosine cos_theta (mirrored about 1/2 above it).
WT_SHEEN_INLINE float sheen_lambda(SheenFit f, float cos_theta) {
  float c = fmin(fabs(cos_theta), 1.0f);
  return exp(c < 0.5f ? sheen_fit_exponent(f, c) : 2.0f * f.l_half - sheen_fit_exponent(f, 1.0f - c));
}

/// f |cos i| of the sheen lobe with colour 1 for unit directions above the
/// surface (oz, iz > 0) and their unit half vector's z:
/// D / (4 oz (1 + Lambda(o) + Lambda(i))).
WT_SHEEN_INLINE float sheen_eval_cos(float oz, float iz, float hz, float alpha) {
  if (!(oz > 0.0f) || !(iz > 0.0f)) return 0.0f;
  SheenFit f = sheen_fit(alpha);
  return sheen_d(hz, alpha) / (4.0f * oz * (1.0f + sheen_lambda(f, oz) + sheen_lambda(f, iz)));
}

#endif  // WT_SHARED_SHEEN_H
