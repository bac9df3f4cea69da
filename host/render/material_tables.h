// Directional albedos of the GGX lobe, tabulated once per process for the
// energy compensation of the metallic-roughness BSDF (kernels/materials/pbr.cl):
// Kulla and Conty 2017's multiple-scattering lobe needs E(mu) and its
// average, and the diffuse base under the dielectric coat is scaled by what
// the coat leaves, 1 - E_coat(mu).
#pragma once

#include "shared/materials.h"

#include <vector>

namespace wt {

/// The table the kernels read (WT_PBR_TABLE_* layout, shared/materials.h),
/// integrated at build time by host/tools/make_pbr_table.cpp (about 0.5 s,
/// too long to pay at every start).
const std::vector<float>& pbrAlbedoTable();

/// Integrate the table (what the build embeds).
std::vector<float> integratePbrAlbedoTable();

/// Directional albedos of the GGX single-scattering lobe at cos(theta_o) =
/// mu and roughness r (alpha = r^2): with F = 1, and with Schlick Fresnel
/// of reflectance f0 at normal incidence.
struct GgxAlbedo {
  double white = 0.0;    ///< F = 1
  double fresnel = 0.0;  ///< Schlick F(f0)
};

/// Integrated over the visible-normal parameterisation (u1, u2) by the
/// midpoint rule, `radial` points in u1 = 1 - (1 - v)^3 (which crowds the
/// grazing microfacets of the distribution's tail, where the lost energy
/// is) and `around` points in u2; 128 x 24 (the table's) is within 1e-4 of
/// the converged value.
GgxAlbedo ggxAlbedo(double mu, double roughness, double f0, int radial = 128, int around = 24);

}  // namespace wt
