#include "render/material_tables.h"

#include "shared/ggx.h"
#include "shared/materials.h"
#include "shared/sheen.h"

#include <algorithm>
#include <cmath>

namespace wt {

namespace {

/// The directional albedo of a GGX lobe seen from (ox, oy, oz), by the
/// midpoint rule over its visible normals (u1 crowded towards 1, where the
/// grazing half-vectors lie); `sample` and `g2` pick the isotropic or
/// anisotropic lobe.
template <class SampleNormal, class MaskingShadowing>
GgxAlbedo visibleNormalAlbedo(float ox, float oy, float oz, float g1, double f0, int radial, int around,
                              SampleNormal sample, MaskingShadowing g2) {
  GgxAlbedo sum;
  for (int a = 0; a < radial; ++a) {
    double v = (a + 0.5) / radial, w = 1.0 - v;
    float u1 = float(1.0 - w * w * w);
    double jacobian = 3.0 * w * w;
    for (int b = 0; b < around; ++b) {
      float u2 = (float(b) + 0.5f) / float(around);
      float hx, hy, hz;
      sample(u1, u2, &hx, &hy, &hz);
      float oh = ox * hx + oy * hy + oz * hz;
      float ix = 2.0f * oh * hx - ox, iy = 2.0f * oh * hy - oy, iz = 2.0f * oh * hz - oz;
      if (iz <= 0.0f) continue;
      // f cos / pdf of a visible-normal sample: F G2 / G1
      double weight = jacobian * g2(ix, iy, iz) / g1;
      sum.white += weight;
      sum.fresnel += weight * ggx_schlick(float(f0), oh);
    }
  }
  double n = double(radial) * around;
  sum.white /= n;
  sum.fresnel /= n;
  return sum;
}

}  // namespace

GgxAlbedo ggxAlbedo(double mu, double roughness, double f0, int radial, int around) {
  const float alpha = float(roughness * roughness);
  const float ox = float(std::sqrt(std::max(0.0, 1.0 - mu * mu))), oy = 0.0f, oz = float(mu);
  return visibleNormalAlbedo(
      ox, oy, oz, ggx_g1(ox, oy, oz, alpha), f0, radial, around,
      [&](float u1, float u2, float* hx, float* hy, float* hz) {
        ggx_sample_visible_normal(ox, oy, oz, alpha, u1, u2, hx, hy, hz);
      },
      [&](float ix, float iy, float iz) { return ggx_g2(ox, oy, oz, ix, iy, iz, alpha); });
}

GgxAlbedo ggxAlbedoAniso(double mu, double cos2Phi, double alphaT, double alphaB, double f0, int radial, int around) {
  const double s = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  const double c = std::sqrt(std::clamp(cos2Phi, 0.0, 1.0)), sn = std::sqrt(std::max(0.0, 1.0 - c * c));
  const float ox = float(s * c), oy = float(s * sn), oz = float(mu), at = float(alphaT), ab = float(alphaB);
  return visibleNormalAlbedo(
      ox, oy, oz, ggx_g1_aniso(ox, oy, oz, at, ab), f0, radial, around,
      [&](float u1, float u2, float* hx, float* hy, float* hz) {
        ggx_sample_visible_normal_aniso(ox, oy, oz, at, ab, u1, u2, hx, hy, hz);
      },
      [&](float ix, float iy, float iz) { return ggx_g2_aniso(ox, oy, oz, ix, iy, iz, at, ab); });
}

double pbrAnisoAverage(const std::vector<float>& table, int offset, float alphaT, float alphaB, float rCoord,
                       float kCoord) {
  // (1 / pi) int E cos dw = 4 int_0^1 x^3 dx (2 / pi) int_0^(pi/2) E dphi with mu = x^2,
  // by the midpoint rule over the interpolant the kernels read
  const int nx = 256, nphi = 64;
  double sum = 0.0;
  for (int a = 0; a < nx; ++a) {
    double x = (a + 0.5) / nx, mu = x * x, st = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    double ring = 0.0;
    for (int b = 0; b < nphi; ++b) {
      double phi = 0.5 * M_PI * (b + 0.5) / nphi;
      ring += pbr_aniso_albedo(table.data(), offset, float(st * std::cos(phi)), float(st * std::sin(phi)), float(mu),
                               alphaT, alphaB, rCoord, kCoord);
    }
    sum += 4.0 * x * x * x * ring / nphi;
  }
  return sum / nx;
}

double sheenAlbedo(double mu, double sheenRoughness, int polar, int around) {
  const float alpha = float(sheenRoughness * sheenRoughness);
  const double ox = std::sqrt(std::max(0.0, 1.0 - mu * mu)), oz = mu;
  // wi over the hemisphere: cos(theta_i) = v^2 crowds the grazing directions,
  // where the fibres' lobe lies; phi over [0, pi] twice (the lobe is symmetric about wo's plane)
  double sum = 0.0;
  for (int a = 0; a < polar; ++a) {
    double v = (a + 0.5) / polar, iz = v * v, jacobian = 2.0 * v;
    double s = std::sqrt(std::max(0.0, 1.0 - iz * iz));
    for (int b = 0; b < around; ++b) {
      double phi = M_PI * (b + 0.5) / around;
      double ix = s * std::cos(phi), iy = s * std::sin(phi);
      double hx = ox + ix, hy = iy, hz = oz + iz, len = std::sqrt(hx * hx + hy * hy + hz * hz);
      sum += jacobian * sheen_eval_cos(float(oz), float(iz), float(hz / len), alpha);
    }
  }
  return sum * (1.0 / polar) * (2.0 * M_PI / around);
}

std::vector<float> integratePbrAlbedoTable() {
  const int n = WT_PBR_TABLE_N;
  std::vector<float> t(WT_PBR_TABLE_SIZE, 0.0f);
  // averages 2 int E(mu) mu dmu, by the trapezoid rule on the grid
  auto average = [&](const std::vector<double>& f) {
    double s = 0.0;
    for (int i = 0; i + 1 < n; ++i) {
      double m0 = pbr_table_mu(i), m1 = pbr_table_mu(i + 1);
      s += 0.5 * (f[i] * m0 + f[i + 1] * m1) * (m1 - m0);
    }
    return 2.0 * s;
  };
  for (int j = 0; j < n; ++j) {
    double r = pbr_table_roughness(j), sheenR = pbr_table_sheen_roughness(j);
    std::vector<double> e(n), s(n);
    for (int i = 0; i < n; ++i) {
      double mu = std::max(double(pbr_table_mu(i)), 1e-4);
      GgxAlbedo a = ggxAlbedo(mu, r, 0.0);  // Schlick with F0 = 0: (1 - v.h)^5
      e[i] = a.white;
      s[i] = a.fresnel;
      t[WT_PBR_TABLE_E + j * n + i] = float(e[i]);
      t[WT_PBR_TABLE_S + j * n + i] = float(s[i]);
      t[WT_PBR_TABLE_SHEEN + j * n + i] = float(sheenAlbedo(mu, sheenR));
    }
    t[WT_PBR_TABLE_E_AVG + j] = float(average(e));
    t[WT_PBR_TABLE_S_AVG + j] = float(average(s));
  }
  // the anisotropic lobe: per (k, r_b), its albedos over (c, mu), then their averages
  for (int k = 0; k < WT_ANISO_N_K; ++k)
    for (int j = 0; j < WT_ANISO_N_R; ++j) {
      double rb = pbr_aniso_roughness(j), alphaB = rb * rb;
      double alphaT = pbr_aniso_alpha_t(k, float(alphaB));
      for (int c = 0; c < WT_ANISO_N_C; ++c)
        for (int i = 0; i < WT_ANISO_N_MU; ++i) {
          double x = double(i) / (WT_ANISO_N_MU - 1), mu = std::max(x * x, 1e-4);
          double cos2 = pbr_aniso_view_cos2(float(c) / (WT_ANISO_N_C - 1), float(alphaT), float(alphaB));
          GgxAlbedo a = ggxAlbedoAniso(mu, cos2, alphaT, alphaB, 0.0);
          int at = ((k * WT_ANISO_N_R + j) * WT_ANISO_N_C + c) * WT_ANISO_N_MU + i;
          t[WT_PBR_TABLE_ANISO_E + at] = float(a.white);
          t[WT_PBR_TABLE_ANISO_S + at] = float(a.fresnel);
        }
    }
  for (int k = 0; k < WT_ANISO_N_K; ++k)
    for (int j = 0; j < WT_ANISO_N_R; ++j) {
      float rb = pbr_aniso_roughness(j), alphaB = rb * rb, alphaT = pbr_aniso_alpha_t(k, alphaB);
      t[WT_PBR_TABLE_ANISO_E_AVG + k * WT_ANISO_N_R + j] = float(pbrAnisoAverage(t, WT_PBR_TABLE_ANISO_E, alphaT, alphaB, float(j), float(k)));
      t[WT_PBR_TABLE_ANISO_S_AVG + k * WT_ANISO_N_R + j] = float(pbrAnisoAverage(t, WT_PBR_TABLE_ANISO_S, alphaT, alphaB, float(j), float(k)));
    }
  return t;
}

}  // namespace wt
