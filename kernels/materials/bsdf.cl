// The surface BSDF: Lambertian (scenes made in code) or glTF 2.0
// metallic-roughness, evaluated and sampled in the local shading frame (z
// along the shading normal), restricted to the lobes a path may still use
// (per-lobe bounce limits).
//
// Metallic-roughness follows the glTF specification's appendix B -- a GGX
// specular lobe (height-correlated Smith masking, Schlick Fresnel with F0 =
// 0.04 for the dielectric and the base colour for metals) over a Lambertian
// base, mixed by metallic -- with two corrections for energy conservation:
// the multiple-scattering lobe of Kulla and Conty 2017 restores what single
// scattering loses at high roughness, and the base under the dielectric coat
// is weighted by what the coat leaves, (1 - E_coat(mu_o)) (1 - E_coat(mu_i)) /
// (1 - E_coat_avg), instead of the specification's (1 - F(v.h)), which gains
// energy at grazing angles. A white material then reflects exactly what
// arrives, at every roughness and angle (tests/kernels/test_bsdf.cpp).
//
// Sampling picks the GGX lobe (visible normals, Heitz 2018) or a cosine
// lobe with probabilities from the lobes' albedos, and every continuous
// sample is weighted by the mixture pdf of both techniques (one-sample MIS
// over lobes). Below WT_PBR_MIN_ROUGHNESS the GGX lobe is a mirror.
#ifndef WT_MATERIALS_BSDF_CL
#define WT_MATERIALS_BSDF_CL

#include "common.h"
#include "materials/lambert.cl"
#include "shared/materials.h"

#ifndef WT_HAS_PBR
#error "WT_HAS_PBR is not defined: build options must come from kernelDefines()"
#endif

#define WT_LOBE_DIFFUSE 1u   ///< the Lambertian base (and any cosine-sampled direction)
#define WT_LOBE_SPECULAR 2u  ///< GGX reflection, its multiple scattering, the mirror
#define WT_LOBE_DELTA 4u     ///< set on a sample: the direction came from the mirror

/// A material at a shading point.
typedef struct Bsdf {
  uint model;        ///< WT_MATERIAL_*
  float3 base;       ///< base colour (albedo of the diffuse base, F0 of the metal)
  float metallic;
  float roughness;   ///< perceptual; alpha = roughness^2
  int mirror;        ///< roughness below WT_PBR_MIN_ROUGHNESS
  __global const float* table;  ///< directional albedos (shared/materials.h)
} Bsdf;

/// The outcome of sampling a direction.
typedef struct BsdfSample {
  float3 wi;       ///< local frame, unit
  float3 weight;   ///< f cos / pdf: what the throughput is multiplied by
  float pdf;       ///< solid-angle pdf of the whole mixture; 0 for a mirror sample
  uint lobe;       ///< WT_LOBE_DIFFUSE or WT_LOBE_SPECULAR, | WT_LOBE_DELTA for a mirror
} BsdfSample;

inline Bsdf bsdf_make(WtMaterial m, __global const float* table) {
  Bsdf b;
  b.model = m.model;
  b.base = vec4_xyz(m.base_color);
  b.metallic = m.base_color.w;
  b.roughness = m.roughness;
  b.mirror = m.roughness < WT_PBR_MIN_ROUGHNESS;
  b.table = table;
  return b;
}

inline float bsdf_luminance(float3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

/// Albedos the PBR model needs at one direction's cosine.
typedef struct PbrAlbedo {
  float e;       ///< GGX single scattering with F = 1
  float e_coat;  ///< the dielectric coat, with its multiple scattering
} PbrAlbedo;

inline PbrAlbedo pbr_albedo(Bsdf b, float mu) {
  PbrAlbedo a;
  if (b.mirror) {
    a.e = 1.0f;
    a.e_coat = ggx_schlick(WT_PBR_DIELECTRIC_F0, mu);
  } else {
    a.e = pbr_table_albedo(b.table, WT_PBR_TABLE_E, mu, b.roughness);
    a.e_coat = pbr_table_albedo(b.table, WT_PBR_TABLE_E_COAT, mu, b.roughness);
  }
  return a;
}

inline float pbr_coat_average(Bsdf b) {
  return b.mirror ? ggx_schlick_average(WT_PBR_DIELECTRIC_F0)
                  : pbr_table_average(b.table, WT_PBR_TABLE_E_COAT_AVG, b.roughness);
}

/// Probability that sampling uses the GGX lobe (or the mirror), from the
/// lobes' albedos at wo; 0 or 1 when only one lobe is allowed.
inline float pbr_specular_probability(Bsdf b, PbrAlbedo ao, uint lobes) {
  if (!(lobes & WT_LOBE_SPECULAR)) return 0.0f;
  if (!(lobes & WT_LOBE_DIFFUSE)) return 1.0f;
  float s = b.metallic * ao.e + (1.0f - b.metallic) * ao.e_coat;
  float d = b.metallic * (1.0f - ao.e) + (1.0f - b.metallic) * (1.0f - ao.e_coat) * bsdf_luminance(b.base);
  return s + d > 0.0f ? s / (s + d) : 1.0f;
}

/// f cos of the continuous part (no mirror) for local wo, wi, restricted to
/// `lobes`; *pdf: the mixture's density of sampling wi.
inline float3 pbr_eval(Bsdf b, float3 wo, float3 wi, uint lobes, float* pdf) {
  *pdf = 0.0f;
  if (wo.z <= 0.0f || wi.z <= 0.0f) return (float3)(0.0f);
  PbrAlbedo ao = pbr_albedo(b, wo.z), ai = pbr_albedo(b, wi.z);
  float p_spec = pbr_specular_probability(b, ao, lobes);
  float3 f = (float3)(0.0f);
  float pdf_spec = 0.0f;
  if ((lobes & WT_LOBE_SPECULAR) && !b.mirror) {
    float alpha = b.roughness * b.roughness;
    float3 h = normalize(wo + wi);
    float oh = fmax(dot(wo, h), 0.0f);
    float d = ggx_d(h.x, h.y, h.z, alpha);
    float dv = d * ggx_g2(wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, alpha) / (4.0f * wo.z * wi.z);
    float m5 = ggx_schlick(0.0f, oh);  // (1 - oh)^5
    float3 f_metal = b.base + (1.0f - b.base) * m5;
    float f_coat = ggx_schlick(WT_PBR_DIELECTRIC_F0, oh);
    f += (b.metallic * f_metal + (1.0f - b.metallic) * f_coat) * dv;
    // multiple scattering: (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), by the average Fresnel
    float e_avg = pbr_table_average(b.table, WT_PBR_TABLE_E_AVG, b.roughness);
    float ms = (1.0f - ao.e) * (1.0f - ai.e) / (WT_PI * fmax(1.0f - e_avg, 1e-6f));
    float3 f_avg_metal = b.base + (1.0f - b.base) / 21.0f;
    float3 fms_metal = f_avg_metal * f_avg_metal * e_avg / (1.0f - f_avg_metal * (1.0f - e_avg));
    float fms_coat = pbr_multiscatter_fresnel(ggx_schlick_average(WT_PBR_DIELECTRIC_F0), e_avg);
    f += (b.metallic * fms_metal + (1.0f - b.metallic) * fms_coat) * ms;
    pdf_spec = ggx_g1(wo.x, wo.y, wo.z, alpha) * d / (4.0f * wo.z);
  }
  if (lobes & WT_LOBE_DIFFUSE) {
    float coat_avg = pbr_coat_average(b);
    f += (1.0f - b.metallic) * b.base * (1.0f / WT_PI) * (1.0f - ao.e_coat) * (1.0f - ai.e_coat) /
         fmax(1.0f - coat_avg, 1e-6f);
  }
  *pdf = p_spec * pdf_spec + (1.0f - p_spec) * wi.z / WT_PI;
  return f * wi.z;
}

/// f cos of the continuous part for local wo, wi; *pdf as pbr_eval.
inline float3 bsdf_eval(Bsdf b, float3 wo, float3 wi, uint lobes, float* pdf) {
#if WT_HAS_PBR
  if (b.model == WT_MATERIAL_PBR) return pbr_eval(b, wo, wi, lobes, pdf);
#endif
  bool ok = (lobes & WT_LOBE_DIFFUSE) && wo.z > 0.0f && wi.z > 0.0f;
  *pdf = ok ? wi.z / WT_PI : 0.0f;
  return ok ? b.base * (wi.z / WT_PI) : (float3)(0.0f);
}

/// Draw a direction for local wo with uniforms u_lobe, u1, u2. False when
/// nothing is reflected (no allowed lobe, a direction below the surface).
inline bool bsdf_sample(Bsdf b, float3 wo, uint lobes, float u_lobe, float u1, float u2, BsdfSample* s) {
  if (wo.z <= 0.0f || !(lobes & (WT_LOBE_DIFFUSE | WT_LOBE_SPECULAR))) return false;
  float p_spec = 0.0f;
#if WT_HAS_PBR
  if (b.model == WT_MATERIAL_PBR) p_spec = pbr_specular_probability(b, pbr_albedo(b, wo.z), lobes);
#endif
  if (u_lobe < p_spec) {
    s->lobe = WT_LOBE_SPECULAR;
    if (b.mirror) {
      // the mirror: F at mu_o, over the probability of having picked it
      s->wi = (float3)(-wo.x, -wo.y, wo.z);
      float m5 = ggx_schlick(0.0f, wo.z);
      float3 f = b.metallic * (b.base + (1.0f - b.base) * m5) +
                 (1.0f - b.metallic) * ggx_schlick(WT_PBR_DIELECTRIC_F0, wo.z);
      s->weight = f / p_spec;
      s->pdf = 0.0f;
      s->lobe |= WT_LOBE_DELTA;
      return true;
    }
    float alpha = b.roughness * b.roughness;
    float hx, hy, hz;
    ggx_sample_visible_normal(wo.x, wo.y, wo.z, alpha, u1, u2, &hx, &hy, &hz);
    float3 h = (float3)(hx, hy, hz);
    s->wi = 2.0f * dot(wo, h) * h - wo;
  } else {
    if (!(lobes & WT_LOBE_DIFFUSE)) return false;
    s->lobe = WT_LOBE_DIFFUSE;
    s->wi = lambert_sample((float3)(0.0f, 0.0f, 1.0f), u1, u2);
  }
  if (s->wi.z <= 0.0f) return false;
  float3 f_cos = bsdf_eval(b, wo, s->wi, lobes, &s->pdf);
  if (!(s->pdf > 0.0f) || !(f_cos.x > 0.0f || f_cos.y > 0.0f || f_cos.z > 0.0f)) return false;
  s->weight = f_cos / s->pdf;
  return true;
}

#endif  // WT_MATERIALS_BSDF_CL
