// Small kernels that expose shared device code to the tests, which compare
// them with the host build of the same code (tests/kernels/test_shared_code.cpp).
#include "common.h"
#include "materials/lambert.cl"

WT_KERNEL void test_rng(uint count, uint sample, uint bounce, uint dim, uint seed,
                        __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = rng_uniform(i, sample, bounce, dim, seed);
}

// lambert_sample about normal.xyz, or lambert_sample_local (about +z) where normal.w is 1
WT_KERNEL void test_lambert(uint count, float4 normal, __global const float2* u,
                            __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 d = normal.w != 0.0f ? lambert_sample_local(u[i].x, u[i].y) : lambert_sample(normal.xyz, u[i].x, u[i].y);
  out[i] = (float4)(d, 0.0f);
}

#include "geometry/triangle.cl"

// Ray i against the triangles in lanes [lane_lo, lane_hi) of block `block`
// of `blocks` (WT_TRIANGLE_BLOCK), skipping `skip`: out[2i] from
// triangle_intersect4, out[2i + 1] from triangle_intersect one triangle
// after another; (t, b1, b2, prim).
WT_KERNEL void test_intersect4(uint rays, __global const float4* ray_o, __global const float4* ray_d,
                               __global const float4* blocks, uint block, uint lane_lo, uint lane_hi, uint skip,
                               __global float4* out) {
  uint i = get_global_id(0);
  if (i >= rays) return;
  float3 org = ray_o[i].xyz, dir = ray_d[i].xyz;
  float tmin = ray_o[i].w, tmax = ray_d[i].w;
  RayShear shear = triangle_ray_shear(dir);
  float t = 0.0f, b1 = 0.0f, b2 = 0.0f;
  uint prim = triangle_intersect4(org, shear, tmin, tmax, blocks, block, lane_lo, lane_hi, skip, skip, &t, &b1, &b2);
  out[2 * i] = prim == WT_NO_HIT ? (float4)(0.0f, 0.0f, 0.0f, as_float(WT_NO_HIT)) : (float4)(t, b1, b2, as_float(prim));
  float best = tmax, bb1 = 0.0f, bb2 = 0.0f;
  uint best_prim = WT_NO_HIT;
  for (uint k = 4u * block + lane_lo; k < 4u * block + lane_hi; ++k) {
    if (k == skip) continue;
    float3 p0, p1, p2;
    triangle_corners(blocks, k, &p0, &p1, &p2);
    float tk, u, v;
    if (triangle_intersect(org, shear, tmin, best, p0, p1, p2, &tk, &u, &v)) best = tk, bb1 = u, bb2 = v, best_prim = k;
  }
  out[2 * i + 1] = best_prim == WT_NO_HIT ? (float4)(0.0f, 0.0f, 0.0f, as_float(WT_NO_HIT))
                                          : (float4)(best, bb1, bb2, as_float(best_prim));
}

// The point at barycentrics bary[i] of triangle i, spawned off both faces:
// out[2i] on the side of the winding normal, out[2i + 1] on the other.
WT_KERNEL void test_offset(uint count, __global const float4* verts, __global const float2* bary,
                           __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 p0 = verts[3 * i].xyz, p1 = verts[3 * i + 1].xyz, p2 = verts[3 * i + 2].xyz;
  float3 error;
  float3 p = triangle_point(p0, p1, p2, bary[i].x, bary[i].y, &error);
  float3 n = normalize(cross(p1 - p0, p2 - p0));
  out[2 * i] = (float4)(ray_offset_origin(p, error, n), 0.0f);
  out[2 * i + 1] = (float4)(ray_offset_origin(p, error, -n), 0.0f);
}

#include "lights/light_sampling.cl"

WT_KERNEL void test_atan2(uint count, __global const float2* yx, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = wt_atan2(yx[i].x, yx[i].y);
}

WT_KERNEL void test_light_pick(uint count, __global const WtAliasSlot* alias, uint light_count,
                               __global uint* chosen, __global float* pmf) {
  uint i = get_global_id(0);
  if (i >= count) return;
  LightScene ls;
  ls.alias = alias;
  ls.light_count = light_count;
  float p;
  chosen[i] = light_pick(ls, rng_uniform(i, 0u, 0u, 4u, 77u), &p);
  pmf[i] = p;
}

WT_KERNEL void test_mis(uint count, __global const float2* pdfs, uint flags, __global float2* weights) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float2 p = pdfs[i];
  weights[i] = (float2)(mis_weight(p.x, p.y, flags), mis_weight(p.y, p.x, flags));
}

WT_KERNEL void test_sincospi(uint count, __global const float* x, __global float2* sin_cos) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float c;
  float s = wt_sincospi(x[i], &c);
  sin_cos[i] = (float2)(s, c);
}

/// Arvo's spherical-triangle sampling as first written (acos, sin, cos of
/// library calls): the reference light_sample_spherical_triangle must agree with.
inline float3 test_spherical_triangle_arvo(float3 A, float3 B, float3 C, float solid_angle, float u1, float u2) {
  float3 n_ab = light_orthonormal(B, A), n_ac = light_orthonormal(C, A);
  float cos_alpha = clamp(dot(n_ab, n_ac), -1.0f, 1.0f);
  float sin_alpha = sqrt(fmax(0.0f, 1.0f - cos_alpha * cos_alpha));
  float alpha = acos(cos_alpha);
  float area = u1 * solid_angle;
  float s = -sin(area - alpha), t = -cos(area - alpha);
  float cos_c = dot(A, B);
  float k1 = t + cos_alpha, k2 = s - sin_alpha * cos_c;
  float cos_b = (k2 + (k2 * t - k1 * s) * cos_alpha) / ((k2 * s + k1 * t) * sin_alpha);
  cos_b = clamp(cos_b, -1.0f, 1.0f);
  float3 c_prime = cos_b * A + sqrt(fmax(0.0f, 1.0f - cos_b * cos_b)) * n_ac;
  float cos_theta = 1.0f - u2 * (1.0f - dot(c_prime, B));
  float sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  return normalize(cos_theta * B + sin_theta * light_orthonormal(c_prime, B));
}

/// Direction i towards the triangle verts[3 i .. 3 i + 2] from p_of[i] for
/// uniforms u[i]: out[2 i] the sampler's (w, solid angle), out[2 i + 1] the
/// reference's (w, 0).
WT_KERNEL void test_spherical_triangle(uint count, __global const float4* verts, __global const float4* p_of,
                                       __global const float2* u, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 p = p_of[i].xyz, p0 = verts[3 * i].xyz, p1 = verts[3 * i + 1].xyz, p2 = verts[3 * i + 2].xyz;
  float omega = light_triangle_solid_angle(p, p0, p1, p2);
  float3 A = normalize(p0 - p), B = normalize(p1 - p), C = normalize(p2 - p);
  out[2 * i] = (float4)(light_sample_spherical_triangle(A, B, C, omega, u[i].x, u[i].y), omega);
  out[2 * i + 1] = (float4)(test_spherical_triangle_arvo(A, B, C, omega, u[i].x, u[i].y), 0.0f);
}

/// Rectangle i, views[4 i ..]: (p, two-sided), (c, 1 / area), e1, e2, sampled
/// from p with uniforms u[i] by light_sample_rect: out[3 i] (wi, distance),
/// out[3 i + 1] (s, t, the sampler's pdf, the emission's pdf light_quad_pdf
/// gives the same direction with selection 1 / area), out[3 i + 2]
/// (solid angle, 1 where sampled, 0).
WT_KERNEL void test_quad_sample(uint count, __global const float4* views, __global const float2* u,
                                __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 p = views[4 * i].xyz, c = views[4 * i + 1].xyz, e1 = views[4 * i + 2].xyz, e2 = views[4 * i + 3].xyz;
  LightSample s;
  float2 st = (float2)(0.0f);
  bool ok = light_sample_rect(p, c, e1, e2, views[4 * i].w != 0.0f, u[i].x, u[i].y, &s, &st);
  float pdf_hit = 0.0f;
  if (ok) pdf_hit = light_quad_pdf(views[4 * i + 1].w, p, c, e1, e2, s.distance, s.wi, normalize(cross(e1, e2)));
  out[3 * i] = ok ? (float4)(s.wi, s.distance) : (float4)(0.0f);
  out[3 * i + 1] = (float4)(st, ok ? s.pdf : 0.0f, pdf_hit);
  out[3 * i + 2] = (float4)(light_quad_solid_angle(p, c, e1, e2), ok ? 1.0f : 0.0f, 0.0f, 0.0f);
}

/// light_quad_pdf of rectangle views[4 i ..] (as test_quad_sample's) for the
/// direction and distance dirs[i] (wi, distance): out[i].
WT_KERNEL void test_quad_pdf(uint count, __global const float4* views, __global const float4* dirs, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 p = views[4 * i].xyz, c = views[4 * i + 1].xyz, e1 = views[4 * i + 2].xyz, e2 = views[4 * i + 3].xyz;
  out[i] = light_quad_pdf(views[4 * i + 1].w, p, c, e1, e2, dirs[i].w, dirs[i].xyz, normalize(cross(e1, e2)));
}

#include "shared/sampler.h"
#include "sampler.cl"

/// Item i draws pair 2 (i % 6) of pixel i with sampler_get2 and with
/// sampler_get twice: (pair, single, single).
WT_KERNEL void test_sampler_pairs(uint count, WtFrameParams frame, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  uint dim = 2u * (i % 6u);
  float2 pair = sampler_get2(frame, i, dim);
  out[i] = (float4)(pair, sampler_get(frame, i, dim), sampler_get(frame, i, dim + 1u));
}

WT_KERNEL void test_sobol(uint count, uint pixel, uint bounce, uint dim, uint seed, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = sampler_sobol(pixel, i, bounce, dim, seed);
}

#include "stress.cl"  // test_accumulate, which `wavetrace stress` runs too

#include "materials/bsdf.cl"

// bsdf_sample for `count` triples of uniforms (u_lobe, u1, u2): the local
// direction and mixture pdf (w = -1: nothing sampled), the weight and lobe.
// wo.w != 0: seen from inside (the back face).
WT_KERNEL void test_bsdf_sample(uint count, WtMaterial material, float4 wo, uint lobes,
                                __global const float* table, __global const float4* u,
                                __global float4* wi_pdf, __global float4* weight_lobe, float4 coat_n) {
  uint i = get_global_id(0);
  if (i >= count) return;
  Bsdf b = bsdf_make(material, table, wo.w != 0.0f);
  bsdf_coat_normal(&b, coat_n.xyz);
  BsdfSample s;
  if (bsdf_sample(b, wo.xyz, lobes, u[i].x, u[i].y, u[i].z, &s)) {
    wi_pdf[i] = (float4)(s.wi, s.pdf);
    weight_lobe[i] = (float4)(s.weight, as_float(s.lobe));
  } else {
    wi_pdf[i] = (float4)(0.0f, 0.0f, 0.0f, -1.0f);
    weight_lobe[i] = (float4)(0.0f);
  }
}

// bsdf_eval for `count` local directions: f cos and the mixture pdf.
WT_KERNEL void test_bsdf_eval(uint count, WtMaterial material, float4 wo, uint lobes,
                              __global const float* table, __global const float4* wi, __global float4* out,
                              float4 coat_n) {
  uint i = get_global_id(0);
  if (i >= count) return;
  Bsdf b = bsdf_make(material, table, wo.w != 0.0f);
  bsdf_coat_normal(&b, coat_n.xyz);
  float pdf;
  float3 f = bsdf_eval(b, wo.xyz, wi[i].xyz, lobes, &pdf);
  out[i] = (float4)(f, pdf);
}

#include "materials/textured.cl"

// KHR_materials_anisotropy's shading frame (materials/textured.cl) at a
// point with `tangent` (w: the bitangent's sign) and interpolated normal n,
// the shading normal ns: frame[0] = (t, strength), frame[1] = (b, 0); then
// bsdf_eval in that frame for `count` world directions wi, seen from world
// wo: out[i] = (f cos, pdf).
WT_KERNEL void test_anisotropic_eval(uint count, WtMaterial material, float4 tangent, float4 n, float4 ns, float4 wo,
                                     __global const float* table, __global const float4* wi, __global float4* frame,
                                     __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  SurfaceScene ss = {0, 0, 0, 0, 0, 0, 0};
  SurfacePoint sp;
  sp.uv = (float4)(0.0f);
  sp.uv_scale = (float2)(0.0f);
  sp.color = (float4)(1.0f);
  sp.tangent = tangent.xyz;
  sp.sign = tangent.w;
  sp.footprint = 0.0f;
  float3 dir = anisotropy_direction(ss, 0u, &material, sp, n.xyz);
  float3 t, b;
  frame_from_normal(ns.xyz, &t, &b);
  anisotropy_frame(dir, ns.xyz, &t, &b);
  if (i == 0) frame[0] = (float4)(t, material.anisotropy), frame[1] = (float4)(b, 0.0f);
  float3 o = (float3)(dot(wo.xyz, t), dot(wo.xyz, b), dot(wo.xyz, ns.xyz));
  float3 w = (float3)(dot(wi[i].xyz, t), dot(wi[i].xyz, b), dot(wi[i].xyz, ns.xyz));
  Bsdf bsdf = bsdf_make(material, table, 0);
  float pdf;
  float3 f = bsdf_eval(bsdf, o, w, WT_LOBE_DIFFUSE | WT_LOBE_SPECULAR, &pdf);
  out[i] = (float4)(f, pdf);
}

#if WT_HAS_IRIDESCENCE
// KHR_materials_iridescence's film Fresnel (shared/iridescence.h) for
// `count` cosines: film = (outside ior, film ior, thickness nm), f0 the
// base's F0 per channel; out[i] = (rgb, 0).
WT_KERNEL void test_iridescence_fresnel(uint count, float4 film, float4 f0, __global const float* cos1,
                                        __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float f[3];
  iridescence_fresnel(film.x, film.y, f0.x, f0.y, f0.z, film.z, cos1[i], f);
  out[i] = (float4)(f[0], f[1], f[2], 0.0f);
}
#endif

#include "lights/light_tree.cl"

// light_tree_pick at (p, n) for `count` uniforms: the light index and pmf.
WT_KERNEL void test_light_tree_pick(uint count, __global const WtLightNode* nodes, float4 p, float4 n,
                                    __global const float* u, __global uint* chosen, __global float* pmf) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float q;
  chosen[i] = light_tree_pick(nodes, p.xyz, n.xyz, u[i], &q);
  pmf[i] = q;
}

// light_tree_pmf at (p, n) for `count` leaves.
WT_KERNEL void test_light_tree_pmf(uint count, __global const WtLightNode* nodes, __global const uint* leaves,
                                   float4 p, float4 n, __global float* pmf) {
  uint i = get_global_id(0);
  if (i >= count) return;
  pmf[i] = light_tree_pmf(nodes, leaves[i], p.xyz, n.xyz);
}

// light_tree_importance2 of sibling pair (first[i], first[i] + 1) at p[i] with normal n[i].
WT_KERNEL void test_light_tree_importance2(uint count, __global const WtLightNode* nodes, __global const uint* first,
                                           __global const float4* p, __global const float4* n, __global float2* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  out[i] = light_tree_importance2(&nodes[first[i]], p[i].xyz, n[i].xyz);
}

// Nested dielectrics (shared/media.h): walk i meets the boundaries
// steps[i * step_count + j] = (material, entering), starting outside every
// volume and crossing each one it meets (transmitted, or passed as a false
// hit). out per step: (real, n near, n far, as_float(the current entry's
// material after the step, WT_MEDIUM_NONE: none)); stacks: the stack after it.
WT_KERNEL void test_media_walk(uint count, uint step_count, __global const WtMaterial* materials,
                               __global const uint2* steps, __global float4* out, __global uint4* stacks) {
  uint i = get_global_id(0);
  if (i >= count) return;
  WtMediaStack s = {{WT_MEDIUM_NONE, WT_MEDIUM_NONE, WT_MEDIUM_NONE, WT_MEDIUM_NONE}};
  for (uint j = 0; j < step_count; ++j) {
    uint2 step = steps[i * step_count + j];
    WtMediaCrossing c = media_crossing(&s, materials, step.x, (int)step.y);
    media_cross(&s, materials, step.x, (int)step.y);
    int current = media_current(&s, materials);
    out[i * step_count + j] = (float4)(as_float(c.real), c.ior_near, c.ior_far,
                                       as_float(current < 0 ? WT_MEDIUM_NONE : s.id[current]));
    stacks[i * step_count + j] = (uint4)(s.id[0], s.id[1], s.id[2], s.id[3]);
  }
}

// KHR_materials_dispersion's index per channel (shared/media.h): out[3i + c]
// for (ior, dispersion) = pairs[i].
WT_KERNEL void test_media_channel_ior(uint count, __global const float2* pairs, __global float* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  for (uint c = 0; c < WT_DISPERSION_CHANNELS; ++c) out[3u * i + c] = media_channel_ior(pairs[i].x, pairs[i].y, c);
}
