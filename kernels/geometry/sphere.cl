// Analytic spheres. A sphere is one prim_data row, (center xyz, radius),
// and one prim_info row, (material, 0, 0, 0); world space like the triangles.
#ifndef WT_GEOMETRY_SPHERE_CL
#define WT_GEOMETRY_SPHERE_CL

#include "common.h"

/// The nearer root in (tmin, tmax) of a ray with sphere (center, radius);
/// false for none. `leaving`: the ray starts on this sphere's surface (it is
/// the primitive the ray leaves), so its root there is dropped: such a ray
/// can only meet the sphere again at the far root, and only when it heads
/// inwards. The discriminant is taken from the distance between the center
/// and the ray's line (Haines et al., Ray Tracing Gems ch. 7), which keeps
/// small spheres far away, and the roots from the numerically stable
/// quadratic formula, which keeps the near root of large spheres close by.
inline bool sphere_intersect(float4 sphere, float3 o, float3 d, float tmin, float tmax, bool leaving, float* t_hit) {
  float3 f = o - sphere.xyz;
  float r = sphere.w;
  float a = dot(d, d);
  float b = dot(f, d);  // half the linear coefficient
  if (leaving && b >= 0.0f) return false;
  float3 l = f - (b / a) * d;  // from the center to the line's closest point
  float len_l = length(l);
  float disc = a * ((r - len_l) * (r + len_l));  // b^2 - a c, without cancelling b^2 against a c
  if (!(disc >= 0.0f)) return false;
  float c = (dot(f, f) - r * r);
  float q = -(b + copysign(sqrt(disc), b));
  float t0 = c / q, t1 = q / a;
  float near = fmin(t0, t1), far = fmax(t0, t1);
  float t = (!leaving && near > tmin) ? near : far;
  if (!(t > tmin && t < tmax)) return false;
  *t_hit = t;
  return true;
}

/// The surface of a sphere where ray (o, d) meets it at t: the point
/// reprojected onto the sphere (more precise than o + t d) with its
/// rounding error bound, the outward unit normal, uv (u the angle about +Y
/// from +X over 2 pi, v the angle from -Y over pi) and dp/du.
inline void sphere_surface(float4 sphere, float3 o, float3 d, float t, float3* p, float3* p_error, float3* normal,
                           float2* uv, float3* dpdu) {
  float3 center = sphere.xyz;
  float3 q = o + t * d - center;
  float len = length(q);
  float3 n = len > 0.0f ? q / len : (float3)(0.0f, 1.0f, 0.0f);
  float3 rel = sphere.w * n;
  *p = center + rel;
  // the reprojection's error (pbrt-v4's bound for it), then the sum's rounding
  *p_error = spawn_gamma(6) * fabs(rel) + spawn_gamma(2) * fabs(*p);
  *normal = n;
  float phi = wt_atan2(-n.z, n.x);
  if (phi < 0.0f) phi += 2.0f * WT_PI;
  *uv = (float2)(phi * (0.5f / WT_PI), acos(clamp(n.y, -1.0f, 1.0f)) * (-1.0f / WT_PI) + 1.0f);
  *dpdu = (float3)(-2.0f * WT_PI * rel.z, 0.0f, -2.0f * WT_PI * rel.x);
}

/// 1 - cos of the half-angle of the cone a sphere of radius r subtends from
/// squared distance d2 > r^2 to its center, without the cancellation of
/// 1 - cos for small spheres far away.
inline float sphere_cone_one_minus_cos(float r, float d2) {
  float sin2 = fmin(r * r / d2, 1.0f);
  return sin2 / (1.0f + sqrt(1.0f - sin2));
}

/// Solid-angle pdf of sphere_sample_cone from p; 0 where p is inside or
/// on the sphere, which light sampling leaves to BSDF sampling.
inline float sphere_cone_pdf(float4 sphere, float3 p) {
  float3 pc = sphere.xyz - p;
  float d2 = dot(pc, pc);
  if (!(d2 > sphere.w * sphere.w)) return 0.0f;
  return 1.0f / (2.0f * WT_PI * sphere_cone_one_minus_cos(sphere.w, d2));
}

/// A direction uniform in the cone about unit axis w of 1 - cos(half-angle)
/// `one_minus_cos_max` (pdf 1 / (2 pi one_minus_cos_max)), with its angle's
/// cosine and sine from the axis.
inline float3 sphere_cone_direction(float3 w, float one_minus_cos_max, float u1, float u2, float* cos_t, float* sin_t) {
  float one_minus_cos = u1 * one_minus_cos_max;
  *cos_t = 1.0f - one_minus_cos;
  *sin_t = sqrt(fmax(0.0f, one_minus_cos * (2.0f - one_minus_cos)));
  float phi = 2.0f * WT_PI * u2;
  float3 t, b;
  frame_from_normal(w, &t, &b);
  return *cos_t * w + *sin_t * (cos(phi) * t + sin(phi) * b);
}

/// A direction uniform in the cone of directions from p that meet the
/// sphere (pdf sphere_cone_pdf), the distance to the near point it meets
/// and that point pushed outward past its rounding error (where a shadow
/// ray ends). False from inside or on the sphere.
inline bool sphere_sample_cone(float4 sphere, float3 p, float u1, float u2, float3* wi, float* distance,
                               float3* target) {
  float3 pc = sphere.xyz - p;
  float d2 = dot(pc, pc);
  float r = sphere.w;
  if (!(d2 > r * r) || !isfinite(d2)) return false;
  float d = sqrt(d2);
  float cos_t, sin_t;
  float3 dir = sphere_cone_direction(pc / d, sphere_cone_one_minus_cos(r, d2), u1, u2, &cos_t, &sin_t);
  // the near root along dir; reprojected so the point lies on the sphere
  float reach = d * cos_t - sqrt(fmax(0.0f, r * r - d2 * sin_t * sin_t));
  float3 on, on_error, n, dpdu;
  float2 uv;
  sphere_surface(sphere, p, dir, fmax(reach, 0.0f), &on, &on_error, &n, &uv, &dpdu);
  *target = ray_offset_origin(on, on_error, n);
  *wi = dir;
  *distance = length(on - p);
  return *distance > 0.0f;
}

#endif  // WT_GEOMETRY_SPHERE_CL
