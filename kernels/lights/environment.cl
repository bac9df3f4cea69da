// Environment lighting: the radiance arriving from a direction, importance
// sampling of the equirectangular map, and the matching solid-angle pdf.
//
// Convention (OpenEXR's latitude-longitude map, Imf::LatLongMap; world +Y up
// as in glTF). A world direction d is first turned into the map's frame,
// m = R_y(-rotation) d, then
//   longitude = atan2(m.x, m.z)  (0 at +Z, +pi/2 at +X),  theta = angle from +Y
//   u = 0.5 - longitude / (2 pi)   in [0,1]: column floor(u * width)
//   v = theta / pi                 in [0,1]: row floor(v * height), row 0 at +Y
// so +Z is the image centre, +X a quarter of the width from the left, -X three
// quarters, -Z the left/right edge. OpenEXR puts pixel centres at
// x = u * (width - 1); here texel i covers u in [i, i+1) / width, which differs
// by at most half a texel. The map's rotation is about +Y and positive turns
// it counter-clockwise seen from above (+Z towards +X): what the map shows at
// longitude L appears at world longitude L + rotation.
//
// Lookups are nearest-texel, so radiance is constant over a texel, exactly the
// piecewise-constant density that is sampled: luminance x sin(theta of the row
// centre), row by the marginal cdf, then column by the row's conditional cdf
// (binary searches; monotone in u1, u2, so stratified samples stay
// stratified). pdf(u,v) = p_row p_column width height, and
// pdf_solid_angle = pdf(u,v) / (2 pi^2 sin theta).
//
// The constant environment (WT_ENV_CONSTANT) and an all-black map
// (WT_ENV_MAP_UNIFORM) sample the uniform sphere. The three functions take
// the same data arguments; a constant environment needs only `env` (pass any
// valid buffers for the others).
#ifndef WT_LIGHTS_ENVIRONMENT_CL
#define WT_LIGHTS_ENVIRONMENT_CL

#include "common.h"
#include "shared/environment.h"

#define WT_ENV_UNIFORM_PDF (1.0f / (4.0f * WT_PI))

/// World direction -> the map's frame (undo the rotation about +Y).
inline float3 environment_to_map(WtEnvironment env, float3 d) {
  return (float3)(env.cos_rotation * d.x - env.sin_rotation * d.z, d.y,
                  env.sin_rotation * d.x + env.cos_rotation * d.z);
}

/// The map's frame -> world (rotate by `rotation` about +Y).
inline float3 environment_to_world(WtEnvironment env, float3 m) {
  return (float3)(env.cos_rotation * m.x + env.sin_rotation * m.z, m.y,
                  env.cos_rotation * m.z - env.sin_rotation * m.x);
}

/// Texel (column, row) a world direction (any length > 0) falls in, and
/// sin(theta) of the direction itself; sin_theta is 0 or NaN at the poles
/// and for a zero vector.
inline uint2 environment_texel(WtEnvironment env, float3 direction_world, float* sin_theta) {
  float3 m = environment_to_map(env, direction_world);
  float r = sqrt(m.x * m.x + m.z * m.z);
  *sin_theta = r / length(m);
  // atan2(r, y) rather than acos(y): accurate near the poles too
  float u = clamp(0.5f - wt_atan2(m.x, m.z) * (0.5f / WT_PI), 0.0f, 1.0f);
  float v = clamp(wt_atan2(r, m.y) * (1.0f / WT_PI), 0.0f, 1.0f);
  return (uint2)(min((uint)(u * (float)env.width), env.width - 1u),
                 min((uint)(v * (float)env.height), env.height - 1u));
}

/// Largest i in [0, n) with cdf[i] <= u, given cdf[0] = 0 <= u < cdf[n] = 1;
/// then cdf[i] < cdf[i+1], so the chosen bin has probability > 0.
inline uint environment_search(__global const float* cdf, uint n, float u) {
  uint lo = 0u, hi = n;
  while (hi - lo > 1u) {
    uint mid = (lo + hi) >> 1;
    if (cdf[mid] <= u) lo = mid;
    else hi = mid;
  }
  return lo;
}

/// Solid-angle pdf of a texel chosen with probabilities p_row, p_column, at a
/// direction with this sin(theta). Shared by sampling and environment_pdf so
/// both round alike.
inline float environment_texel_pdf(WtEnvironment env, float p_row, float p_column, float sin_theta) {
  float pdf_uv = p_row * p_column * (float)(env.width * env.height);
  return pdf_uv / (2.0f * WT_PI * WT_PI * sin_theta);
}

/// Radiance (nits per channel, intensity applied) arriving from
/// `direction_world` (pointing away from the scene; any length > 0).
/// Nearest texel, no filtering.
inline float3 environment_eval(WtEnvironment env, __global const float4* texels,
                               __global const float* marginal_cdf,
                               __global const float* conditional_cdf, float3 direction_world) {
  if (env.mode == WT_ENV_CONSTANT) return vec4_xyz(env.color) * env.intensity;
  float sin_theta;
  uint2 t = environment_texel(env, direction_world, &sin_theta);
  return texels[t.y * env.width + t.x].xyz * env.intensity;
}

/// Solid-angle pdf with which environment_sample returns `direction_world`,
/// for MIS. 0 where the map is black (and at the exact poles).
inline float environment_pdf(WtEnvironment env, __global const float4* texels,
                             __global const float* marginal_cdf,
                             __global const float* conditional_cdf, float3 direction_world) {
  if (env.mode != WT_ENV_MAP) return WT_ENV_UNIFORM_PDF;
  float sin_theta;
  uint2 t = environment_texel(env, direction_world, &sin_theta);
  if (!(sin_theta > 0.0f)) return 0.0f;
  float p_row = marginal_cdf[t.y + 1u] - marginal_cdf[t.y];
  __global const float* row = conditional_cdf + t.y * (env.width + 1u);
  float p_column = row[t.x + 1u] - row[t.x];
  return environment_texel_pdf(env, p_row, p_column, sin_theta);
}

/// Sample a direction towards the environment from uniforms u1, u2 in [0,1):
/// returns the radiance arriving from it (as environment_eval), the unit
/// world direction and its solid-angle pdf (as environment_pdf; > 0 and
/// finite for a map with energy).
inline float3 environment_sample(WtEnvironment env, __global const float4* texels,
                                 __global const float* marginal_cdf,
                                 __global const float* conditional_cdf, float u1, float u2,
                                 float3* direction_world, float* pdf_solid_angle) {
  if (env.mode != WT_ENV_MAP) {
    // uniform sphere
    float y = 1.0f - 2.0f * u1;
    float r = sqrt(fmax(0.0f, 1.0f - y * y));
    float phi = 2.0f * WT_PI * u2;
    *direction_world = (float3)(r * cos(phi), y, r * sin(phi));
    *pdf_solid_angle = WT_ENV_UNIFORM_PDF;
    return environment_eval(env, texels, marginal_cdf, conditional_cdf, *direction_world);
  }
  // cdf[n] = 1 must stay above u
  const float kBelowOne = 0x1.fffffep-1f;
  u1 = clamp(u1, 0.0f, kBelowOne);
  u2 = clamp(u2, 0.0f, kBelowOne);

  // row, then column within the row
  uint row = environment_search(marginal_cdf, env.height, u1);
  float r0 = marginal_cdf[row];
  float p_row = marginal_cdf[row + 1u] - r0;
  __global const float* cdf = conditional_cdf + row * (env.width + 1u);
  uint column = environment_search(cdf, env.width, u2);
  float c0 = cdf[column];
  float p_column = cdf[column + 1u] - c0;

  // Offset inside the texel, kept off its edges by a few float ULPs of u and
  // v (remapped linearly, still monotone), so that the direction maps back to
  // this texel in environment_pdf and environment_eval despite rounding.
  const float kEdge = 2e-6f;
  float margin_u = fmin(0.25f, kEdge * (float)env.width);
  float margin_v = fmin(0.25f, kEdge * (float)env.height);
  float du = margin_u + clamp((u2 - c0) / p_column, 0.0f, 1.0f) * (1.0f - 2.0f * margin_u);
  float dv = margin_v + clamp((u1 - r0) / p_row, 0.0f, 1.0f) * (1.0f - 2.0f * margin_v);
  float u = ((float)column + du) / (float)env.width;
  float v = ((float)row + dv) / (float)env.height;

  float theta = WT_PI * v, longitude = WT_PI * (1.0f - 2.0f * u);
  float sin_theta = sin(theta);
  float3 m = (float3)(sin_theta * sin(longitude), cos(theta), sin_theta * cos(longitude));
  *direction_world = environment_to_world(env, m);
  // sin_theta > 0: v stays margin_v away from the poles
  *pdf_solid_angle = environment_texel_pdf(env, p_row, p_column, sin_theta);
  return texels[row * env.width + column].xyz * env.intensity;
}

#endif  // WT_LIGHTS_ENVIRONMENT_CL
