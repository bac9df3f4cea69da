// Arbitrary output variables, compiled in only with WT_AOV (a render that
// asks for them, RenderSettings::aovs). Per pixel, each sample's values go to
// aov_sample (written by shade), accumulate adds them to aov_accum; the ids
// of the first sample go to aov_ids. Albedo and normal are a denoiser's
// (OIDN's) guides: those of the first hit that is not a perfect mirror or
// smooth glass (a specular chain is followed), the environment's radiance
// where the path escapes first. The buffers' layout: aov_fold.cl.
#ifndef WT_AOV_CL
#define WT_AOV_CL

#include "common.h"
#include "shared/materials.h"
#include "aov_fold.cl"

#if WT_AOV

/// A material whose every lobe is a delta (a smooth metal, a smooth fully
/// transmitting dielectric): the albedo and normal guides look through it.
inline bool aov_specular_only(WtMaterial m) {
  if (m.model != WT_MATERIAL_PBR || m.roughness >= WT_PBR_MIN_ROUGHNESS) return false;
  if (m.sheen.x > 0.0f || m.sheen.y > 0.0f || m.sheen.z > 0.0f) return false;
  if (m.clearcoat > 0.0f && m.clearcoat_roughness >= WT_PBR_MIN_ROUGHNESS) return false;
  if (m.base_color.w >= 1.0f) return true;  // metallic
#if WT_HAS_TRANSMISSION
  return m.transmission >= 1.0f;
#else
  return false;
#endif
}

/// Every sample starts with nothing found (shade at the camera ray).
inline void aov_begin(__global float4* a) {
  a[0] = (float4)(0.0f);
  a[1] = (float4)(0.0f);
  a[2] = (float4)(0.0f, 0.0f, 0.0f, INFINITY);
#if WT_BVH_COST
  a[3] = (float4)(0.0f, 0.0f, a[3].z, 0.0f);  // z: extend's count for this sample's camera ray
#else
  a[3] = (float4)(0.0f);
#endif
}

/// The path escaped with radiance `le` from the environment (0 where hidden).
inline void aov_miss(__global float4* a, float3 le) {
  if (a[0].w == 0.0f) a[0] = (float4)(le, 1.0f);
}

/// The path hit material `m` with shading normal `n` facing the ray.
inline void aov_surface(__global float4* a, WtMaterial m, float3 n) {
  float4 n_count = a[1];
  n_count.w += 1.0f;
  if (a[0].w == 0.0f) {
    float3 albedo = vec4_xyz(m.base_color);
    float3 le = vec4_xyz(m.emission);
    float peak = fmax(le.x, fmax(le.y, le.z));
    // an emitter's guide is its colour (the emission scaled to a peak of 1)
    if (peak > 0.0f) albedo = fmin(albedo + le / peak, (float3)(1.0f));
    bool through = aov_specular_only(m);
    // on a specular chain the colour stays as a fallback where the path ends there
    a[0] = (float4)(albedo, through ? 0.0f : 1.0f);
    n_count.xyz = n;
  }
  a[1] = n_count;
}

/// The camera ray's hit: where, how far, and its surface coordinates.
inline void aov_camera_hit(__global float4* a, float3 p, float distance, float2 uv) {
  a[2] = (float4)(p, distance);
  a[3] = (float4)(uv, a[3].z, 1.0f);
}

#endif  // WT_AOV
#endif  // WT_AOV_CL
