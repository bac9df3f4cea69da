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
// KHR_materials_transmission turns a share `transmission` of the dielectric
// (what is not metal) into a rough dielectric interface (Walter et al.
// 2007: GGX reflection and refraction with the exact Fresnel term of index
// KHR_materials_ior, the refracted part tinted by the base colour): a
// volume boundary that bends light by the ratio of indices across it
// (KHR_materials_volume), or a thin wall that light crosses without
// bending (the glTF default without a volume), its reflection flipped to
// the far side. Radiance crossing into a denser medium is scaled by the
// squared index ratio, so a path in and out of a closed object carries none.
//
// Sampling picks the GGX lobe (visible normals, Heitz 2018), a cosine lobe
// or the interface (visible normals again, then reflection or transmission
// by Fresnel) with probabilities from the lobes' albedos, and every
// continuous sample is weighted by the mixture pdf of all three techniques
// (one-sample MIS over lobes). Below WT_PBR_MIN_ROUGHNESS the GGX lobe is a
// mirror and the interface smooth; so is a volume boundary of index 1,
// which transmits straight through at any roughness.
#ifndef WT_MATERIALS_BSDF_CL
#define WT_MATERIALS_BSDF_CL

#include "common.h"
#include "materials/lambert.cl"
#include "shared/materials.h"

#if !defined(WT_HAS_PBR) || !defined(WT_HAS_TRANSMISSION)
#error "WT_HAS_PBR / WT_HAS_TRANSMISSION are not defined: build options must come from kernelDefines()"
#endif

#define WT_LOBE_DIFFUSE 1u       ///< the Lambertian base (and any cosine-sampled direction)
#define WT_LOBE_SPECULAR 2u      ///< reflection: GGX, its multiple scattering, the mirror, the interface's reflection
#define WT_LOBE_DELTA 4u         ///< set on a sample: the direction came from a mirror or a smooth interface
#define WT_LOBE_TRANSMISSION 8u  ///< through the interface: refraction, or crossing a thin wall

/// A material at a shading point.
typedef struct Bsdf {
  uint model;        ///< WT_MATERIAL_*
  float3 base;       ///< base colour (albedo of the diffuse base, F0 of the metal, tint of transmission)
  float metallic;
  float roughness;   ///< perceptual; alpha = roughness^2
  int mirror;        ///< roughness below WT_PBR_MIN_ROUGHNESS
  float transmission;  ///< share of the dielectric that is the interface (0 without WT_HAS_TRANSMISSION)
  float eta;         ///< n(far side) / n(wo side) of a volume boundary; the index itself for a thin wall
  int thin;          ///< thin-walled: transmission does not bend
  int smooth;        ///< the interface is smooth (mirror roughness, or a volume boundary of index 1)
  __global const float* table;  ///< directional albedos (shared/materials.h)
} Bsdf;

/// The outcome of sampling a direction.
typedef struct BsdfSample {
  float3 wi;       ///< local frame, unit
  float3 weight;   ///< f |cos| / pdf: what the throughput is multiplied by
  float pdf;       ///< solid-angle pdf of the whole mixture; 0 for a delta sample
  uint lobe;       ///< WT_LOBE_DIFFUSE, _SPECULAR or _TRANSMISSION, | WT_LOBE_DELTA for a delta
} BsdfSample;

/// The BSDF of `m` seen from its front face (inside = 0) or from its back
/// face, inside the volume it bounds (inside = 1).
inline Bsdf bsdf_make(WtMaterial m, __global const float* table, int inside) {
  Bsdf b;
  b.model = m.model;
  b.base = vec4_xyz(m.base_color);
  b.metallic = m.base_color.w;
  b.roughness = m.roughness;
  b.mirror = m.roughness < WT_PBR_MIN_ROUGHNESS;
  b.transmission = (WT_HAS_TRANSMISSION && m.model == WT_MATERIAL_PBR) ? m.transmission : 0.0f;
  b.thin = m.volume.w == 0.0f;
  b.eta = (b.thin || !inside) ? m.ior : 1.0f / m.ior;
  b.smooth = b.mirror || (!b.thin && fabs(b.eta - 1.0f) < 1e-3f);
  b.table = table;
  return b;
}

/// Whether any light passes through (the far side needs lights and rays).
inline bool bsdf_transmits(Bsdf b) { return b.transmission > 0.0f && b.metallic < 1.0f; }

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

/// Probabilities of the three sampling techniques -- GGX reflection (or the
/// mirror), the cosine lobe, the interface -- from the lobes' albedos at wo
/// (ao = pbr_albedo(b, mu_o); unused for Lambertian materials), restricted
/// to the lobes allowed; all 0 when no allowed lobe reflects.
typedef struct Techniques {
  float specular, diffuse, interface;
} Techniques;

inline Techniques bsdf_techniques(Bsdf b, PbrAlbedo ao, uint lobes) {
  Techniques t = {0.0f, 0.0f, 0.0f};
  if (b.model != WT_MATERIAL_PBR) {
    t.diffuse = (lobes & WT_LOBE_DIFFUSE) ? 1.0f : 0.0f;
    return t;
  }
  float metal = b.metallic, opaque = (1.0f - b.metallic) * (1.0f - b.transmission),
        clear = (1.0f - b.metallic) * b.transmission;
  if (lobes & WT_LOBE_SPECULAR) t.specular = metal * ao.e + opaque * ao.e_coat;
  if (lobes & WT_LOBE_DIFFUSE)
    t.diffuse = metal * (1.0f - ao.e) + opaque * (1.0f - ao.e_coat) * bsdf_luminance(b.base);
  bool reflect = (lobes & WT_LOBE_SPECULAR) != 0u, through = (lobes & WT_LOBE_TRANSMISSION) != 0u;
  if (clear > 0.0f && (reflect || through))
    t.interface = clear * (reflect && through ? 1.0f
                                              : reflect ? ao.e_coat : (1.0f - ao.e_coat) * fmax(bsdf_luminance(b.base), 0.05f));
  float sum = t.specular + t.diffuse + t.interface;
  if (!(sum > 0.0f)) return (Techniques){0.0f, 0.0f, 0.0f};
  t.specular /= sum, t.diffuse /= sum, t.interface /= sum;
  return t;
}

/// Probability that the interface reflects rather than transmits, at
/// Fresnel reflectance f, restricted to the allowed lobes.
inline float interface_reflect_probability(float f, uint lobes) {
  bool reflect = (lobes & WT_LOBE_SPECULAR) != 0u, through = (lobes & WT_LOBE_TRANSMISSION) != 0u;
  return reflect && through ? f : (reflect ? 1.0f : 0.0f);
}

#if WT_HAS_TRANSMISSION
/// f |cos| of the rough interface for local wo (z > 0) and wi on either
/// side; *pdf: the density of its technique (visible normal, then Fresnel's
/// choice) producing wi.
inline float3 interface_eval(Bsdf b, float3 wo, float3 wi, uint lobes, float* pdf) {
  *pdf = 0.0f;
  float alpha = b.roughness * b.roughness;
  float3 h;
  bool refracted = false;
  if (wi.z > 0.0f) {
    if (!(lobes & WT_LOBE_SPECULAR)) return (float3)(0.0f);
    h = normalize(wo + wi);
  } else if (wi.z < 0.0f && (lobes & WT_LOBE_TRANSMISSION)) {
    if (b.thin) {
      h = normalize(wo + (float3)(wi.x, wi.y, -wi.z));  // the thin wall: its reflection, mirrored through the plane
    } else {
      h = wo + b.eta * wi;
      if (!(dot(h, h) > 0.0f)) return (float3)(0.0f);
      h = normalize(h);
      if (h.z < 0.0f) h = -h;
      refracted = true;
    }
  } else {
    return (float3)(0.0f);
  }
  float oh = dot(wo, h);
  if (!(oh > 0.0f)) return (float3)(0.0f);
  float f = ggx_fresnel_dielectric(oh, b.eta);
  float p_reflect = interface_reflect_probability(f, lobes);
  float d = ggx_d(h.x, h.y, h.z, alpha);
  float g1 = ggx_g1(wo.x, wo.y, wo.z, alpha);
  float g2 = ggx_g2(wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, alpha);  // Lambda depends on |cos| only
  if (!refracted) {
    // reflection, or the thin wall's mirrored reflection: D G F / (4 |cos o| |cos i|) |cos i|
    float share = wi.z > 0.0f ? f : 1.0f - f;
    *pdf = g1 * d / (4.0f * wo.z) * (wi.z > 0.0f ? p_reflect : 1.0f - p_reflect);
    float3 tint = wi.z > 0.0f ? (float3)(1.0f) : b.base;
    return tint * (share * d * g2 / (4.0f * wo.z));
  }
  float ih = dot(wi, h);
  if (!(ih < 0.0f)) return (float3)(0.0f);  // a microfacet facing away from wi
  float denom = oh + b.eta * ih;
  denom *= denom;
  // (1 - F) D G |o.h| |i.h| / (|cos o| |cos i| (o.h + eta i.h)^2) |cos i|, with
  // radiance scaled by 1 / eta^2 on the way
  *pdf = g1 * oh * d / wo.z * (b.eta * b.eta * -ih / denom) * (1.0f - p_reflect);
  return b.base * ((1.0f - f) * d * g2 * oh * -ih / (denom * wo.z));
}
#endif

/// f |cos| of the continuous part (no mirror, no smooth interface) for local
/// wo, wi, restricted to `lobes`; *pdf: the mixture's density of sampling wi.
inline float3 pbr_eval(Bsdf b, float3 wo, float3 wi, uint lobes, float* pdf) {
  *pdf = 0.0f;
  if (wo.z <= 0.0f || wi.z == 0.0f) return (float3)(0.0f);
  PbrAlbedo ao = pbr_albedo(b, wo.z);
  Techniques t = bsdf_techniques(b, ao, lobes);
  float3 f = (float3)(0.0f);
  float pdf_spec = 0.0f, pdf_diffuse = 0.0f, pdf_interface = 0.0f;
  float opaque = (1.0f - b.metallic) * (1.0f - b.transmission);
  if (wi.z > 0.0f) {
    PbrAlbedo ai = pbr_albedo(b, wi.z);
    if ((lobes & WT_LOBE_SPECULAR) && !b.mirror) {
      float alpha = b.roughness * b.roughness;
      float3 h = normalize(wo + wi);
      float oh = fmax(dot(wo, h), 0.0f);
      float d = ggx_d(h.x, h.y, h.z, alpha);
      float dv = d * ggx_g2(wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, alpha) / (4.0f * wo.z * wi.z);
      float m5 = ggx_schlick(0.0f, oh);  // (1 - oh)^5
      float3 f_metal = b.base + (1.0f - b.base) * m5;
      float f_coat = ggx_schlick(WT_PBR_DIELECTRIC_F0, oh);
      f += (b.metallic * f_metal + opaque * f_coat) * dv;
      // multiple scattering: (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), by the average Fresnel
      float e_avg = pbr_table_average(b.table, WT_PBR_TABLE_E_AVG, b.roughness);
      float ms = (1.0f - ao.e) * (1.0f - ai.e) / (WT_PI * fmax(1.0f - e_avg, 1e-6f));
      float3 f_avg_metal = b.base + (1.0f - b.base) / 21.0f;
      float3 fms_metal = f_avg_metal * f_avg_metal * e_avg / (1.0f - f_avg_metal * (1.0f - e_avg));
      float fms_coat = pbr_multiscatter_fresnel(ggx_schlick_average(WT_PBR_DIELECTRIC_F0), e_avg);
      f += (b.metallic * fms_metal + opaque * fms_coat) * ms;
      pdf_spec = ggx_g1(wo.x, wo.y, wo.z, alpha) * d / (4.0f * wo.z);
    }
    if (lobes & WT_LOBE_DIFFUSE) {
      float coat_avg = pbr_coat_average(b);
      f += opaque * b.base * (1.0f / WT_PI) * (1.0f - ao.e_coat) * (1.0f - ai.e_coat) /
           fmax(1.0f - coat_avg, 1e-6f);
      pdf_diffuse = wi.z / WT_PI;
    }
    f *= wi.z;
  }
#if WT_HAS_TRANSMISSION
  if (t.interface > 0.0f && !b.smooth)
    f += (1.0f - b.metallic) * b.transmission * interface_eval(b, wo, wi, lobes, &pdf_interface);
#endif
  *pdf = t.specular * pdf_spec + t.diffuse * pdf_diffuse + t.interface * pdf_interface;
  return f;
}

/// f |cos| of the continuous part for local wo, wi; *pdf as pbr_eval.
inline float3 bsdf_eval(Bsdf b, float3 wo, float3 wi, uint lobes, float* pdf) {
#if WT_HAS_PBR
  if (b.model == WT_MATERIAL_PBR) return pbr_eval(b, wo, wi, lobes, pdf);
#endif
  bool ok = (lobes & WT_LOBE_DIFFUSE) && wo.z > 0.0f && wi.z > 0.0f;
  *pdf = ok ? wi.z / WT_PI : 0.0f;
  return ok ? b.base * (wi.z / WT_PI) : (float3)(0.0f);
}

#if WT_HAS_TRANSMISSION
/// The interface's direction for a microfacet normal h: reflection, or
/// transmission (bent by eta, or through the thin wall) with probability 1 -
/// p_reflect; u picks. False under total internal reflection.
inline bool interface_direction(Bsdf b, float3 wo, float3 h, float p_reflect, float u, float3* wi, uint* lobe) {
  float oh = dot(wo, h);
  float3 r = 2.0f * oh * h - wo;
  if (u < p_reflect) {
    *wi = r;
    *lobe = WT_LOBE_SPECULAR;
    return true;
  }
  *lobe = WT_LOBE_TRANSMISSION;
  if (b.thin) {
    *wi = (float3)(r.x, r.y, -r.z);
    return true;
  }
  float sin2_t = (1.0f - oh * oh) / (b.eta * b.eta);
  if (sin2_t >= 1.0f) return false;
  float cos_t = sqrt(1.0f - sin2_t);
  *wi = normalize(-wo / b.eta + (oh / b.eta - cos_t) * h);
  return true;
}
#endif

/// Draw a direction for local wo with uniforms u_lobe, u1, u2. False when
/// nothing is scattered (no allowed lobe, a direction on the wrong side).
inline bool bsdf_sample(Bsdf b, float3 wo, uint lobes, float u_lobe, float u1, float u2, BsdfSample* s) {
  if (wo.z <= 0.0f || !(lobes & (WT_LOBE_DIFFUSE | WT_LOBE_SPECULAR | WT_LOBE_TRANSMISSION))) return false;
  PbrAlbedo ao = {1.0f, 1.0f};
  if (b.model == WT_MATERIAL_PBR) ao = pbr_albedo(b, wo.z);
  Techniques t = bsdf_techniques(b, ao, lobes);
  if (u_lobe < t.specular) {
    s->lobe = WT_LOBE_SPECULAR;
    if (b.mirror) {
      // the mirror: F at mu_o, over the probability of having picked it
      s->wi = (float3)(-wo.x, -wo.y, wo.z);
      float m5 = ggx_schlick(0.0f, wo.z);
      float3 f = b.metallic * (b.base + (1.0f - b.base) * m5) +
                 (1.0f - b.metallic) * (1.0f - b.transmission) * ggx_schlick(WT_PBR_DIELECTRIC_F0, wo.z);
      s->weight = f / t.specular;
      s->pdf = 0.0f;
      s->lobe |= WT_LOBE_DELTA;
      return true;
    }
    float alpha = b.roughness * b.roughness;
    float hx, hy, hz;
    ggx_sample_visible_normal(wo.x, wo.y, wo.z, alpha, u1, u2, &hx, &hy, &hz);
    float3 h = (float3)(hx, hy, hz);
    s->wi = 2.0f * dot(wo, h) * h - wo;
  } else if (u_lobe < t.specular + t.interface) {
#if WT_HAS_TRANSMISSION
    float u = fmin((u_lobe - t.specular) / t.interface, 0x1.fffffep-1f);  // reused for reflect or transmit
    float clear = (1.0f - b.metallic) * b.transmission;
    if (b.smooth) {
      float f = ggx_fresnel_dielectric(wo.z, b.eta);
      float p_reflect = interface_reflect_probability(f, lobes);
      if (!interface_direction(b, wo, (float3)(0.0f, 0.0f, 1.0f), p_reflect, u, &s->wi, &s->lobe)) return false;
      float3 w = s->lobe == WT_LOBE_SPECULAR
                     ? (float3)(f / p_reflect)
                     : b.base * ((1.0f - f) / ((b.thin ? 1.0f : b.eta * b.eta) * (1.0f - p_reflect)));
      s->weight = w * (clear / t.interface);
      s->pdf = 0.0f;
      s->lobe |= WT_LOBE_DELTA;
      return s->weight.x > 0.0f || s->weight.y > 0.0f || s->weight.z > 0.0f;
    }
    float alpha = b.roughness * b.roughness;
    float hx, hy, hz;
    ggx_sample_visible_normal(wo.x, wo.y, wo.z, alpha, u1, u2, &hx, &hy, &hz);
    float3 h = (float3)(hx, hy, hz);
    float p_reflect = interface_reflect_probability(ggx_fresnel_dielectric(dot(wo, h), b.eta), lobes);
    if (!interface_direction(b, wo, h, p_reflect, u, &s->wi, &s->lobe)) return false;
#else
    return false;
#endif
  } else {
    if (!(lobes & WT_LOBE_DIFFUSE) || !(t.diffuse > 0.0f)) return false;
    s->lobe = WT_LOBE_DIFFUSE;
    s->wi = lambert_sample((float3)(0.0f, 0.0f, 1.0f), u1, u2);
  }
  // reflection stays on wo's side, transmission crosses
  if ((s->lobe & WT_LOBE_TRANSMISSION) ? !(s->wi.z < 0.0f) : !(s->wi.z > 0.0f)) return false;
  float3 f_cos = bsdf_eval(b, wo, s->wi, lobes, &s->pdf);
  if (!(s->pdf > 0.0f) || !(f_cos.x > 0.0f || f_cos.y > 0.0f || f_cos.z > 0.0f)) return false;
  s->weight = f_cos / s->pdf;
  return true;
}

#endif  // WT_MATERIALS_BSDF_CL
