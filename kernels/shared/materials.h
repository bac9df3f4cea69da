// Material models and the layout of the albedo table that the
// metallic-roughness BSDF and its layers read, shared by host and kernels.
#ifndef WT_SHARED_MATERIALS_H
#define WT_SHARED_MATERIALS_H

#include "shared/ggx.h"
#include "shared/sheen.h"
#include "shared/types.h"

#ifdef __OPENCL_C_VERSION__
#define WT_MATERIALS_INLINE inline
#define WT_GLOBAL __global
#else
#define WT_MATERIALS_INLINE static inline
#define WT_GLOBAL
#endif

/// Reflectance at normal incidence of glTF's dielectric (ior 1.5).
#define WT_PBR_DIELECTRIC_F0 0.04f
/// Roughness below which the specular lobe is a perfect mirror (sqrt(WT_GGX_MIN_ALPHA)).
#define WT_PBR_MIN_ROUGHNESS 0.031622777f

// The albedo table: N x N entries over mu = cos(theta_o) at (i / (N - 1))^2
// (crowded towards grazing, where a smooth surface's albedo turns steeply;
// 1e-4 for i = 0) and roughness from WT_PBR_MIN_ROUGHNESS to 1 at
// WT_PBR_MIN_ROUGHNESS + (1 - WT_PBR_MIN_ROUGHNESS) (j / (N - 1))^2 (crowded
// towards smooth), then the averages over mu (2 int_0^1 E(mu) mu dmu) per
// roughness. GGX with Schlick's Fresnel F0 + (F90 - F0)(1 - v.h)^5 has the
// single-scattering albedo F0 (E - S) + F90 S for every F0 and F90 (the
// split sum), so E and S serve every dielectric, the clear coat and
// KHR_materials_specular's coloured, weighted F0 exactly. The sheen rows
// run over sheen roughness from WT_SHEEN_MIN_ROUGHNESS to 1 the same way.
#define WT_PBR_TABLE_N 32
#define WT_PBR_TABLE_E 0                                            ///< GGX single scattering, F = 1
#define WT_PBR_TABLE_S (WT_PBR_TABLE_N * WT_PBR_TABLE_N)            ///< GGX single scattering with F = (1 - v.h)^5
#define WT_PBR_TABLE_SHEEN (2 * WT_PBR_TABLE_N * WT_PBR_TABLE_N)    ///< the sheen lobe with colour 1 (shared/sheen.h), over (mu, sheen roughness)
#define WT_PBR_TABLE_E_AVG (3 * WT_PBR_TABLE_N * WT_PBR_TABLE_N)    ///< average of E, per roughness
#define WT_PBR_TABLE_S_AVG (WT_PBR_TABLE_E_AVG + WT_PBR_TABLE_N)    ///< average of S, per roughness
#define WT_PBR_TABLE_SIZE (WT_PBR_TABLE_S_AVG + WT_PBR_TABLE_N)

/// Continuous table row of a roughness whose rows start at `lowest`, in [0, N - 1].
WT_MATERIALS_INLINE float pbr_table_row(float roughness, float lowest) {
  float t = (roughness - lowest) / (1.0f - lowest);
  return sqrt(fmin(fmax(t, 0.0f), 1.0f)) * (float)(WT_PBR_TABLE_N - 1);
}

/// Continuous table coordinate of a GGX roughness, in [0, N - 1].
WT_MATERIALS_INLINE float pbr_table_roughness_coord(float roughness) {
  return pbr_table_row(roughness, WT_PBR_MIN_ROUGHNESS);
}

/// The GGX roughness of table row j.
WT_MATERIALS_INLINE float pbr_table_roughness(int j) {
  float y = (float)j / (float)(WT_PBR_TABLE_N - 1);
  return WT_PBR_MIN_ROUGHNESS + (1.0f - WT_PBR_MIN_ROUGHNESS) * y * y;
}

/// The sheen roughness of the sheen rows' row j.
WT_MATERIALS_INLINE float pbr_table_sheen_roughness(int j) {
  float y = (float)j / (float)(WT_PBR_TABLE_N - 1);
  return WT_SHEEN_MIN_ROUGHNESS + (1.0f - WT_SHEEN_MIN_ROUGHNESS) * y * y;
}

/// The cosine of table column i.
WT_MATERIALS_INLINE float pbr_table_mu(int i) {
  float x = (float)i / (float)(WT_PBR_TABLE_N - 1);
  return x * x;
}

/// Bilinear lookup of a 2D table at mu and a continuous row y.
WT_MATERIALS_INLINE float pbr_table_lookup(WT_GLOBAL const float* table, int offset, float mu, float y) {
  float x = sqrt(fmin(fmax(mu, 0.0f), 1.0f)) * (float)(WT_PBR_TABLE_N - 1);
  int x0 = (int)fmin(x, (float)(WT_PBR_TABLE_N - 2)), y0 = (int)fmin(y, (float)(WT_PBR_TABLE_N - 2));
  float fx = x - (float)x0, fy = y - (float)y0;
  WT_GLOBAL const float* row0 = table + offset + y0 * WT_PBR_TABLE_N;
  WT_GLOBAL const float* row1 = row0 + WT_PBR_TABLE_N;
  float a = row0[x0] + fx * (row0[x0 + 1] - row0[x0]);
  float b = row1[x0] + fx * (row1[x0 + 1] - row1[x0]);
  return a + fy * (b - a);
}

/// Bilinear lookup of a GGX table (offset WT_PBR_TABLE_E or _S) at (mu, roughness).
WT_MATERIALS_INLINE float pbr_table_albedo(WT_GLOBAL const float* table, int offset, float mu, float roughness) {
  return pbr_table_lookup(table, offset, mu, pbr_table_roughness_coord(roughness));
}

/// The sheen lobe's albedo (colour 1) at (mu, sheen roughness).
WT_MATERIALS_INLINE float pbr_table_sheen(WT_GLOBAL const float* table, float mu, float sheen_roughness) {
  return pbr_table_lookup(table, WT_PBR_TABLE_SHEEN, mu, pbr_table_row(sheen_roughness, WT_SHEEN_MIN_ROUGHNESS));
}

/// Linear lookup of an average (offset WT_PBR_TABLE_E_AVG or _S_AVG) at a roughness.
WT_MATERIALS_INLINE float pbr_table_average(WT_GLOBAL const float* table, int offset, float roughness) {
  float y = pbr_table_roughness_coord(roughness);
  int y0 = (int)fmin(y, (float)(WT_PBR_TABLE_N - 2));
  float fy = y - (float)y0;
  return table[offset + y0] + fy * (table[offset + y0 + 1] - table[offset + y0]);
}

/// Kulla and Conty 2017: the energy the multiple-scattering lobe (of albedo
/// 1 - E_avg on average with F = 1) carries once each inner bounce is
/// weighted by the average Fresnel: F_avg^2 E_avg / (1 - F_avg (1 - E_avg)).
WT_MATERIALS_INLINE float pbr_multiscatter_fresnel(float f_avg, float e_avg) {
  return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

#endif  // WT_SHARED_MATERIALS_H
