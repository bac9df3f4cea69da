// Next-event estimation: pick a light (alias table by power, or uniformly
// among analytic lights for the minimal integrator), sample a point or
// direction on it, and the pdfs MIS needs for lights hit by BSDF sampling.
#ifndef WT_LIGHTS_LIGHT_SAMPLING_CL
#define WT_LIGHTS_LIGHT_SAMPLING_CL

#include "common.h"
#include "shared/lights.h"
#include "lights/environment_adapter.cl"

/// The light list as the shading stage sees it.
typedef struct LightScene {
  __global const WtLight* lights;
  __global const WtAliasSlot* alias;
  uint light_count;
  __global const float4* tri_verts;  ///< for triangle lights, leaf order
  EnvScene env;
} LightScene;

/// A sampled connection from a shading point towards a light.
typedef struct LightSample {
  float3 wi;        ///< unit, world, towards the light
  float distance;   ///< to the sampled point; INFINITY for directional and environment
  float3 radiance;  ///< arriving radiance, or intensity / distance^2 for delta lights
  float pdf;        ///< solid-angle pdf given this light was picked; 1 for delta lights
  int is_delta;     ///< point, spot, directional: BSDF sampling cannot hit these
} LightSample;

/// Pick a light with probability proportional to its power.
inline uint light_pick(LightScene ls, float u, float* pmf) {
  float scaled = u * (float)ls.light_count;
  uint slot = min((uint)scaled, ls.light_count - 1u);
  float remainder = scaled - (float)slot;
  uint chosen = remainder < ls.alias[slot].threshold ? slot : ls.alias[slot].alias;
  *pmf = ls.alias[chosen].pmf;
  return chosen;
}

inline float light_spot_falloff(WtLight light, float3 from_light) {
  // glTF's recommended smooth falloff between the outer and inner cones
  float cd = dot(vec4_xyz(light.direction), from_light);
  float t = clamp((cd - light.cos_outer) / fmax(light.cos_inner - light.cos_outer, 1e-4f), 0.0f, 1.0f);
  return t * t;
}

/// Sample light `index` from shading point p. False when nothing arrives.
inline bool light_sample(LightScene ls, uint index, float3 p, float u1, float u2, LightSample* s) {
  WtLight light = ls.lights[index];
  s->is_delta = 1;
  s->pdf = 1.0f;
  if (light.type == WT_LIGHT_POINT || light.type == WT_LIGHT_SPOT) {
    float3 to_light = vec4_xyz(light.position) - p;
    float d2 = dot(to_light, to_light);
    if (!(d2 > 0.0f)) return false;
    s->distance = sqrt(d2);
    s->wi = to_light / s->distance;
    s->radiance = vec4_xyz(light.intensity) / d2;
    if (light.type == WT_LIGHT_SPOT) s->radiance *= light_spot_falloff(light, -s->wi);
    return true;
  }
  if (light.type == WT_LIGHT_DIRECTIONAL) {
    s->wi = -vec4_xyz(light.direction);
    s->distance = INFINITY;
    s->radiance = vec4_xyz(light.intensity);
    return true;
  }
  s->is_delta = 0;
  if (light.type == WT_LIGHT_TRIANGLE) {
    // uniform by area (the square-root parameterisation), converted to solid angle
    uint t = light.triangle;
    float3 p0 = ls.tri_verts[3 * t].xyz, p1 = ls.tri_verts[3 * t + 1].xyz, p2 = ls.tri_verts[3 * t + 2].xyz;
    float su = sqrt(u1);
    float b1 = su * (1.0f - u2), b2 = su * u2;
    float3 q = (1.0f - b1 - b2) * p0 + b1 * p1 + b2 * p2;
    float3 n = cross(p1 - p0, p2 - p0);
    float area2 = length(n);
    float3 to_light = q - p;
    float d2 = dot(to_light, to_light);
    if (!(area2 > 0.0f) || !(d2 > 0.0f)) return false;
    s->distance = sqrt(d2);
    s->wi = to_light / s->distance;
    // a single-sided light only emits from its front (n) side
    float cos_light = -dot(n, s->wi) / area2;
    if (light.position.w != 0.0f) cos_light = fabs(cos_light);
    if (!(cos_light > 0.0f)) return false;
    s->pdf = (2.0f / area2) * d2 / cos_light;
    s->radiance = vec4_xyz(light.intensity);
    return true;
  }
  // environment
  s->distance = INFINITY;
  s->radiance = env_sample(ls.env, u1, u2, &s->wi, &s->pdf);
  return s->pdf > 0.0f;
}

/// Solid-angle pdf of reaching an emissive triangle by light sampling, as
/// seen from a point at `distance` along unit `wi`; `pdf_area` already holds
/// the selection probability over the triangle's area.
inline float light_triangle_pdf(float pdf_area, float distance, float3 wi, float3 n_geometric) {
  float cos_light = fabs(dot(n_geometric, wi));
  return cos_light > 0.0f ? pdf_area * distance * distance / cos_light : 0.0f;
}

/// MIS weight of a strategy with pdf `a` against one with pdf `b`.
inline float mis_weight(float a, float b, uint flags) {
  if (flags & WT_FLAG_POWER_HEURISTIC) {
    a *= a;
    b *= b;
  }
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

#endif  // WT_LIGHTS_LIGHT_SAMPLING_CL
