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

/// A microfacet normal h drawn from the normals visible from unit direction
/// v (vz > 0), given two uniforms (Heitz 2018, "Sampling the GGX
/// Distribution of Visible Normals"). Its density over h is
/// G1(v) max(0, v.h) D(h) / vz.
WT_GGX_INLINE void ggx_sample_visible_normal(float vx, float vy, float vz, float alpha, float u1, float u2,
                                             float* hx, float* hy, float* hz) {
  // the view direction stretched to the hemisphere configuration
  float sx = alpha * vx, sy = alpha * vy, sz = vz;
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
  float r = sqrt(u1), phi = 2.0f * WT_GGX_PI * u2;
  float p1 = r * cos(phi), p2 = r * sin(phi);
  float s = 0.5f * (1.0f + sz);
  p2 = (1.0f - s) * sqrt(fmax(0.0f, 1.0f - p1 * p1)) + s * p2;
  float p3 = sqrt(fmax(0.0f, 1.0f - p1 * p1 - p2 * p2));
  float nx = p1 * t1x + p2 * t2x + p3 * sx;
  float ny = p1 * t1y + p2 * t2y + p3 * sy;
  float nz = p2 * t2z + p3 * sz;
  // back to the ellipsoid configuration
  float ex = alpha * nx, ey = alpha * ny, ez = fmax(nz, 0.0f);
  float elen = sqrt(ex * ex + ey * ey + ez * ez);
  *hx = ex / elen, *hy = ey / elen, *hz = ez / elen;
}

#endif  // WT_SHARED_GGX_H
