// Directional albedos of the GGX and sheen lobes, tabulated at build time for
// the energy compensation of the metallic-roughness BSDF and its layers
// (kernels/materials/bsdf.cl): Kulla and Conty 2017's multiple-scattering
// lobe needs E(mu) and its average, the diffuse base under the dielectric's
// specular lobe is scaled by what that lobe leaves (F0 E + (1 - F0) S, E
// and S the split sum of Schlick's Fresnel), and the clear coat and the
// sheen leave the layers below them what they do not reflect.
#pragma once

#include "shared/materials.h"

#include <vector>

namespace wt {

/// The table the kernels read (WT_PBR_TABLE_* layout, shared/materials.h),
/// integrated at build time by host/tools/make_pbr_table.cpp (about 4 s,
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

/// The same for the anisotropic lobe (alpha_t along x, alpha_b along y)
/// seen from cos(theta_o) = mu at an azimuth whose cos^2 from x is cos2Phi;
/// 64 x 32 (the table's, to be paid once per build for its 11 520 entries)
/// is within 2e-4 of 16 times as many points at the tested nodes
/// (SharedTable.AnisotropicAlbedoTable...).
GgxAlbedo ggxAlbedoAniso(double mu, double cos2Phi, double alphaT, double alphaB, double f0, int radial = 64,
                         int around = 32);

/// (1 / pi) int E cos dw of the interpolated anisotropic table at offset
/// (WT_PBR_TABLE_ANISO_E or _S) for continuous (r_b, k) coordinates.
double pbrAnisoAverage(const std::vector<float>& table, int offset, float alphaT, float alphaB, float rCoord,
                       float kCoord);

/// Directional albedo of the sheen lobe (shared/sheen.h) with colour 1 at
/// cos(theta_o) = mu and sheen roughness r (alpha = r^2), by the midpoint
/// rule over wi: `polar` points in v with cos(theta_i) = v^2 (crowding the
/// grazing directions, where the fibres reflect) by `around` in phi.
double sheenAlbedo(double mu, double sheenRoughness, int polar = 96, int around = 48);

}  // namespace wt
