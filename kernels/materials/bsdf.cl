// The surface BSDF: Lambertian (scenes made in code) or glTF 2.0
// metallic-roughness with its layers, evaluated and sampled in the local
// shading frame (z along the shading normal), restricted to the lobes a path
// may still use (per-lobe bounce limits).
//
// Metallic-roughness follows the glTF specification's appendix B -- a GGX
// specular lobe (height-correlated Smith masking, Schlick Fresnel with the
// dielectric's F0 and the base colour for metals) over a Lambertian base,
// mixed by metallic -- with two corrections for energy conservation: the
// multiple-scattering lobe of Kulla and Conty 2017 restores what single
// scattering loses at high roughness, and the base under the dielectric's
// specular lobe is weighted by what that lobe leaves, (1 - E_spec(mu_o)) (1 -
// E_spec(mu_i)) / (1 - E_spec_avg) per channel, instead of the
// specification's (1 - F(v.h)), which gains energy at grazing angles.
//
// The dielectric's Fresnel term is specular (F0 + (1 - F0)(1 - v.h)^5) with
// F0 = min(((ior - 1) / (ior + 1))^2 specularColor, 1) per channel
// (KHR_materials_specular and _ior; 0.04 and specular 1 without them).
// Schlick's albedo is linear in F0 and F90 (the split sum), so E_spec(mu) =
// specular (F0 E + (1 - F0) S + F_ms (1 - E)) comes from two tables, E (F =
// 1) and S (F = (1 - v.h)^5), for every F0 exactly. Specular 0 leaves the
// Lambertian base / pi. A white material reflects exactly what arrives, at
// every roughness, angle and F0 (tests/kernels/test_bsdf.cpp).
//
// KHR_materials_transmission turns a share `transmission` of the dielectric
// (what is not metal) into a rough dielectric interface (Walter et al.
// 2007: GGX reflection and refraction with the exact Fresnel term of index
// KHR_materials_ior, weighted by specular except under total internal
// reflection; the refracted part tinted by the base colour): a volume
// boundary that bends light by the ratio of indices across it
// (KHR_materials_volume), or a thin wall that light crosses without
// bending (the glTF default without a volume), its reflection flipped to
// the far side. Radiance crossing into a denser medium is scaled by the
// squared index ratio, so a path in and out of a closed object carries none.
//
// Two layers lie over that base on its outside (not seen from inside a
// volume), the clear coat above the sheen as the extensions order them:
//
//   f = clearcoat f_coat + w_coat(mu_o) [ f_sheen + w_sheen(mu_o) f_base ]
//
// f_coat: KHR_materials_clearcoat, GGX of its own roughness with Schlick's
// F0 0.04 (single scattering). f_sheen: KHR_materials_sheen, sheenColor
// times the Charlie distribution with Estevez and Kulla's visibility
// (shared/sheen.h). Each layer leaves those below it what it does not
// reflect towards the viewer: w_coat = 1 - clearcoat E_coat(mu_o), w_sheen
// = 1 - max(sheenColor) E_sheen(mu_o), E the layer's tabulated albedo. That
// is the albedo in place of clearcoat's F(n.v) and the view-only form the
// sheen extension allows: a white lossless base under any layers then
// reflects exactly 1, where the reciprocal product (1 - E(mu_o))(1 -
// E(mu_i)) / (1 - E_avg) used for the diffuse base gains energy over a
// specular base (4.8% over a white mirror under a smooth coat at normal
// incidence) and the sheen's reciprocal min form loses some of a diffuse
// one (docs/materials.md). The layered BSDF is therefore not reciprocal,
// which a path tracer that always evaluates from the viewer's side does
// not need. KHR_materials_unlit needs nothing here: the loader makes it a
// black Lambertian emitter of its base colour.
//
// Sampling picks the coat's GGX lobe, the base's GGX lobe (visible normals,
// Heitz 2018 for both), the interface (visible normals again, then
// reflection or transmission by Fresnel) or a cosine lobe (the diffuse base
// and the sheen) with probabilities from the lobes' albedos at wo (the
// dielectric's by single scattering: no averages to look up), and every
// continuous sample is weighted by the mixture pdf of all techniques
// (one-sample MIS over lobes). Below WT_PBR_MIN_ROUGHNESS the GGX lobes are
// mirrors (a mirror coat over a mirror base: one delta, both lobes' weights)
// and the interface smooth; so is a volume boundary of index 1, which
// transmits straight through at any roughness. The clear coat, the sheen
// and a dielectric F0 other than 0.04 are compiled in only for scenes that
// use them (WT_HAS_CLEARCOAT, WT_HAS_SHEEN, WT_HAS_SPECULAR).
//
// KHR_materials_anisotropy (WT_HAS_ANISOTROPY) makes the base's GGX
// reflection anisotropic: alpha_t = mix(alpha, 1, strength^2) along the
// local x axis (shade turns the frame to the anisotropy direction), alpha_b
// = alpha along y. Its energy compensation and the base's share read the
// anisotropic albedo tables at the view's azimuth (shared/materials.h,
// docs/materials.md, "Anisotropy").
//
// KHR_materials_iridescence (WT_HAS_IRIDESCENCE) puts a thin film on the
// base's reflection lobe: its Fresnel (metal and dielectric) is mixed with
// the film's (shared/iridescence.h) by the iridescence factor, and the
// diffuse base under it keeps (1 - max F_film(mu_o)) (1 - max F_film(mu_i))
// in that share (the extension's rgb_mix, made reciprocal and bounded);
// the film's share scatters once (docs/materials.md, "Iridescence").
#ifndef WT_MATERIALS_BSDF_CL
#define WT_MATERIALS_BSDF_CL

#include "common.h"
#include "materials/lambert.cl"
#include "shared/materials.h"
#include "shared/sheen.h"
#if WT_HAS_IRIDESCENCE
#include "shared/iridescence.h"
#endif

#define WT_LOBE_DIFFUSE 1u       ///< the Lambertian base and the sheen (any cosine-sampled direction)
#define WT_LOBE_SPECULAR 2u      ///< reflection: GGX (base and clear coat), its multiple scattering, the mirrors, the interface's reflection
#define WT_LOBE_DELTA 4u         ///< set on a sample: the direction came from a mirror or a smooth interface
#define WT_LOBE_TRANSMISSION 8u  ///< through the interface: refraction, or crossing a thin wall

/// The dielectric's Fresnel quantities (F0, its albedos): per channel where
/// KHR_materials_specular may tint F0, one float otherwise (0.04 is grey),
/// so scenes without the extension pay nothing for the colour.
#if WT_HAS_SPECULAR
typedef float3 DielectricColor;
#define dielectric_luminance(c) bsdf_luminance(c)
#else
typedef float DielectricColor;
#define dielectric_luminance(c) (c)
#endif

inline float bsdf_luminance(float3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

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
  DielectricColor f0;  ///< the dielectric's F0, min(((ior-1)/(ior+1))^2 specularColor, 1) (0.04 without WT_HAS_SPECULAR)
  float specular;    ///< weight of the dielectric's whole Fresnel term (1 without WT_HAS_SPECULAR)
  float clearcoat;   ///< weight of the clear coat (0 without WT_HAS_CLEARCOAT, and inside a volume)
  float clearcoat_roughness;  ///< perceptual; alpha = roughness^2
  int clearcoat_mirror;       ///< a coat whose roughness is below WT_PBR_MIN_ROUGHNESS
#if WT_HAS_CLEARCOAT
  float3 coat_t, coat_b, coat_n;  ///< the coat's own frame in the local one (clearcoatNormalTexture); else the local axes
#endif
  float3 sheen;      ///< sheen colour (0 without WT_HAS_SHEEN, and inside a volume)
  float sheen_roughness;  ///< clamped to [WT_SHEEN_MIN_ROUGHNESS, 1]; alpha = roughness^2
  SheenFit sheen_fit;     ///< its visibility's Lambda fit, once per material
#if WT_HAS_ANISOTROPY
  float alpha_t;          ///< the base's GGX alpha along the local x axis (the anisotropy direction)
  float alpha_b;          ///< and along y; alpha_t == alpha_b: isotropic, alpha = roughness^2
  float aniso_r, aniso_k;  ///< the anisotropic tables' (r_b, k) coordinates of the lobe (pbr_aniso_coords)
#endif
#if WT_HAS_IRIDESCENCE
  float iridescence;      ///< the film's share of the base's Fresnel (0: no film, and inside a volume)
  float film_ior;         ///< the film's index
  float film_thickness;   ///< nm (> 0 where iridescence > 0)
#endif
  __global const float* table;  ///< directional albedos (shared/materials.h)
} Bsdf;

/// The base's GGX lobe (reflection, metal and dielectric): its
/// distribution, masking and visible-normal sampling, anisotropic where
/// KHR_materials_anisotropy makes alpha_t differ from alpha_b (an isotropic
/// lobe runs the isotropic code, so strength 0 is exactly the old lobe).
inline float base_ggx_d(Bsdf b, float3 h) {
#if WT_HAS_ANISOTROPY
  if (b.alpha_t != b.alpha_b) return ggx_d_aniso(h.x, h.y, h.z, b.alpha_t, b.alpha_b);
#endif
  return ggx_d(h.x, h.y, h.z, b.roughness * b.roughness);
}

inline float base_ggx_g1(Bsdf b, float3 v) {
#if WT_HAS_ANISOTROPY
  if (b.alpha_t != b.alpha_b) return ggx_g1_aniso(v.x, v.y, v.z, b.alpha_t, b.alpha_b);
#endif
  return ggx_g1(v.x, v.y, v.z, b.roughness * b.roughness);
}

inline float base_ggx_g2(Bsdf b, float3 o, float3 i) {
#if WT_HAS_ANISOTROPY
  if (b.alpha_t != b.alpha_b) return ggx_g2_aniso(o.x, o.y, o.z, i.x, i.y, i.z, b.alpha_t, b.alpha_b);
#endif
  return ggx_g2(o.x, o.y, o.z, i.x, i.y, i.z, b.roughness * b.roughness);
}

inline float3 base_ggx_sample(Bsdf b, float3 wo, float u1, float u2) {
  float hx, hy, hz;
#if WT_HAS_ANISOTROPY
  ggx_sample_visible_normal_aniso(wo.x, wo.y, wo.z, b.alpha_t, b.alpha_b, u1, u2, &hx, &hy, &hz);
#else
  float alpha = b.roughness * b.roughness;
  ggx_sample_visible_normal(wo.x, wo.y, wo.z, alpha, u1, u2, &hx, &hy, &hz);
#endif
  return (float3)(hx, hy, hz);
}

#if WT_HAS_CLEARCOAT
/// Local direction w in the coat's frame (its normal along z).
inline float3 coat_local(Bsdf b, float3 w) { return (float3)(dot(w, b.coat_t), dot(w, b.coat_b), dot(w, b.coat_n)); }

/// Whether the coat has a normal of its own, apart from the shading normal.
inline bool coat_apart(Bsdf b) { return b.coat_n.z < 1.0f; }

/// KHR_materials_clearcoat's clearcoatNormalTexture: the coat's GGX lobe
/// (its albedo, distribution, masking, Fresnel and sampling) about local
/// normal n instead of the shading normal; the base and the sheen keep
/// theirs. The coat is a closure of its own, as in Cycles and the glTF
/// specification's clearcoat_brdf: its cosines are to its own normal.
inline void bsdf_coat_normal(Bsdf* b, float3 n) {
  float len = length(n);
  if (!(len > 0.0f) || !isfinite(len)) return;
  n /= len;
  if (n.z >= 1.0f) return;
  b->coat_n = n;
  frame_from_normal(n, &b->coat_t, &b->coat_b);
}
#endif

/// The outcome of sampling a direction.
typedef struct BsdfSample {
  float3 wi;       ///< local frame, unit
  float3 weight;   ///< f |cos| / pdf: what the throughput is multiplied by
  float pdf;       ///< solid-angle pdf of the whole mixture; 0 for a delta sample
  uint lobe;       ///< WT_LOBE_DIFFUSE, _SPECULAR or _TRANSMISSION, | WT_LOBE_DELTA for a delta
} BsdfSample;

inline bool bsdf_has_sheen(Bsdf b) { return WT_HAS_SHEEN && (b.sheen.x > 0.0f || b.sheen.y > 0.0f || b.sheen.z > 0.0f); }

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
  b.f0 = (DielectricColor)(WT_PBR_DIELECTRIC_F0);
  b.specular = 1.0f;
  b.clearcoat = 0.0f;
  b.clearcoat_roughness = 1.0f;
  b.clearcoat_mirror = 0;
#if WT_HAS_CLEARCOAT
  b.coat_t = (float3)(1.0f, 0.0f, 0.0f);
  b.coat_b = (float3)(0.0f, 1.0f, 0.0f);
  b.coat_n = (float3)(0.0f, 0.0f, 1.0f);
#endif
  b.sheen = (float3)(0.0f);
  b.sheen_roughness = 1.0f;
  b.sheen_fit = (SheenFit){0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  bool pbr = m.model == WT_MATERIAL_PBR;
#if WT_HAS_ANISOTROPY
  b.alpha_t = b.alpha_b = m.roughness * m.roughness;
  b.aniso_r = b.aniso_k = 0.0f;
  if (pbr && m.anisotropy > 0.0f) {
    float alpha_t, alpha_b;
    ggx_anisotropy_alphas(m.roughness, fmin(m.anisotropy, 1.0f), &alpha_t, &alpha_b);
    // a lobe stretched past the mirror threshold along t is no longer a mirror
    // (the interface keeps the isotropic roughness: the extension shapes reflection)
    if (alpha_t >= WT_GGX_MIN_ALPHA) {
      b.alpha_t = alpha_t;
      b.alpha_b = fmax(alpha_b, WT_GGX_MIN_ALPHA);
      b.mirror = 0;
      pbr_aniso_coords(b.alpha_t, b.alpha_b, &b.aniso_r, &b.aniso_k);
    }
  }
#endif
#if WT_HAS_SPECULAR
  if (pbr) {
    float r = (m.ior - 1.0f) / (m.ior + 1.0f);
    b.f0 = fmin(r * r * vec4_xyz(m.specular), (float3)(1.0f));
    b.specular = m.specular.w;
  }
#endif
  // the layers lie on the outside: a ray inside a volume meets the interface first
  bool outside = !inside || b.thin;
#if WT_HAS_CLEARCOAT
  if (pbr && outside && m.clearcoat > 0.0f) {
    b.clearcoat = m.clearcoat;
    b.clearcoat_roughness = m.clearcoat_roughness;
    b.clearcoat_mirror = m.clearcoat_roughness < WT_PBR_MIN_ROUGHNESS;
  }
#endif
#if WT_HAS_IRIDESCENCE
  b.iridescence = 0.0f;
  b.film_ior = 1.0f;
  b.film_thickness = 0.0f;
  // a film of no thickness is no film: the formula would not give the base's
  // Fresnel back there (docs/materials.md, "Iridescence")
  if (pbr && outside && m.iridescence.x > 0.0f && m.iridescence.w > 0.0f && m.iridescence.y > 0.0f) {
    b.iridescence = fmin(m.iridescence.x, 1.0f);
    b.film_ior = m.iridescence.y;
    b.film_thickness = m.iridescence.w;
  }
#endif
#if WT_HAS_SHEEN
  if (pbr && outside) {
    b.sheen = vec4_xyz(m.sheen);
    b.sheen_roughness = fmin(fmax(m.sheen.w, WT_SHEEN_MIN_ROUGHNESS), 1.0f);
    if (bsdf_has_sheen(b)) b.sheen_fit = sheen_fit(b.sheen_roughness * b.sheen_roughness);
  }
#endif
  return b;
}

/// Whether any light passes through (the far side needs lights and rays).
inline bool bsdf_transmits(Bsdf b) { return b.transmission > 0.0f && b.metallic < 1.0f; }

#if WT_HAS_IRIDESCENCE
/// The film's Fresnel at cos `oh` over a base of F0 `f0` (air outside).
inline float3 bsdf_film_fresnel(Bsdf b, float3 f0, float oh) {
  float f[3];
  iridescence_fresnel(1.0f, b.film_ior, f0.x, f0.y, f0.z, b.film_thickness, oh, f);
  return (float3)(f[0], f[1], f[2]);
}

/// The dielectric's film Fresnel: over F0 specular f0 (the extension's
/// iridescent_dielectric_layer with KHR_materials_specular).
inline float3 bsdf_film_dielectric(Bsdf b, float oh, float opaque) {
  return opaque > 0.0f ? bsdf_film_fresnel(b, (float3)(b.specular * b.f0), oh) : (float3)(0.0f);
}

/// The base's reflection Fresnel `f_spec` (metal and dielectric, already
/// weighted by metallic and `opaque`) with the film's share iridescence:
/// mix(f_spec, metallic F_film(base) + opaque film_dielectric, iridescence).
inline float3 bsdf_iridescent_fresnel(Bsdf b, float oh, float3 f_spec, float opaque, float3 film_dielectric) {
  float3 f_metal = b.metallic > 0.0f ? bsdf_film_fresnel(b, b.base, oh) : (float3)(0.0f);
  return mix(f_spec, b.metallic * f_metal + opaque * film_dielectric, b.iridescence);
}
#endif

/// GGX albedos at a cosine for a roughness (a mirror below
/// WT_PBR_MIN_ROUGHNESS): E with F = 1 and S with F = (1 - v.h)^5.
inline float2 pbr_moments(__global const float* table, float mu, float roughness) {
  if (roughness < WT_PBR_MIN_ROUGHNESS) return (float2)(1.0f, ggx_schlick(0.0f, mu));
  return (float2)(pbr_table_albedo(table, WT_PBR_TABLE_E, mu, roughness),
                  pbr_table_albedo(table, WT_PBR_TABLE_S, mu, roughness));
}

/// The base's GGX albedos (E, S) towards local direction w (z > 0): the
/// isotropic tables at mu, or an anisotropic lobe's at mu and w's azimuth.
inline float2 base_moments(Bsdf b, float3 w) {
#if WT_HAS_ANISOTROPY
  if (b.alpha_t != b.alpha_b)
    return (float2)(pbr_aniso_albedo(b.table, WT_PBR_TABLE_ANISO_E, w.x, w.y, w.z, b.alpha_t, b.alpha_b, b.aniso_r, b.aniso_k),
                    pbr_aniso_albedo(b.table, WT_PBR_TABLE_ANISO_S, w.x, w.y, w.z, b.alpha_t, b.alpha_b, b.aniso_r, b.aniso_k));
#endif
  return pbr_moments(b.table, w.z, b.roughness);
}

/// The hemispherical averages of the base's E (s = 0) or S (s = 1); 1 and
/// 1/21 for a mirror.
inline float base_average(Bsdf b, int s) {
  if (b.mirror) return s ? 1.0f / 21.0f : 1.0f;
#if WT_HAS_ANISOTROPY
  if (b.alpha_t != b.alpha_b)
    return pbr_aniso_average(b.table, s ? WT_PBR_TABLE_ANISO_S_AVG : WT_PBR_TABLE_ANISO_E_AVG, b.aniso_r, b.aniso_k);
#endif
  return pbr_table_average(b.table, s ? WT_PBR_TABLE_S_AVG : WT_PBR_TABLE_E_AVG, b.roughness);
}

/// Kulla and Conty's Fresnel of the multiple-scattering lobe, per channel.
inline float3 pbr_multiscatter_fresnel3(float3 f_avg, float e_avg) {
  return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

/// The same for the dielectric's F0.
inline DielectricColor pbr_dielectric_multiscatter(DielectricColor f_avg, float e_avg) {
  return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

/// The dielectric's specular albedo from the moments (E, S) at a cosine and
/// its multiple-scattering Fresnel: single scattering by the split sum, and
/// the multiple-scattering lobe's share of what single scattering lost.
inline DielectricColor pbr_dielectric_albedo(Bsdf b, float2 es, DielectricColor fms) {
  return b.specular * (b.f0 * es.x + (1.0f - b.f0) * es.y + fms * (1.0f - es.x));
}

/// What the PBR model needs from wo alone to pick a technique (the
/// averages and multiple scattering wait for evaluation: looked up for every
/// view they were a visible share of a render, docs/materials.md, "Cost").
typedef struct PbrView {
  float e;          ///< GGX albedo at mu_o, F = 1
  float s;          ///< GGX albedo at mu_o, F = (1 - v.h)^5
  DielectricColor spec_ss;  ///< the dielectric's single-scattering albedo at mu_o
  float coat;       ///< clearcoat x the coat's albedo at mu_o
  float sheen;      ///< the sheen lobe's albedo at mu_o, colour 1
  float sheen_lambda_o;  ///< the sheen's Lambda at mu_o
  float w_coat;     ///< 1 - coat: what the coat leaves to the sheen and the base
  float w_base;     ///< w_coat (1 - max(sheen colour) sheen): what both layers leave to the base
} PbrView;

/// The view of a Lambertian material (no layers; nothing else is read).
inline PbrView pbr_view_none(void) {
  PbrView v;
  v.e = v.s = v.coat = v.sheen = v.sheen_lambda_o = 0.0f;
  v.spec_ss = (DielectricColor)(0.0f);
  v.w_coat = v.w_base = 1.0f;
  return v;
}

// Inlined, pbr_view's result stays in memory in pbr_eval, and LLVM marks
// it with llvm.experimental.noalias.scope.decl, which Oclgrind does not
// define (tests/oclgrind/noalias_scope.cl): under Oclgrind it is called.
#if WT_NO_SRET_INLINE
__attribute__((noinline))
#endif
inline PbrView pbr_view(Bsdf b, float3 wo) {
  PbrView v;
  float mu = wo.z;
  float2 es = base_moments(b, wo);
  v.e = es.x, v.s = es.y;
  v.spec_ss = pbr_dielectric_albedo(b, es, (DielectricColor)(0.0f));
  v.coat = v.sheen = v.sheen_lambda_o = 0.0f;
#if WT_HAS_CLEARCOAT
  float mu_coat = coat_local(b, wo).z;  // the coat's albedo at its own normal
  if (b.clearcoat > 0.0f && mu_coat > 0.0f) {
    float2 c = pbr_moments(b.table, mu_coat, b.clearcoat_roughness);
    v.coat = b.clearcoat * (WT_PBR_DIELECTRIC_F0 * c.x + (1.0f - WT_PBR_DIELECTRIC_F0) * c.y);
  }
#endif
  v.w_coat = v.w_base = 1.0f - v.coat;
#if WT_HAS_SHEEN
  if (bsdf_has_sheen(b)) {
    v.sheen = pbr_table_sheen(b.table, mu, b.sheen_roughness);
    v.sheen_lambda_o = sheen_lambda(b.sheen_fit, mu);
    v.w_base *= 1.0f - fmax(b.sheen.x, fmax(b.sheen.y, b.sheen.z)) * v.sheen;
  }
#endif
  return v;
}

/// Probabilities of the sampling techniques -- the base's GGX reflection
/// (or its mirror), the cosine lobe (diffuse base and sheen), the
/// interface, the coat's GGX reflection (or its mirror) -- from the lobes'
/// albedos at wo (the view v; unused for Lambertian materials), restricted
/// to the lobes allowed; all 0 when no allowed lobe reflects.
typedef struct Techniques {
  float specular, diffuse, interface, clearcoat, sheen;
} Techniques;

inline Techniques bsdf_techniques(Bsdf b, PbrView v, uint lobes) {
  Techniques t = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  if (b.model != WT_MATERIAL_PBR) {
    t.diffuse = (lobes & WT_LOBE_DIFFUSE) ? 1.0f : 0.0f;
    return t;
  }
  float metal = b.metallic, opaque = (1.0f - b.metallic) * (1.0f - b.transmission),
        clear = (1.0f - b.metallic) * b.transmission;
  bool reflect = (lobes & WT_LOBE_SPECULAR) != 0u, through = (lobes & WT_LOBE_TRANSMISSION) != 0u;
  float spec = dielectric_luminance(v.spec_ss);
  if (reflect) t.specular = v.w_base * (metal * v.e + opaque * spec);
  if (lobes & WT_LOBE_DIFFUSE) {
    t.diffuse = v.w_base * (metal * (1.0f - v.e) + opaque * bsdf_luminance((1.0f - v.spec_ss) * b.base));
    t.sheen = v.w_coat * bsdf_luminance(b.sheen) * v.sheen;
  }
  if (clear > 0.0f && (reflect || through))
    t.interface = v.w_base * clear *
                  (reflect && through ? 1.0f : reflect ? spec : (1.0f - spec) * fmax(bsdf_luminance(b.base), 0.05f));
  if (reflect) t.clearcoat = v.coat;
  float sum = t.specular + t.diffuse + t.interface + t.clearcoat + t.sheen;
  if (!(sum > 0.0f)) return (Techniques){0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  t.specular /= sum, t.diffuse /= sum, t.interface /= sum, t.clearcoat /= sum, t.sheen /= sum;
  return t;
}

/// Probability that the interface reflects rather than transmits, at
/// Fresnel reflectance f, restricted to the allowed lobes.
inline float interface_reflect_probability(float f, uint lobes) {
  bool reflect = (lobes & WT_LOBE_SPECULAR) != 0u, through = (lobes & WT_LOBE_TRANSMISSION) != 0u;
  return reflect && through ? f : (reflect ? 1.0f : 0.0f);
}

/// The interface's reflectance at cos(theta) on wo's side: the exact
/// Fresnel term weighted by specular, but all of it under total internal
/// reflection (where nothing could be transmitted instead).
inline float interface_fresnel(Bsdf b, float cos_i) {
  float f = ggx_fresnel_dielectric(cos_i, b.eta);
  return f >= 1.0f ? 1.0f : b.specular * f;
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
  float f = interface_fresnel(b, oh);
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
  PbrView v = pbr_view(b, wo);
  Techniques t = bsdf_techniques(b, v, lobes);
  float3 f = (float3)(0.0f);       // the base, before the layers above take their share
  float3 f_layers = (float3)(0.0f);  // the coat and the sheen
  float pdf_spec = 0.0f, pdf_diffuse = 0.0f, pdf_interface = 0.0f, pdf_coat = 0.0f;
  float opaque = (1.0f - b.metallic) * (1.0f - b.transmission);
  if (wi.z > 0.0f) {
    float3 h = normalize(wo + wi);
    float oh = fmax(dot(wo, h), 0.0f);
    float m5 = ggx_schlick(0.0f, oh);  // (1 - oh)^5
    float2 es_i = base_moments(b, wi);
    float e_avg = base_average(b, 0);
    DielectricColor fms = pbr_dielectric_multiscatter(b.f0 + (1.0f - b.f0) / 21.0f, e_avg);
#if WT_HAS_IRIDESCENCE
    // the film's share of the base's Fresnel and, for the diffuse, max(F_film) at oh
    float film_keep = 1.0f;  // the multiple scattering's and the layered diffuse's share
    float film_diffuse = 0.0f;
    float3 film_dielectric = (float3)(0.0f);
    if (b.iridescence > 0.0f) {
      film_keep = 1.0f - b.iridescence;
      film_dielectric = bsdf_film_dielectric(b, oh, opaque);
      if (lobes & WT_LOBE_DIFFUSE) {
        // the extension's rgb_mix reads F at the half vector, which gains
        // energy at grazing wo; 1 - max F at mu_o and at mu_i does not
        float3 fo = bsdf_film_dielectric(b, wo.z, opaque), fi = bsdf_film_dielectric(b, wi.z, opaque);
        film_diffuse = b.iridescence * (1.0f - fmin(fmax(fmax(fo.x, fo.y), fo.z), 1.0f)) *
                       (1.0f - fmin(fmax(fmax(fi.x, fi.y), fi.z), 1.0f));
      }
    }
#endif
    if ((lobes & WT_LOBE_SPECULAR) && !b.mirror) {
      float d = base_ggx_d(b, h);
      float dv = d * base_ggx_g2(b, wo, wi) / (4.0f * wo.z * wi.z);
      float3 f_metal = b.base + (1.0f - b.base) * m5;
      DielectricColor f_dielectric = b.specular * (b.f0 + (1.0f - b.f0) * m5);
#if WT_HAS_IRIDESCENCE
      if (b.iridescence > 0.0f) {
        f += bsdf_iridescent_fresnel(b, oh, b.metallic * f_metal + opaque * f_dielectric, opaque, film_dielectric) * dv;
      } else {
        f += (b.metallic * f_metal + opaque * f_dielectric) * dv;
      }
#else
      f += (b.metallic * f_metal + opaque * f_dielectric) * dv;
#endif
      // multiple scattering: (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), by the average Fresnel
      {
        float ms = (1.0f - v.e) * (1.0f - es_i.x) / (WT_PI * fmax(1.0f - e_avg, 1e-6f));
#if WT_HAS_IRIDESCENCE
        ms *= film_keep;  // the film's share scatters once
#endif
        float3 fms_metal = pbr_multiscatter_fresnel3(b.base + (1.0f - b.base) / 21.0f, e_avg);
        f += (b.metallic * fms_metal + opaque * b.specular * fms) * ms;
      }
      pdf_spec = base_ggx_g1(b, wo) * d / (4.0f * wo.z);
    }
    if (lobes & WT_LOBE_DIFFUSE) {
      // what the specular lobe (with its multiple scattering) leaves, both ways, over its average
      float s_avg = base_average(b, 1);
      DielectricColor spec_avg = b.specular * (b.f0 * e_avg + (1.0f - b.f0) * s_avg + fms * (1.0f - e_avg));
      DielectricColor spec_o = pbr_dielectric_albedo(b, (float2)(v.e, v.s), fms);
      DielectricColor spec_i = pbr_dielectric_albedo(b, es_i, fms);
#if WT_HAS_IRIDESCENCE
      if (b.iridescence > 0.0f) {
        // the extension's rgb_mix: the base under the film keeps 1 - max(F_film(oh))
        f += opaque * b.base * ((1.0f / WT_PI) * (film_keep * (1.0f - spec_o) * (1.0f - spec_i) / fmax(1.0f - spec_avg, 1e-6f) + film_diffuse));
      } else {
        f += opaque * b.base * ((1.0f / WT_PI) * (1.0f - spec_o) * (1.0f - spec_i) / fmax(1.0f - spec_avg, 1e-6f));
      }
#else
      f += opaque * b.base * ((1.0f / WT_PI) * (1.0f - spec_o) * (1.0f - spec_i) / fmax(1.0f - spec_avg, 1e-6f));
#endif
      pdf_diffuse = wi.z / WT_PI;
    }
    f *= wi.z;
#if WT_HAS_CLEARCOAT
    // D G F / (4 mu_o mu_i) mu_i, F0 0.04, in the coat's frame
    float3 wo_c = coat_local(b, wo), wi_c = coat_local(b, wi), h_c = coat_local(b, h);
    if ((lobes & WT_LOBE_SPECULAR) && b.clearcoat > 0.0f && !b.clearcoat_mirror && wo_c.z > 0.0f && wi_c.z > 0.0f) {
      float alpha = b.clearcoat_roughness * b.clearcoat_roughness;
      float d = ggx_d(h_c.x, h_c.y, h_c.z, alpha);
      float g2 = ggx_g2(wo_c.x, wo_c.y, wo_c.z, wi_c.x, wi_c.y, wi_c.z, alpha);
      f_layers += b.clearcoat * ggx_schlick(WT_PBR_DIELECTRIC_F0, oh) * d * g2 / (4.0f * wo_c.z);
      pdf_coat = ggx_g1(wo_c.x, wo_c.y, wo_c.z, alpha) * d / (4.0f * wo_c.z);
    }
#endif
#if WT_HAS_SHEEN
    if ((lobes & WT_LOBE_DIFFUSE) && bsdf_has_sheen(b)) {
      // D / (4 mu_o (1 + Lambda(o) + Lambda(i))), under the coat
      float alpha = b.sheen_roughness * b.sheen_roughness;
      float fibres = sheen_d(h.z, alpha) / (4.0f * wo.z * (1.0f + v.sheen_lambda_o + sheen_lambda(b.sheen_fit, wi.z)));
      f_layers += v.w_coat * b.sheen * fibres;
      pdf_diffuse = wi.z / WT_PI;
    }
#endif
  }
#if WT_HAS_TRANSMISSION
  if (t.interface > 0.0f && !b.smooth)
    f += (1.0f - b.metallic) * b.transmission * interface_eval(b, wo, wi, lobes, &pdf_interface);
#endif
  *pdf = t.specular * pdf_spec + (t.diffuse + t.sheen) * pdf_diffuse + t.interface * pdf_interface +
         t.clearcoat * pdf_coat;
  return f_layers + v.w_base * f;
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

/// The delta reflections towards the mirror direction of wo that the
/// techniques allow: the base's mirror (its layers' share w_base of it) and
/// the mirror coat. Their weight F (what a delta carries, no pdf), summed,
/// and *p: the summed probability of the techniques that produce them, so a
/// mirror coat over a mirror base is one delta reached by either technique.
/// `which`: 1 the base's, 2 the coat's, 3 both (one direction: the coat has
/// no normal of its own).
inline float3 pbr_mirror(Bsdf b, PbrView v, Techniques t, float3 wo, float* p, uint which) {
  float3 f = (float3)(0.0f);
  *p = 0.0f;
  if ((which & 1u) && b.mirror && t.specular > 0.0f) {
    float m5 = ggx_schlick(0.0f, wo.z);
    float opaque = (1.0f - b.metallic) * (1.0f - b.transmission);
    float3 f_base = b.metallic * (b.base + (1.0f - b.base) * m5) + opaque * b.specular * (b.f0 + (1.0f - b.f0) * m5);
#if WT_HAS_IRIDESCENCE
    if (b.iridescence > 0.0f) {
      f_base = bsdf_iridescent_fresnel(b, wo.z, f_base, opaque, bsdf_film_dielectric(b, wo.z, opaque));
    }
#endif
    f += v.w_base * f_base;
    *p += t.specular;
  }
#if WT_HAS_CLEARCOAT
  if ((which & 2u) && b.clearcoat_mirror && t.clearcoat > 0.0f) {
    f += b.clearcoat * ggx_schlick(WT_PBR_DIELECTRIC_F0, coat_local(b, wo).z);
    *p += t.clearcoat;
  }
#endif
  return f;
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

#if WT_HAS_THIN_SHADOWS
/// What a smooth thin wall passes straight through (wi = -wo) for local wo
/// (z > 0): the delta transmission's weight times the probability of
/// sampling it (bsdf_sample), the clear share under the layers, 1 - F,
/// tinted by the base colour. Shadow rays cross the wall with it
/// (kernels/connect.cl), so a path that samples that lobe has found the same
/// light on average.
inline float3 bsdf_thin_pass(Bsdf b, float3 wo) {
  PbrView v = pbr_view(b, wo);
  float f = interface_fresnel(b, wo.z);
  return b.base * ((1.0f - f) * ((1.0f - b.metallic) * b.transmission * v.w_base));
}
#endif

/// Draw a direction for local wo with uniforms u_lobe, u1, u2. False when
/// nothing is scattered (no allowed lobe, a direction on the wrong side).
inline bool bsdf_sample(Bsdf b, float3 wo, uint lobes, float u_lobe, float u1, float u2, BsdfSample* s) {
  if (wo.z <= 0.0f || !(lobes & (WT_LOBE_DIFFUSE | WT_LOBE_SPECULAR | WT_LOBE_TRANSMISSION))) return false;
  PbrView v = b.model == WT_MATERIAL_PBR ? pbr_view(b, wo) : pbr_view_none();
  Techniques t = bsdf_techniques(b, v, lobes);
  // the techniques in order: coat, base GGX, interface, cosine (diffuse and sheen)
  float below_spec = t.clearcoat, below_interface = below_spec + t.specular;
  float below_cosine = below_interface + t.interface;
  if (u_lobe < below_interface) {
    bool coat = u_lobe < below_spec;
    s->lobe = WT_LOBE_SPECULAR;
    if (coat ? b.clearcoat_mirror : b.mirror) {
      // the mirror: F at mu_o, over the probability of having picked a technique that makes it
      float p;
      uint which = 3u;
      s->wi = (float3)(-wo.x, -wo.y, wo.z);
#if WT_HAS_CLEARCOAT
      // a coat of its own normal mirrors about it, apart from the base's mirror
      if (coat_apart(b)) {
        which = coat ? 2u : 1u;
        if (coat) s->wi = 2.0f * dot(wo, b.coat_n) * b.coat_n - wo;
      }
#endif
      float3 f = pbr_mirror(b, v, t, wo, &p, which);
      s->weight = f / p;
      s->pdf = 0.0f;
      s->lobe |= WT_LOBE_DELTA;
      return p > 0.0f && s->wi.z > 0.0f && (f.x > 0.0f || f.y > 0.0f || f.z > 0.0f);
    }
    float3 h;
    if (coat) {
#if WT_HAS_CLEARCOAT
      float alpha = b.clearcoat_roughness * b.clearcoat_roughness, hx, hy, hz;
      float3 wo_c = coat_local(b, wo);
      if (!(wo_c.z > 0.0f)) return false;
      ggx_sample_visible_normal(wo_c.x, wo_c.y, wo_c.z, alpha, u1, u2, &hx, &hy, &hz);
      h = hx * b.coat_t + hy * b.coat_b + hz * b.coat_n;
#else
      return false;
#endif
    } else {
      h = base_ggx_sample(b, wo, u1, u2);
    }
    s->wi = 2.0f * dot(wo, h) * h - wo;
  } else if (u_lobe < below_cosine) {
#if WT_HAS_TRANSMISSION
    float u = fmin((u_lobe - below_interface) / t.interface, 0x1.fffffep-1f);  // reused for reflect or transmit
    float clear = (1.0f - b.metallic) * b.transmission;
    if (b.smooth) {
      float f = interface_fresnel(b, wo.z);
      float p_reflect = interface_reflect_probability(f, lobes);
      if (!interface_direction(b, wo, (float3)(0.0f, 0.0f, 1.0f), p_reflect, u, &s->wi, &s->lobe)) return false;
      float3 w = s->lobe == WT_LOBE_SPECULAR
                     ? (float3)(f / p_reflect)
                     : b.base * ((1.0f - f) / ((b.thin ? 1.0f : b.eta * b.eta) * (1.0f - p_reflect)));
      s->weight = w * (clear * v.w_base / t.interface);
      s->pdf = 0.0f;
      s->lobe |= WT_LOBE_DELTA;
      return s->weight.x > 0.0f || s->weight.y > 0.0f || s->weight.z > 0.0f;
    }
    float alpha = b.roughness * b.roughness;
    float hx, hy, hz;
    ggx_sample_visible_normal(wo.x, wo.y, wo.z, alpha, u1, u2, &hx, &hy, &hz);
    float3 h = (float3)(hx, hy, hz);
    float p_reflect = interface_reflect_probability(interface_fresnel(b, dot(wo, h)), lobes);
    if (!interface_direction(b, wo, h, p_reflect, u, &s->wi, &s->lobe)) return false;
#else
    return false;
#endif
  } else {
    if (!(lobes & WT_LOBE_DIFFUSE) || !(t.diffuse + t.sheen > 0.0f)) return false;
    s->lobe = WT_LOBE_DIFFUSE;
    s->wi = lambert_sample_local(u1, u2);
  }
  // reflection stays on wo's side, transmission crosses
  if ((s->lobe & WT_LOBE_TRANSMISSION) ? !(s->wi.z < 0.0f) : !(s->wi.z > 0.0f)) return false;
  float3 f_cos = bsdf_eval(b, wo, s->wi, lobes, &s->pdf);
  if (!(s->pdf > 0.0f) || !(f_cos.x > 0.0f || f_cos.y > 0.0f || f_cos.z > 0.0f)) return false;
  s->weight = f_cos / s->pdf;
  return true;
}

#endif  // WT_MATERIALS_BSDF_CL
