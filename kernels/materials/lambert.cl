// Cosine-weighted sampling: the diffuse lobe of every material (the
// Lambertian model and the metallic-roughness base and sheen in bsdf.cl,
// sampled about +z of the shading frame), so a Lambertian estimator's
// weight f * cos / pdf is exactly the albedo.
#ifndef WT_MATERIALS_LAMBERT_CL
#define WT_MATERIALS_LAMBERT_CL

#include "common.h"

/// A cosine-distributed direction about +z (the local shading frame's
/// normal) from two uniforms in [0,1): unit up to rounding, no frame to build.
inline float3 lambert_sample_local(float u1, float u2) {
  float r = sqrt(u1);
  float cos_phi;
  float sin_phi = wt_sincospi(2.0f * u2, &cos_phi);  // phi = 2 pi u2
  return (float3)(r * cos_phi, r * sin_phi, sqrt(fmax(0.0f, 1.0f - u1)));
}

/// The same about a world-space unit normal n.
inline float3 lambert_sample(float3 n, float u1, float u2) {
  float3 l = lambert_sample_local(u1, u2);
  float3 t, b;
  frame_from_normal(n, &t, &b);
  return normalize(l.x * t + l.y * b + l.z * n);
}

#endif  // WT_MATERIALS_LAMBERT_CL
