// Triangle geometry: watertight ray/triangle intersection (Woop, Benthin and
// Wald 2013) and the surface data a shading stage needs.
#ifndef WT_GEOMETRY_TRIANGLE_CL
#define WT_GEOMETRY_TRIANGLE_CL

#include "common.h"

/// Per-ray constants of the watertight test: the axis permutation that makes
/// kz the dominant direction axis, and the shear that maps the ray to +z.
typedef struct RayShear {
  int kx, ky, kz;
  float sx, sy, sz;
} RayShear;

inline RayShear triangle_ray_shear(float3 d) {
  RayShear s;
  float3 ad = fabs(d);
  s.kz = (ad.x > ad.y) ? (ad.x > ad.z ? 0 : 2) : (ad.y > ad.z ? 1 : 2);
  s.kx = s.kz == 2 ? 0 : s.kz + 1;
  s.ky = s.kx == 2 ? 0 : s.kx + 1;
  float dz = vec3_component(d, s.kz);
  // Keep the winding of the sheared triangle independent of the ray's sign.
  if (dz < 0.0f) {
    int tmp = s.kx;
    s.kx = s.ky;
    s.ky = tmp;
  }
  s.sx = vec3_component(d, s.kx) / dz;
  s.sy = vec3_component(d, s.ky) / dz;
  s.sz = 1.0f / dz;
  return s;
}

/// Hit in (tmin, tmax): writes the distance and the barycentrics of p1 and p2.
/// The reference form of triangle_intersect4, which traversal uses and which
/// must give the same answers (SharedCode.FourLaneTriangleTestMatchesOneByOne).
/// Forced inline: PoCL otherwise calls it per triangle, which traversal cannot
/// afford (docs/lab/2026-11-23-performance-log.md, "After forcing").
__attribute__((always_inline)) inline bool triangle_intersect(float3 org, RayShear s, float tmin, float tmax, float3 p0,
                               float3 p1, float3 p2, float* t_hit, float* b1, float* b2) {
  float3 a = p0 - org;
  float3 b = p1 - org;
  float3 c = p2 - org;
  float az = vec3_component(a, s.kz), bz = vec3_component(b, s.kz), cz = vec3_component(c, s.kz);
  float ax = vec3_component(a, s.kx) - s.sx * az;
  float ay = vec3_component(a, s.ky) - s.sy * az;
  float bx = vec3_component(b, s.kx) - s.sx * bz;
  float by = vec3_component(b, s.ky) - s.sy * bz;
  float cx = vec3_component(c, s.kx) - s.sx * cz;
  float cy = vec3_component(c, s.ky) - s.sy * cz;

  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
#if WT_HAS_FP64
  // An edge function of exactly zero is ambiguous in float: decide it in double
  // so that a ray through a shared edge hits exactly one of the two triangles.
  if (u == 0.0f || v == 0.0f || w == 0.0f) {
    u = (float)((double)cx * (double)by - (double)cy * (double)bx);
    v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
    w = (float)((double)bx * (double)ay - (double)by * (double)ax);
  }
#endif
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
  float det = u + v + w;
  if (det == 0.0f) return false;

  float t_scaled = u * s.sz * az + v * s.sz * bz + w * s.sz * cz;
  float inv_det = 1.0f / det;
  float t = t_scaled * inv_det;
  if (!(t > tmin && t < tmax)) return false;

  *t_hit = t;
  *b1 = v * inv_det;
  *b2 = w * inv_det;
  return true;
}

/// Leaf-order triangle `prim` in the block layout of tri_verts (shared/types.h,
/// WT_TRIANGLE_BLOCK): float4 row 3k + a of block prim / 4 holds axis a of
/// corner k for its four triangles. This is the triangle's lane as floats:
/// element 12 k + 4 a is axis a of corner k.
inline __global const float* triangle_block_lane(__global const float4* tri_verts, uint prim) {
  return (__global const float*)(tri_verts + WT_TRIANGLE_BLOCK_ROWS * (prim >> 2)) + (prim & 3u);
}

/// The three corners of leaf-order triangle `prim`.
inline void triangle_corners(__global const float4* tri_verts, uint prim, float3* p0, float3* p1, float3* p2) {
  __global const float* f = triangle_block_lane(tri_verts, prim);
  *p0 = (float3)(f[0], f[4], f[8]);
  *p1 = (float3)(f[12], f[16], f[20]);
  *p2 = (float3)(f[24], f[28], f[32]);
}

/// The four lanes of a block's test (triangle_test4_k): which lanes hit, and
/// each lane's distance and barycentric terms (b1 = v inv_det, b2 = w inv_det).
typedef struct TriangleLanes {
  int4 ok;  ///< non-zero: the lane's triangle is hit in (tmin, tmax) and not skipped
  float4 t, v, w, inv_det;
} TriangleLanes;

/// The watertight test of triangle_intersect on float4 lanes, one triangle
/// per lane, with the same operations in the same order (so the same
/// answers): corner k's coordinates less the ray's origin on the ray's
/// permuted axes (kx, ky, kz) in xk, yk, zk. ok: the lane is hit in (tmin,
/// tmax). Loads nothing, for callers whose corners are not stored
/// (displaced micro-triangles) as well as for triangle_test4_k.
WT_INLINE_STRUCT TriangleLanes triangle_test4_lanes(RayShear s, float tmin, float tmax, float4 x0, float4 y0,
                                                    float4 z0, float4 x1, float4 y1, float4 z1, float4 x2,
                                                    float4 y2, float4 z2) {
  float4 az = z0, bz = z1, cz = z2;
  float4 ax = x0 - s.sx * az;
  float4 ay = y0 - s.sy * az;
  float4 bx = x1 - s.sx * bz;
  float4 by = y1 - s.sy * bz;
  float4 cx = x2 - s.sx * cz;
  float4 cy = y2 - s.sy * cz;

  float4 u = cx * by - cy * bx;
  float4 v = ax * cy - ay * cx;
  float4 w = bx * ay - by * ax;
#if WT_HAS_FP64
  // exactly-zero edge functions decided in double, lane by lane (rare)
  int4 zero = (u == 0.0f) | (v == 0.0f) | (w == 0.0f);
  if (zero.s0 | zero.s1 | zero.s2 | zero.s3) {
#define WT_EDGE_IN_DOUBLE(l)                                                                   \
  if (u.l == 0.0f || v.l == 0.0f || w.l == 0.0f) {                                             \
    u.l = (float)((double)cx.l * (double)by.l - (double)cy.l * (double)bx.l);                  \
    v.l = (float)((double)ax.l * (double)cy.l - (double)ay.l * (double)cx.l);                  \
    w.l = (float)((double)bx.l * (double)ay.l - (double)by.l * (double)ax.l);                  \
  }
    WT_EDGE_IN_DOUBLE(s0) WT_EDGE_IN_DOUBLE(s1) WT_EDGE_IN_DOUBLE(s2) WT_EDGE_IN_DOUBLE(s3)
#undef WT_EDGE_IN_DOUBLE
  }
#endif
  // inside: no edge function of either sign against another (as the one-triangle test)
  int4 inside = ((u >= 0.0f) & (v >= 0.0f) & (w >= 0.0f)) | ((u <= 0.0f) & (v <= 0.0f) & (w <= 0.0f));
  float4 det = u + v + w;
  float4 t_scaled = u * s.sz * az + v * s.sz * bz + w * s.sz * cz;
  float4 inv_det = 1.0f / det;
  float4 t = t_scaled * inv_det;
  TriangleLanes h;
  h.ok = inside & (det != 0.0f) & (t > tmin) & (t < tmax);
  h.t = t;
  h.v = v;
  h.w = w;
  h.inv_det = inv_det;
  return h;
}

/// The hits in (tmin, tmax) of the triangles of block `block`
/// (leaf-order triangles 4 block + lane) whose lanes lie in [lane_lo,
/// lane_hi), but skip_a and skip_b, tested at once (triangle_test4_lanes).
/// The block's rows are
/// already one axis of one corner for the four triangles: the ray's axes
/// (kx, ky, kz) pick rows, no shuffle. triangle_nearest4 picks the nearest
/// lane; traversal with the alpha test (bvh_block_hit, kernels/bvh.cl)
/// drops the lanes whose surface has a hole there and picks again. This
/// form takes the ray's origin already on its permuted axes (o_k = (org[kx],
/// org[ky], org[kz]), triangle_origin_k), for callers that keep it per ray
/// (streams test many leaves with each ray).
WT_INLINE_STRUCT TriangleLanes triangle_test4_k(float3 o_k, RayShear s, float tmin, float tmax,
                                                __global const float4* tri_verts, uint block, uint lane_lo,
                                                uint lane_hi, uint skip_a, uint skip_b) {
  __global const float4* r = tri_verts + WT_TRIANGLE_BLOCK_ROWS * block;
  float ox = o_k.x, oy = o_k.y, oz = o_k.z;
  float4 vx[3], vy[3], vz[3];
#pragma unroll
  for (int k = 0; k < 3; ++k) {
    vx[k] = r[3 * k + s.kx] - ox;
    vy[k] = r[3 * k + s.ky] - oy;
    vz[k] = r[3 * k + s.kz] - oz;
  }
  TriangleLanes h = triangle_test4_lanes(s, tmin, tmax, vx[0], vy[0], vz[0], vx[1], vy[1], vz[1], vx[2], vy[2], vz[2]);
  uint4 lane = (uint4)(0u, 1u, 2u, 3u);
  uint4 index = (uint4)(4u * block) + lane;
  h.ok = h.ok & (lane >= (uint4)(lane_lo)) & (lane < (uint4)(lane_hi)) & (index != (uint4)(skip_a)) &
         (index != (uint4)(skip_b));
  return h;
}

/// The nearest of a block's lanes that hit (h.ok has one at least): its
/// leaf-order triangle, distance and barycentrics; ties go to the lower
/// index, as testing the triangles one by one would.
__attribute__((always_inline)) inline uint triangle_nearest4(TriangleLanes h, uint block, float* t_hit, float* b1,
                                                             float* b2) {
  int4 ok = h.ok;
  float4 t = h.t, v = h.v, w = h.w, inv_det = h.inv_det;
  float4 tt = (float4)(ok.s0 ? t.s0 : INFINITY, ok.s1 ? t.s1 : INFINITY, ok.s2 ? t.s2 : INFINITY, ok.s3 ? t.s3 : INFINITY);
  float best = fmin(fmin(tt.s0, tt.s1), fmin(tt.s2, tt.s3));
  int l = (ok.s0 && tt.s0 == best) ? 0 : (ok.s1 && tt.s1 == best) ? 1 : (ok.s2 && tt.s2 == best) ? 2 : 3;
  float inv = l == 0 ? inv_det.s0 : l == 1 ? inv_det.s1 : l == 2 ? inv_det.s2 : inv_det.s3;
  float vl = l == 0 ? v.s0 : l == 1 ? v.s1 : l == 2 ? v.s2 : v.s3;
  float wl = l == 0 ? w.s0 : l == 1 ? w.s1 : l == 2 ? w.s2 : w.s3;
  *t_hit = best;
  *b1 = vl * inv;
  *b2 = wl * inv;
  return 4u * block + (uint)l;
}

/// Whether any lane of a block's test hit. Lanes are combined with & and |
/// and tested for non-zero, never by their sign bit (any, select) or with ~:
/// Oclgrind's optimised build makes some of these comparisons 1 instead of -1.
inline bool triangle_any4(TriangleLanes h) { return (h.ok.s0 | h.ok.s1 | h.ok.s2 | h.ok.s3) != 0; }

/// The nearest hit among a block's lanes (triangle_test4_k, triangle_nearest4):
/// its triangle, or WT_NO_HIT.
__attribute__((always_inline)) inline uint triangle_intersect4_k(float3 o_k, RayShear s, float tmin, float tmax,
                                                                 __global const float4* tri_verts, uint block,
                                                                 uint lane_lo, uint lane_hi, uint skip_a, uint skip_b,
                                                                 float* t_hit, float* b1, float* b2) {
  TriangleLanes h = triangle_test4_k(o_k, s, tmin, tmax, tri_verts, block, lane_lo, lane_hi, skip_a, skip_b);
  if (!triangle_any4(h)) return WT_NO_HIT;
  return triangle_nearest4(h, block, t_hit, b1, b2);
}

/// The ray's origin on its permuted axes, as triangle_test4_k takes it.
inline float3 triangle_origin_k(float3 org, RayShear s) {
  return (float3)(vec3_component(org, s.kx), vec3_component(org, s.ky), vec3_component(org, s.kz));
}

/// triangle_intersect4_k for a ray whose origin is in world axes.
__attribute__((always_inline)) inline uint triangle_intersect4(float3 org, RayShear s, float tmin, float tmax,
                                                               __global const float4* tri_verts, uint block,
                                                               uint lane_lo, uint lane_hi, uint skip_a, uint skip_b,
                                                               float* t_hit, float* b1, float* b2) {
  return triangle_intersect4_k(triangle_origin_k(org, s), s, tmin, tmax, tri_verts, block, lane_lo, lane_hi, skip_a,
                               skip_b, t_hit, b1, b2);
}

/// Point with barycentrics (1 - b1 - b2, b1, b2) on triangle (p0, p1, p2),
/// and the rounding error bound of each of its coordinates.
inline float3 triangle_point(float3 p0, float3 p1, float3 p2, float b1, float b2, float3* error) {
  float b0 = 1.0f - b1 - b2;
  *error = (float3)(spawn_barycentric_error(b0, b1, b2, p0.x, p1.x, p2.x),
                    spawn_barycentric_error(b0, b1, b2, p0.y, p1.y, p2.y),
                    spawn_barycentric_error(b0, b1, b2, p0.z, p1.z, p2.z));
  return b0 * p0 + b1 * p1 + b2 * p2;
}

/// Surface at a hit: position from the barycentrics (more precise than
/// o + t*d) with its error bound, unit geometric normal (zero for a
/// degenerate triangle) and the interpolated shading normal (the geometric
/// one where the file has none).
inline void triangle_surface(float3 p0, float3 p1, float3 p2, float3 n0, float3 n1, float3 n2,
                             float b1, float b2, float3* position, float3* position_error,
                             float3* n_geometric, float3* n_shading) {
  float b0 = 1.0f - b1 - b2;
  *position = triangle_point(p0, p1, p2, b1, b2, position_error);
  float3 e1 = p1 - p0, e2 = p2 - p0;
  float3 ng = cross(e1, e2);
  float len = length(ng);
  if (!(len > 1e-30f && len < 1e30f)) {
    // the cross product under- or overflowed (edges below 1e-15 or above
    // 1e15): take it again with the edges scaled to about unit length
    float3 a1 = fabs(e1), a2 = fabs(e2);
    float scale = 1.0f / fmax(fmax(fmax(a1.x, a1.y), a1.z), fmax(fmax(a2.x, a2.y), a2.z));
    ng = cross(e1 * scale, e2 * scale);
    len = length(ng);
  }
  *n_geometric = (len > 0.0f && isfinite(len)) ? ng / len : (float3)(0.0f);
  float3 ns = b0 * n0 + b1 * n1 + b2 * n2;
  bool has_normals = dot(n0, n0) > 0.0f && dot(n1, n1) > 0.0f && dot(n2, n2) > 0.0f;
  float ns_len = length(ns);
  *n_shading = (has_normals && ns_len > 0.0f) ? ns / ns_len : *n_geometric;
}

#endif  // WT_GEOMETRY_TRIANGLE_CL
