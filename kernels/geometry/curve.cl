// Round curves as linear swept spheres (docs/curves.md):
// segment k of a curve is the convex hull of its two joint spheres (p0, r0)
// and (p1, r1), a round cone -- the surface swept by a sphere whose centre
// and radius move linearly from one joint to the other (Embree's round
// linear curve). B-splines reach the device already subdivided into such
// segments (host/geometry/curve.cpp).
//
// Rows: segment k is prim_data rows 2k and 2k + 1, its joints as (x, y, z,
// radius), world space; a radius with its sign bit set (-0 included) says
// the curve has no segment beyond that joint. Otherwise the neighbours are
// segments k - 1 (rows 2k - 2, 2k - 1) and k + 1 (rows 2k + 2, 2k + 3), which
// share the joint. prim_info row k: (material, curve index, u at p0, u at p1),
// the u's as float bits (the curve's parameter, 0 at its root, 1 at its tip).
//
// The hulls of consecutive segments overlap around their shared joint.
// A hit inside a neighbour's hull is not on the curve's surface: the test
// drops it (as Embree cuts the neighbours' cones away), so rays from inside
// a curve meet its wall once and closest hits never depend on which of two
// segments reports a joint.
#ifndef WT_GEOMETRY_CURVE_CL
#define WT_GEOMETRY_CURVE_CL

#include "common.h"

/// The parameter s in [0, 1] of the sphere, among those swept from a (s = 0)
/// to b (s = 1), nearest to the point a.xyz + h: where the sphere's surface
/// touches the point's side of the hull. e = b - a, dr = rb - ra. When one
/// joint sphere holds the other (|dr| >= |e|) the hull is the larger one.
inline float curve_sphere_param(float3 e, float dr, float3 h) {
  float l2 = dot(e, e);
  float g = l2 - dr * dr;
  if (!(g > 0.0f)) return dr > 0.0f ? 1.0f : 0.0f;
  float sg = sqrt(g);
  // along the axis, plus the cone's slope times the distance from the axis
  float s = (dot(h, e) * sg + dr * length(cross(h, e))) / (l2 * sg);
  return clamp(s, 0.0f, 1.0f);
}

/// Signed distance from p to the hull of joint spheres a and b (radii >= 0
/// in w), negative inside; *n: the outward unit normal of the nearest
/// surface point (zero on the axis), *s: its sweep parameter.
inline float curve_hull_distance(float4 a, float4 b, float3 p, float3* n, float* s) {
  float3 e = b.xyz - a.xyz;
  float dr = b.w - a.w;
  float3 h = p - a.xyz;
  *s = curve_sphere_param(e, dr, h);
  float3 v = h - *s * e;  // from the nearest sphere's centre
  float len = length(v);
  *n = len > 0.0f ? v / len : (float3)(0.0f);
  return len - (a.w + *s * dr);
}

/// Widen [*lo, *hi] by the roots of ray (o, d) with the sphere (c, r), dd =
/// d.d: the discriminant from the line's distance to the centre (Haines et
/// al., as sphere_intersect does), the roots by the stable quadratic formula.
inline void curve_sphere_roots(float3 c, float r, float3 o, float3 d, float dd, float* lo, float* hi) {
  if (!(r > 0.0f)) return;
  float3 f = o - c;
  float b = dot(f, d);
  float3 l = f - (b / dd) * d;
  float len_l = length(l);
  float disc = dd * ((r - len_l) * (r + len_l));
  if (!(disc >= 0.0f)) return;
  float q = -(b + copysign(sqrt(disc), b));
  float t0 = (dot(f, f) - r * r) / q, t1 = q / dd;  // NaN when q = 0 (a grazing ray through the centre's plane): fmin/fmax skip it
  *lo = fmin(*lo, fmin(t0, t1));
  *hi = fmax(*hi, fmax(t0, t1));
}

/// Widen [*lo, *hi] by the roots of ray (o, d) with the lateral surface of
/// the round cone of a and b: the cone tangent to both spheres, kept
/// between its circles of contact. In the axis frame (unit axis x, slope
/// s = dr / |e|, c = sqrt(1 - s^2)) the cone is c |q| = ra + s z, q the
/// point's offset from the axis and z its position along it, which makes
/// A t^2 + 2 B t + C = 0 with A = c^2 |dq|^2 - s^2 dz^2, B = c^2 q0.dq -
/// s dz R0, C = c^2 |q0|^2 - R0^2 (R0 = ra + s z0). Its discriminant
/// B^2 - A C equals c^2 (|R0 dq - s dz q0|^2 - c^2 |q0 x dq|^2): a
/// difference of two lengths, whose terms do not cancel for segments much
/// longer than thick as the expanded form's do.
inline void curve_cone_roots(float4 a, float4 b, float3 o, float3 d, float* lo, float* hi) {
  float3 e = b.xyz - a.xyz;
  float dr = b.w - a.w;
  float l2 = dot(e, e);
  float g = l2 - dr * dr;
  if (!(g > 0.0f)) return;  // one sphere holds the other: no cone
  float len = sqrt(l2);
  float3 axis = e / len;
  float s = dr / len, c = sqrt(g) / len;
  float3 w = o - a.xyz;
  float z0 = dot(w, axis), dz = dot(d, axis);
  float3 q0 = w - z0 * axis, dq = d - dz * axis;
  float r0 = a.w + s * z0;
  float cq = c * length(q0);
  float A = c * c * dot(dq, dq) - s * s * dz * dz;
  float B = c * c * dot(q0, dq) - s * dz * r0;
  float C = (cq - r0) * (cq + r0);
  float un = length(r0 * dq - (s * dz) * q0);
  float xn = c * length(cross(q0, dq));
  float disc = c * c * ((un - xn) * (un + xn));
  if (!(disc >= 0.0f)) return;
  float q = -(B + copysign(sqrt(disc), B));
  // A or q near 0 (a ray along a generator or the axis) sends a root to
  // infinity or NaN, which the range check drops
  float t0 = q / A, t1 = C / q;
  float z_lo = -a.w * s, z_hi = len - b.w * s;  // the circles of contact
  float za = z0 + t0 * dz, zb = z0 + t1 * dz;
  if (za >= z_lo && za <= z_hi) {
    *lo = fmin(*lo, t0);
    *hi = fmax(*hi, t0);
  }
  if (zb >= z_lo && zb <= z_hi) {
    *lo = fmin(*lo, t1);
    *hi = fmax(*hi, t1);
  }
}

/// A segment's two joint rows (its prim_data rows, or the same values in
/// the leaf joints) with their radii made positive; *left and *right:
/// whether the curve goes on past p0 and past p1.
inline void curve_segment(__global const float4* joints, float4* a, float4* b, bool* left, bool* right) {
  *a = joints[0];
  *b = joints[1];
  *left = !signbit(a->w);
  *right = !signbit(b->w);
  a->w = fabs(a->w);
  b->w = fabs(b->w);
}

/// Whether point p lies inside a neighbour of segment k deeper than `margin`
/// (a hit there is inside the curve, not on its surface).
inline bool curve_inside_neighbour(__global const float4* rows, uint k, bool left, bool right, float3 p,
                                   float margin) {
  float3 n;
  float s;
  if (left) {
    float4 a = rows[2u * k - 2u], b = rows[2u * k - 1u];
    a.w = fabs(a.w);
    b.w = fabs(b.w);
    if (curve_hull_distance(a, b, p, &n, &s) < -margin) return true;
  }
  if (right) {
    float4 a = rows[2u * k + 2u], b = rows[2u * k + 3u];
    a.w = fabs(a.w);
    b.w = fabs(b.w);
    if (curve_hull_distance(a, b, p, &n, &s) < -margin) return true;
  }
  return false;
}

inline float curve_max3(float3 v) { return fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z))); }

inline float4 curve_max3_4(float4 x, float4 y, float4 z) { return fmax(fabs(x), fmax(fabs(y), fabs(z))); }

/// Whether the ray through o along unit dn passes wider of each of four
/// segments (joint spheres rows 2k and 2k + 1 of j, k = 0..3, the radii's
/// sign bits as in prim_data; radius -infinity: no curve, never missed) than the segment's larger radius, by
/// curve_intersect's bound and its rounding margin, in float4 lanes: every
/// hit of a segment lies within that radius of its axis.
inline int4 curve_segments_missed4(__global const float4* j, float3 o, float3 dn) {
  float4 a0 = j[0], b0 = j[1], a1 = j[2], b1 = j[3], a2 = j[4], b2 = j[5], a3 = j[6], b3 = j[7];
  float4 ax = (float4)(a0.x, a1.x, a2.x, a3.x), ay = (float4)(a0.y, a1.y, a2.y, a3.y);
  float4 az = (float4)(a0.z, a1.z, a2.z, a3.z), ar = fabs((float4)(a0.w, a1.w, a2.w, a3.w));
  float4 ex = (float4)(b0.x, b1.x, b2.x, b3.x) - ax, ey = (float4)(b0.y, b1.y, b2.y, b3.y) - ay;
  float4 ez = (float4)(b0.z, b1.z, b2.z, b3.z) - az, br = fabs((float4)(b0.w, b1.w, b2.w, b3.w));
  float4 wx = ax - o.x, wy = ay - o.y, wz = az - o.z;
  float4 wd = wx * dn.x + wy * dn.y + wz * dn.z, ed = ex * dn.x + ey * dn.y + ez * dn.z;
  wx -= wd * dn.x, wy -= wd * dn.y, wz -= wd * dn.z;
  ex -= ed * dn.x, ey -= ed * dn.y, ez -= ed * dn.z;
  float4 ee = ex * ex + ey * ey + ez * ez;
  float4 s = select((float4)(0.0f), clamp(-(wx * ex + wy * ey + wz * ez) / ee, 0.0f, 1.0f), ee > 0.0f);
  float4 gx = wx + s * ex, gy = wy + s * ey, gz = wz + s * ez;
  float4 r = fmax(ar, br);
  // the unprojected e's size, as curve_intersect's margin
  float4 e_max = curve_max3_4((float4)(b0.x, b1.x, b2.x, b3.x) - ax, (float4)(b0.y, b1.y, b2.y, b3.y) - ay,
                              (float4)(b0.z, b1.z, b2.z, b3.z) - az);
  float4 reach = r * 1.001f + spawn_gamma(32) * (curve_max3(o) + curve_max3_4(ax, ay, az) + e_max + r);
  return gx * gx + gy * gy + gz * gz > reach * reach;  // (an infinite reach never misses)
}

/// Ray (o, d) against curve segment k in (tmin, tmax): the distance and the
/// sweep parameter u in [0, 1] from p0 to p1. `joints`: its two rows, read
/// from the leaf joints in a walk (in cache after the leaf's reject; the
/// neighbours' rows are read only for a root about to be reported).
/// `leaving`: the ray starts on this segment's surface (it is the primitive
/// the ray leaves).
///
/// The roots are taken from an origin moved along the ray to where it
/// passes the segment's middle, so a ray from afar keeps the precision of
/// one from close by. The hull is convex, so a ray meets its surface at
/// most twice, at the least and the greatest of the roots of its two
/// spheres and its cone. A ray that starts on the surface (the segment it
/// leaves, or any segment within rounding of its origin: the neighbours
/// sharing a joint) and heads out of the hull cannot meet it again; one
/// heading in meets it at the far root only. Roots inside a neighbour's
/// hull are dropped.
inline bool curve_intersect(__global const float4* rows, uint k, __global const float4* joints, float3 o, float3 d,
                            float tmin, float tmax, bool leaving, float* t_hit, float* u_hit) {
  float4 a, b;
  bool left, right;
  curve_segment(joints, &a, &b, &left, &right);
  float3 n_o;
  float s_o;
  if (leaving) {
    // headed out of the hull it leaves: no hit whatever the roots (on_surface's test below, done first)
    curve_hull_distance(a, b, o, &n_o, &s_o);
    if (dot(d, n_o) >= 0.0f) return false;
  }
  float dd = dot(d, d);
  float t_mid = dot(0.5f * (a.xyz + b.xyz) - o, d) / dd;
  float3 o_mid = o + t_mid * d;
  // Most segments a ray is tested against it misses: first the cheap bound,
  // the hull lies within max(ra, rb) of the segment from a to b. The ray's
  // line passes the segment's points at distance |w_perp + s e_perp| (the
  // parts across the ray), least at the s below.
  float3 e_ab = b.xyz - a.xyz;
  float3 w = a.xyz - o_mid;
  float3 w_perp = w - (dot(w, d) / dd) * d;
  float3 e_perp = e_ab - (dot(e_ab, d) / dd) * d;
  float ee = dot(e_perp, e_perp);
  float s_near = ee > 0.0f ? clamp(-dot(w_perp, e_perp) / ee, 0.0f, 1.0f) : 0.0f;
  float3 gap = w_perp + s_near * e_perp;
  float r_max = fmax(a.w, b.w);
  // wide of the rounding of o_mid, of the projections and of the radii
  float reach = r_max * 1.001f + spawn_gamma(32) * (curve_max3(o_mid) + curve_max3(a.xyz) + curve_max3(e_ab) + r_max);
  if (dot(gap, gap) > reach * reach) return false;
#if !(defined(WT_NO_PREFETCH) && WT_NO_PREFETCH)
  // a ray this near mostly hits: ask for the neighbours' rows (a root's test
  // below reads them, scattered from the leaf joints) while its roots are solved
  if (left) __builtin_prefetch(rows + 2u * k - 2u, 0, 3);
  if (right) __builtin_prefetch(rows + 2u * k + 2u, 0, 3);
#endif
  float lo = INFINITY, hi = -INFINITY;
  curve_cone_roots(a, b, o_mid, d, &lo, &hi);
  curve_sphere_roots(a.xyz, a.w, o_mid, d, dd, &lo, &hi);
  curve_sphere_roots(b.xyz, b.w, o_mid, d, dd, &lo, &hi);
  if (!(lo <= hi)) return false;
  float t_in = t_mid + lo, t_out = t_mid + hi;
  if (!(t_out > tmin) || !(t_in < tmax)) return false;

  // the scale of the coordinates and of the segment, for rounding bounds
  float scale = curve_max3(a.xyz) + length(b.xyz - a.xyz) + fmax(a.w, b.w);
  // a ray that starts on the hull's surface (within rounding of it)
  float dist_o = curve_hull_distance(a, b, o, &n_o, &s_o);
  // (wider than a spawned ray's offset, which is at most about gamma(11) of that)
  bool on_surface = leaving || fabs(dist_o) <= spawn_gamma(16) * (curve_max3(o) + scale);
  if (on_surface) {
    if (dot(d, n_o) >= 0.0f) return false;  // heads out of a convex hull
    t_in = t_out;                           // heads in: its start is not a hit
  }
  float3 e = b.xyz - a.xyz;
  for (int i = 0; i < 2; ++i) {
    float t = i == 0 ? t_in : t_out;
    if (i == 1 && t_out == t_in) break;
    if (!(t > tmin && t < tmax)) continue;
    float3 p = o_mid + (t - t_mid) * d;
    // p's rounding: a point of the surface is never thought inside
    float margin = spawn_gamma(8) * (curve_max3(o) + fabs(t) * curve_max3(d) + scale);
    if ((left || right) && curve_inside_neighbour(rows, k, left, right, p, margin)) continue;
    *t_hit = t;
    *u_hit = curve_sphere_param(e, b.w - a.w, p - a.xyz);
    return true;
  }
  return false;
}

/// The surface of segment k where ray (o, d) meets it at t: the point
/// reprojected onto the nearest swept sphere (so onto the hull) with its
/// rounding error bound, the outward unit normal, uv (u along the curve
/// from info's u at p0 to u at p1, v the angle around the axis over 2 pi)
/// and dp/du (along the axis).
inline void curve_surface(__global const float4* rows, uint k, uint4 info, float3 o, float3 d, float t, float3* p,
                          float3* p_error, float3* normal, float2* uv, float3* dpdu) {
  float4 a, b;
  bool left, right;
  curve_segment(rows + 2u * k, &a, &b, &left, &right);
  float3 e = b.xyz - a.xyz;
  float dr = b.w - a.w;
  float3 h = o + t * d - a.xyz;
  float s = curve_sphere_param(e, dr, h);
  float3 along = s * e;
  float3 v = h - along;
  float len = length(v);
  float3 axis = normalize(e);
  float3 tangent, bitangent;
  frame_from_normal(axis, &tangent, &bitangent);
  float3 n = len > 0.0f ? v / len : tangent;
  float3 rel = (a.w + s * dr) * n;
  *p = a.xyz + (along + rel);
  // the sums' rounding; the nearest sphere's own error moves p along the
  // surface, not off it
  *p_error = spawn_gamma(6) * (fabs(along) + fabs(rel)) + spawn_gamma(3) * (fabs(a.xyz) + fabs(*p));
  *normal = n;
  float u0 = as_float(info.z), u1 = as_float(info.w);
  float phi = wt_atan2(dot(n, bitangent), dot(n, tangent));
  if (phi < 0.0f) phi += 2.0f * WT_PI;
  *uv = (float2)(u0 + s * (u1 - u0), phi * (0.5f / WT_PI));
  *dpdu = u1 > u0 ? e / (u1 - u0) : e;
}

#endif  // WT_GEOMETRY_CURVE_CL
