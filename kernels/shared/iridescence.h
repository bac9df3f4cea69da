// KHR_materials_iridescence's thin-film Fresnel (Belcour & Barla 2017, "A
// Practical Extension to Microfacet Theory for the Modeling of Varying
// Iridescence", in the approximation the extension's "Iridescence Fresnel"
// section gives: Schlick reflectances at both interfaces, phase shifts 0 or
// pi, the film's Airy series integrated against Gaussian fits of the CIE
// sensitivities in Fourier space to its second order, XYZ to Rec. 709).
// Scalars only, so the host's tests evaluate the same definition.
#ifndef WT_SHARED_IRIDESCENCE_H
#define WT_SHARED_IRIDESCENCE_H

#include "shared/ggx.h"

/// One order of the spectral integral: the Rec. 709 response to a film whose
/// optical path difference is `opd` nm, with phase shift `shift` per XYZ
/// component (the extension's evalSensitivity).
WT_GGX_INLINE void iridescence_sensitivity(float opd, float shift_x, float shift_y, float shift_z, float* r, float* g,
                                           float* b) {
  float phase = 2.0f * WT_GGX_PI * opd * 1.0e-9f;
  float p2 = phase * phase;
  float x = 5.4856e-13f * sqrt(2.0f * WT_GGX_PI * 4.3278e+09f) * cos(1.6810e+06f * phase + shift_x) * exp(-p2 * 4.3278e+09f);
  float y = 4.4201e-13f * sqrt(2.0f * WT_GGX_PI * 9.3046e+09f) * cos(1.7953e+06f * phase + shift_y) * exp(-p2 * 9.3046e+09f);
  float z = 5.2481e-13f * sqrt(2.0f * WT_GGX_PI * 6.6121e+09f) * cos(2.2084e+06f * phase + shift_z) * exp(-p2 * 6.6121e+09f);
  x += 9.7470e-14f * sqrt(2.0f * WT_GGX_PI * 4.5282e+09f) * cos(2.2399e+06f * phase + shift_x) * exp(-4.5282e+09f * p2);
  x /= 1.0685e-7f, y /= 1.0685e-7f, z /= 1.0685e-7f;
  *r = 3.2404542f * x - 1.5371385f * y - 0.4985314f * z;
  *g = -0.9692660f * x + 1.8760108f * y + 0.0415560f * z;
  *b = 0.0556434f * x - 0.2040259f * y + 1.0572252f * z;
}

/// The film's normal-incidence reflectance between indices n_t and n_i.
WT_GGX_INLINE float iridescence_ior_to_f0(float n_t, float n_i) {
  float r = (n_t - n_i) / (n_t + n_i);
  return r * r;
}

/// Per channel (c = 0, 1, 2): the base's index from its F0 under air
/// (guarded against F0 = 1), its film-to-base Schlick reflectance at cos2 and
/// the phase shift pi where the base's index is below the film's.
WT_GGX_INLINE void iridescence_base(float f0, float film_ior, float cos2, float* r23, float* phi23) {
  float s = sqrt(fmin(f0 + 0.0001f, 0.9999f));
  float base_ior = (1.0f + s) / (1.0f - s);
  *r23 = ggx_schlick(iridescence_ior_to_f0(base_ior, film_ior), cos2);
  *phi23 = base_ior < film_ior ? WT_GGX_PI : 0.0f;
}

/// The extension's iridescent_fresnel: the reflectance (rgb into out[0..2])
/// of a film of index film_ior and `thickness` nm between a medium of index
/// outside_ior and a base of per-channel F0 f0_r, f0_g, f0_b, seen at cos1
/// (the microfacet's cos to the view). Total internal reflection in the film
/// reflects everything.
WT_GGX_INLINE void iridescence_fresnel(float outside_ior, float film_ior, float f0_r, float f0_g, float f0_b,
                                       float thickness, float cos1, float* out) {
  float ratio = outside_ior / film_ior;
  float cos2_sq = 1.0f - ratio * ratio * (1.0f - cos1 * cos1);
  if (cos2_sq < 0.0f) {
    out[0] = out[1] = out[2] = 1.0f;
    return;
  }
  float cos2 = sqrt(cos2_sq);
  // the first interface
  float r12 = ggx_schlick(iridescence_ior_to_f0(film_ior, outside_ior), cos1);
  float t121 = 1.0f - r12;
  float phi12 = film_ior < outside_ior ? WT_GGX_PI : 0.0f;
  float phi21 = WT_GGX_PI - phi12;
  // the second, per channel
  float f0[3] = {f0_r, f0_g, f0_b}, r23[3], phi[3];
  for (int c = 0; c < 3; ++c) {
    float phi23;
    iridescence_base(f0[c], film_ior, cos2, &r23[c], &phi23);
    phi[c] = phi21 + phi23;
  }
  float opd = 2.0f * film_ior * thickness * cos2;
  float cm[3], r123[3];
  for (int c = 0; c < 3; ++c) {
    float rr = fmin(fmax(r12 * r23[c], 1e-5f), 0.9999f);
    r123[c] = sqrt(rr);
    float rs = t121 * t121 * r23[c] / (1.0f - rr);
    out[c] = r12 + rs;  // the DC term
    cm[c] = rs - t121;
  }
  // pairs of Diracs, m = 1, 2
  for (int m = 1; m <= 2; ++m) {
    float s[3];
    iridescence_sensitivity((float)m * opd, (float)m * phi[0], (float)m * phi[1], (float)m * phi[2], &s[0], &s[1], &s[2]);
    for (int c = 0; c < 3; ++c) {
      cm[c] *= r123[c];
      out[c] += cm[c] * 2.0f * s[c];
    }
  }
  for (int c = 0; c < 3; ++c) out[c] = fmax(out[c], 0.0f);
}

#endif  // WT_SHARED_IRIDESCENCE_H
