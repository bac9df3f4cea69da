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

// The anisotropic lobe's albedos (KHR_materials_anisotropy): E and S as
// above, but the lobe's albedo depends on the view's azimuth as well, so
// they run over four coordinates: mu at (i / (N_MU - 1))^2; c = cos^2 of
// wo's azimuth from the anisotropy axis (x), uniform (Lambda is linear in
// it) mapped by pbr_aniso_view_coord; r_b = sqrt(alpha_b) like the isotropic rows; and k = sqrt((alpha_t -
// alpha_b) / (1 - alpha_b)), uniform (the strength for an unclamped
// alpha_b; k = 0 is isotropic). Then the averages over the hemisphere,
// (1 / pi) int E cos dw, of the interpolated table, per (r_b, k), so that
// the multiple-scattering lobe built from it returns exactly what the
// table says single scattering loses (docs/materials.md, "Anisotropy").
#define WT_ANISO_N_MU 16
#define WT_ANISO_N_C 9
#define WT_ANISO_N_R 16
#define WT_ANISO_N_K 9
#define WT_ANISO_BLOCK (WT_ANISO_N_MU * WT_ANISO_N_C * WT_ANISO_N_R * WT_ANISO_N_K)
#define WT_PBR_TABLE_ANISO_E (WT_PBR_TABLE_S_AVG + WT_PBR_TABLE_N)         ///< anisotropic E, [k][r][c][mu]
#define WT_PBR_TABLE_ANISO_S (WT_PBR_TABLE_ANISO_E + WT_ANISO_BLOCK)       ///< anisotropic S, the same layout
#define WT_PBR_TABLE_ANISO_E_AVG (WT_PBR_TABLE_ANISO_S + WT_ANISO_BLOCK)   ///< average of E, [k][r]
#define WT_PBR_TABLE_ANISO_S_AVG (WT_PBR_TABLE_ANISO_E_AVG + WT_ANISO_N_R * WT_ANISO_N_K)  ///< average of S, [k][r]
#define WT_PBR_TABLE_SIZE (WT_PBR_TABLE_ANISO_S_AVG + WT_ANISO_N_R * WT_ANISO_N_K)

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

/// The anisotropic table's r_b of row j (a perceptual roughness, sqrt(alpha_b)).
WT_MATERIALS_INLINE float pbr_aniso_roughness(int j) {
  float y = (float)j / (float)(WT_ANISO_N_R - 1);
  return WT_PBR_MIN_ROUGHNESS + (1.0f - WT_PBR_MIN_ROUGHNESS) * y * y;
}

/// The anisotropic table's alpha_t of layer k over alpha_b: alpha_b + (1 - alpha_b) (k / (N_K - 1))^2.
WT_MATERIALS_INLINE float pbr_aniso_alpha_t(int k, float alpha_b) {
  float y = (float)k / (float)(WT_ANISO_N_K - 1);
  return alpha_b + (1.0f - alpha_b) * y * y;
}

/// Continuous (r_b, k) coordinates of a lobe's alphas (alpha_t >= alpha_b).
WT_MATERIALS_INLINE void pbr_aniso_coords(float alpha_t, float alpha_b, float* r_coord, float* k_coord) {
  float t = (sqrt(alpha_b) - WT_PBR_MIN_ROUGHNESS) / (1.0f - WT_PBR_MIN_ROUGHNESS);
  *r_coord = sqrt(fmin(fmax(t, 0.0f), 1.0f)) * (float)(WT_ANISO_N_R - 1);
  float u = (alpha_t - alpha_b) / fmax(1.0f - alpha_b, 1e-6f);
  *k_coord = sqrt(fmin(fmax(u, 0.0f), 1.0f)) * (float)(WT_ANISO_N_K - 1);
}

/// Cell index and fraction of a continuous coordinate over n nodes.
WT_MATERIALS_INLINE int pbr_aniso_cell(float x, int n, float* f) {
  int i = (int)fmin(fmax(x, 0.0f), (float)(n - 2));
  *f = fmin(fmax(x - (float)i, 0.0f), 1.0f);
  return i;
}

/// The view's azimuth coordinate: where the roughness it sees, sqrt(alpha_t^2
/// c + alpha_b^2 (1 - c)) with c = cos^2 of its azimuth from x, lies
/// between alpha_b and alpha_t (that roughness sets its masking, and it
/// turns as sqrt(c) near the axis of the smaller alpha: uniform steps in c
/// interpolated up to 14% off at grazing views).
WT_MATERIALS_INLINE float pbr_aniso_view_coord(float c, float alpha_t, float alpha_b) {
  if (!(alpha_t > alpha_b)) return c;
  float a = sqrt(alpha_t * alpha_t * c + alpha_b * alpha_b * (1.0f - c));
  return fmin(fmax(log(a / alpha_b) / log(alpha_t / alpha_b), 0.0f), 1.0f);
}

/// The cos^2 of the azimuth at view coordinate q (pbr_aniso_view_coord's inverse).
WT_MATERIALS_INLINE float pbr_aniso_view_cos2(float q, float alpha_t, float alpha_b) {
  if (!(alpha_t > alpha_b)) return q;
  float a = alpha_b * exp(q * log(alpha_t / alpha_b));
  return fmin(fmax((a * a - alpha_b * alpha_b) / (alpha_t * alpha_t - alpha_b * alpha_b), 0.0f), 1.0f);
}

/// Quadrilinear lookup of an anisotropic table (offset WT_PBR_TABLE_ANISO_E
/// or _S) for a local direction (x along the anisotropy axis, z > 0) at
/// continuous (r_b, k) coordinates.
WT_MATERIALS_INLINE float pbr_aniso_albedo(WT_GLOBAL const float* table, int offset, float x, float y, float z,
                                           float alpha_t, float alpha_b, float r_coord, float k_coord) {
  float sin2 = x * x + y * y;
  float c = sin2 > 0.0f ? x * x / sin2 : 1.0f;
  c = pbr_aniso_view_coord(c, alpha_t, alpha_b);
  float fm, fc, fr, fk;
  int im = pbr_aniso_cell(sqrt(fmin(fmax(z, 0.0f), 1.0f)) * (float)(WT_ANISO_N_MU - 1), WT_ANISO_N_MU, &fm);
  int ic = pbr_aniso_cell(c * (float)(WT_ANISO_N_C - 1), WT_ANISO_N_C, &fc);
  int ir = pbr_aniso_cell(r_coord, WT_ANISO_N_R, &fr);
  int ik = pbr_aniso_cell(k_coord, WT_ANISO_N_K, &fk);
  float result = 0.0f;
  for (int dk = 0; dk < 2; ++dk)
    for (int dr = 0; dr < 2; ++dr) {
      float w = (dk ? fk : 1.0f - fk) * (dr ? fr : 1.0f - fr);
      WT_GLOBAL const float* p =
          table + offset + (((ik + dk) * WT_ANISO_N_R + ir + dr) * WT_ANISO_N_C + ic) * WT_ANISO_N_MU + im;
      float a = p[0] + fm * (p[1] - p[0]);
      float b = p[WT_ANISO_N_MU] + fm * (p[WT_ANISO_N_MU + 1] - p[WT_ANISO_N_MU]);
      result += w * (a + fc * (b - a));
    }
  return result;
}

/// Bilinear lookup of an anisotropic average (offset WT_PBR_TABLE_ANISO_E_AVG or _S_AVG).
WT_MATERIALS_INLINE float pbr_aniso_average(WT_GLOBAL const float* table, int offset, float r_coord, float k_coord) {
  float fr, fk;
  int ir = pbr_aniso_cell(r_coord, WT_ANISO_N_R, &fr), ik = pbr_aniso_cell(k_coord, WT_ANISO_N_K, &fk);
  WT_GLOBAL const float* p = table + offset + ik * WT_ANISO_N_R + ir;
  float a = p[0] + fr * (p[1] - p[0]);
  float b = p[WT_ANISO_N_R] + fr * (p[WT_ANISO_N_R + 1] - p[WT_ANISO_N_R]);
  return a + fk * (b - a);
}

/// Kulla and Conty 2017: the energy the multiple-scattering lobe (of albedo
/// 1 - E_avg on average with F = 1) carries once each inner bounce is
/// weighted by the average Fresnel: F_avg^2 E_avg / (1 - F_avg (1 - E_avg)).
WT_MATERIALS_INLINE float pbr_multiscatter_fresnel(float f_avg, float e_avg) {
  return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

#endif  // WT_SHARED_MATERIALS_H
