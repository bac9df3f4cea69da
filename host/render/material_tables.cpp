#include "render/material_tables.h"

#include "shared/ggx.h"
#include "shared/materials.h"
#include "shared/sheen.h"

#include <algorithm>
#include <cmath>

namespace wt {

GgxAlbedo ggxAlbedo(double mu, double roughness, double f0, int radial, int around) {
  const float alpha = float(roughness * roughness);
  const float ox = float(std::sqrt(std::max(0.0, 1.0 - mu * mu))), oy = 0.0f, oz = float(mu);
  const float g1 = ggx_g1(ox, oy, oz, alpha);
  GgxAlbedo sum;
  for (int a = 0; a < radial; ++a) {
    double v = (a + 0.5) / radial, w = 1.0 - v;
    float u1 = float(1.0 - w * w * w);
    double jacobian = 3.0 * w * w;
    for (int b = 0; b < around; ++b) {
      float u2 = (float(b) + 0.5f) / float(around);
      float hx, hy, hz;
      ggx_sample_visible_normal(ox, oy, oz, alpha, u1, u2, &hx, &hy, &hz);
      float oh = ox * hx + oy * hy + oz * hz;
      float ix = 2.0f * oh * hx - ox, iy = 2.0f * oh * hy - oy, iz = 2.0f * oh * hz - oz;
      if (iz <= 0.0f) continue;
      // f cos / pdf of a visible-normal sample: F G2 / G1
      double weight = jacobian * ggx_g2(ox, oy, oz, ix, iy, iz, alpha) / g1;
      sum.white += weight;
      sum.fresnel += weight * ggx_schlick(float(f0), oh);
    }
  }
  double n = double(radial) * around;
  sum.white /= n;
  sum.fresnel /= n;
  return sum;
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
    return t;
}

}  // namespace wt
