// The GGX (Trowbridge-Reitz) microfacet model in the local shading frame
// (z along the normal), written with scalars only so the host and the
// kernels share one definition: the distribution, the height-correlated
// Smith masking-shadowing, Schlick's Fresnel and sampling of the visible
// normals (Heitz 2018). The host tabulates directional albedos with these
// same functions (host/render/material_tables.cpp) for the energy
// compensation the kernels apply (kernels/materials/bsdf.cl).
#ifndef WT_SHARED_GGX_H
#define WT_SHARED_GGX_H

#include "shared/types.h"
#include "shared/trig.h"

#ifdef __OPENCL_C_VERSION__
#define WT_GGX_INLINE inline
#else
#include <cmath>
#define WT_GGX_INLINE static inline
#endif

#define WT_GGX_PI 3.14159265358979323846f

/// Below this alpha (roughness 0.0316) reflection is treated as a perfect
/// mirror: the distribution's peak, 1 / (pi alpha^2), would outgrow float
/// precision in its own denominator.
#define WT_GGX_MIN_ALPHA 1e-3f

/// D(h) for a unit microfacet normal h: 1 / (pi a^2 ((hx^2 + hy^2) / a^2 + hz^2)^2),
/// written without the cancellation of the cos^2 (a^2 - 1) + 1 form.
WT_GGX_INLINE float ggx_d(float hx, float hy, float hz, float alpha) {
  if (hz <= 0.0f) return 0.0f;
  float a2 = alpha * alpha;
  float t = (hx * hx + hy * hy) / a2 + hz * hz;
  return 1.0f / (WT_GGX_PI * a2 * t * t);
}

/// Smith's Lambda for a unit direction v: (sqrt(1 + a^2 tan^2) - 1) / 2.
WT_GGX_INLINE float ggx_lambda(float vx, float vy, float vz, float alpha) {
  float z2 = vz * vz;
  if (z2 <= 0.0f) return INFINITY;
  float a2_tan2 = alpha * alpha * (vx * vx + vy * vy) / z2;
  return 0.5f * (sqrt(1.0f + a2_tan2) - 1.0f);
}

/// Masking of one direction: 1 / (1 + Lambda).
WT_GGX_INLINE float ggx_g1(float vx, float vy, float vz, float alpha) {
  return 1.0f / (1.0f + ggx_lambda(vx, vy, vz, alpha));
}

/// Height-correlated masking-shadowing of the pair: 1 / (1 + Lambda(o) + Lambda(i)).
WT_GGX_INLINE float ggx_g2(float ox, float oy, float oz, float ix, float iy, float iz, float alpha) {
  return 1.0f / (1.0f + ggx_lambda(ox, oy, oz, alpha) + ggx_lambda(ix, iy, iz, alpha));
}

/// Schlick's approximation, F0 + (1 - F0)(1 - cos)^5.
WT_GGX_INLINE float ggx_schlick(float f0, float cos_theta) {
  float m = fmin(fmax(1.0f - cos_theta, 0.0f), 1.0f);
  float m2 = m * m;
  return f0 + (1.0f - f0) * m2 * m2 * m;
}

/// Fresnel reflectance of unpolarised light at a dielectric interface, for
/// the cosine cos_i >= 0 of the angle on the incident side and eta =
/// n(transmitted side) / n(incident side); 1 under total internal reflection.
WT_GGX_INLINE float ggx_fresnel_dielectric(float cos_i, float eta) {
  cos_i = fmin(fmax(cos_i, 0.0f), 1.0f);
  float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  float cos_t = sqrt(1.0f - sin2_t);
  float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5f * (rs * rs + rp * rp);
}

/// Hemispherical average of Schlick's Fresnel weighted by cos: F0 + (1 - F0) / 21.
WT_GGX_INLINE float ggx_schlick_average(float f0) { return f0 + (1.0f - f0) / 21.0f; }

/// Anisotropic GGX (Heitz 2014), alpha_x along the frame's x axis (the
/// tangent) and alpha_y along y. Written so that alpha_x == alpha_y gives
/// the isotropic forms above; callers with an isotropic lobe keep those.
/// D(h) = 1 / (pi ax ay ((hx / ax)^2 + (hy / ay)^2 + hz^2)^2).
WT_GGX_INLINE float ggx_d_aniso(float hx, float hy, float hz, float ax, float ay) {
  if (hz <= 0.0f) return 0.0f;
  float t = hx * hx / (ax * ax) + hy * hy / (ay * ay) + hz * hz;
  return 1.0f / (WT_GGX_PI * ax * ay * t * t);
}

/// Smith's Lambda of the anisotropic lobe: the isotropic one with
/// alpha^2 tan^2 = (ax^2 vx^2 + ay^2 vy^2) / vz^2.
WT_GGX_INLINE float ggx_lambda_aniso(float vx, float vy, float vz, float ax, float ay) {
  float z2 = vz * vz;
  if (z2 <= 0.0f) return INFINITY;
  float a2_tan2 = (ax * ax * vx * vx + ay * ay * vy * vy) / z2;
  return 0.5f * (sqrt(1.0f + a2_tan2) - 1.0f);
}

WT_GGX_INLINE float ggx_g1_aniso(float vx, float vy, float vz, float ax, float ay) {
  return 1.0f / (1.0f + ggx_lambda_aniso(vx, vy, vz, ax, ay));
}

WT_GGX_INLINE float ggx_g2_aniso(float ox, float oy, float oz, float ix, float iy, float iz, float ax, float ay) {
  return 1.0f / (1.0f + ggx_lambda_aniso(ox, oy, oz, ax, ay) + ggx_lambda_aniso(ix, iy, iz, ax, ay));
}

/// The KHR_materials_anisotropy roughnesses of perceptual roughness r and
/// strength s: alpha_t = mix(r^2, 1, s^2) along the anisotropy direction,
/// alpha_b = r^2 across it.
WT_GGX_INLINE void ggx_anisotropy_alphas(float roughness, float strength, float* alpha_t, float* alpha_b) {
  float a = roughness * roughness;
  *alpha_t = a + (1.0f - a) * strength * strength;
  *alpha_b = a;
}

/// A microfacet normal h drawn from the normals visible from unit direction
/// v (vz > 0), given two uniforms (Heitz 2018, "Sampling the GGX
/// Distribution of Visible Normals"). Its density over h is
/// G1(v) max(0, v.h) D(h) / vz; ggx_sample_visible_normal_aniso stretches
/// x and y by their own alphas.
WT_GGX_INLINE void ggx_sample_visible_normal_aniso(float vx, float vy, float vz, float ax, float ay, float u1, float u2,
                                                   float* hx, float* hy, float* hz) {
  // the view direction stretched to the hemisphere configuration
  float sx = ax * vx, sy = ay * vy, sz = vz;
  float len = sqrt(sx * sx + sy * sy + sz * sz);
  sx /= len, sy /= len, sz /= len;
  // an orthonormal basis around it
  float lensq = sx * sx + sy * sy;
  float t1x = 1.0f, t1y = 0.0f;
  if (lensq > 0.0f) {
    float inv = 1.0f / sqrt(lensq);
    t1x = -sy * inv, t1y = sx * inv;
  }
  float t2x = -sz * t1y, t2y = sz * t1x, t2z = sx * t1y - sy * t1x;
  // a point on the projected disk, warped towards the visible half
  float r = sqrt(u1), cos_phi;
  float sin_phi = wt_sincospi(2.0f * u2, &cos_phi);  // phi = 2 pi u2
  float p1 = r * cos_phi, p2 = r * sin_phi;
  float s = 0.5f * (1.0f + sz);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  float p3 = sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
  float nx = p1 * t1x + p2 * t2x + p3 * sx;
  float ny = p1 * t1y + p2 * t2y + p3 * sy;
  float nz = p2 * t2z + p3 * sz;
  // back to the ellipsoid configuration
  float ex = ax * nx, ey = ay * ny, ez = fmax(nz, 0.0f);
  float elen = sqrt(ex * ex + ey * ey + ez * ez);
  *hx = ex / elen, *hy = ey / elen, *hz = ez / elen;
}

WT_GGX_INLINE void ggx_sample_visible_normal(float vx, float vy, float vz, float alpha, float u1, float u2,
                                             float* hx, float* hy, float* hz) {
  ggx_sample_visible_normal_aniso(vx, vy, vz, alpha, alpha, u1, u2, hx, hy, hz);
}

#endif  // WT_SHARED_GGX_H
