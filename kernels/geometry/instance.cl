// Instances (WT_PRIM_INSTANCE): a geometry stored once, in its own "object
// space" (triangles: its tree in `nodes` after the scene's, its triangles in
// tri_verts and tri_info after the scene's; other types: its tree in
// prim_nodes, traversed by kernels/bvh_prims.cl), placed by one affine
// transform per copy. A copy's rows (shared/types.h, WT_INSTANCE_ROWS): object-from-
// scene, then scene-from-object, each a 3x4 matrix in three float4 rows,
// both rounded to float from one double inverse pair on the host
// (host/geometry/instance.cpp). The ray goes into object space unnormalised,
// so a hit's distance t is the scene ray's own and [tmin, tmax] carry over;
// the surface is computed in object space and moved back.
#ifndef WT_GEOMETRY_INSTANCE_CL
#define WT_GEOMETRY_INSTANCE_CL

#include "bvh.cl"

/// Point p by the 3x4 matrix in rows r[0..2] (w: the translation).
inline float3 instance_point(__global const float4* r, float3 p) {
  float4 a = r[0], b = r[1], c = r[2];
  return (float3)(a.x * p.x + a.y * p.y + a.z * p.z + a.w, b.x * p.x + b.y * p.y + b.z * p.z + b.w,
                  c.x * p.x + c.y * p.y + c.z * p.z + c.w);
}

/// Vector v by the linear part of the 3x4 matrix in rows r[0..2].
inline float3 instance_vector(__global const float4* r, float3 v) {
  float4 a = r[0], b = r[1], c = r[2];
  return (float3)(a.x * v.x + a.y * v.y + a.z * v.z, b.x * v.x + b.y * v.y + b.z * v.z,
                  c.x * v.x + c.y * v.y + c.z * v.z);
}

/// Object-space normal n into scene space by the inverse transpose of
/// scene-from-object, i.e. the transpose of object-from-scene (rows inv[0..2]);
/// not normalised. Right for mirroring copies too: the copy's corners were
/// swapped to keep its front face, and the inverse transpose keeps it.
inline float3 instance_normal(__global const float4* inv, float3 n) {
  return n.x * inv[0].xyz + n.y * inv[1].xyz + n.z * inv[2].xyz;
}

/// Closest hit in (tmin, tmax) of the scene ray (org, dir) on the copy whose
/// rows are `rows` and whose geometry's tree starts at node `root`; `skip` is
/// the geometry's leaf-order triangle the ray leaves on this copy (WT_NO_HIT
/// when it leaves another primitive). The hit's prim is the geometry's
/// leaf-order triangle.
inline bool instance_closest(BvhScene scene, __global const float4* rows, uint root, float3 org, float3 dir,
                             float tmin, float tmax, uint skip, Hit* hit) {
  Hit h = bvh_closest_root(scene, root, instance_point(rows, org), instance_vector(rows, dir), tmin, tmax, skip);
  if (h.prim == WT_NO_HIT) return false;
#if WT_BVH_COST
  h.cost = hit->cost;  // the scene tree's count so far (the copy's own tree is not counted)
#endif
  *hit = h;
  return true;
}

/// Whether the copy blocks (tmin, tmax); emitters are never instanced, so
/// only the surface the ray leaves is skipped.
inline bool instance_occluded(BvhScene scene, __global const float4* rows, uint root, float3 org, float3 dir,
                              float tmin, float tmax, uint skip) {
  return bvh_occluded_root(scene, root, instance_point(rows, org), instance_vector(rows, dir), tmin, tmax, skip,
                           WT_NO_HIT);
}

/// An object-space surface (point po with error bound eo, normals ngo and
/// nso, dp/du) of the copy with rows `rows` moved by scene-from-object. The position's error
/// bound grows by the transform's rounding (pbrt-v4's bound for a point with
/// error, gamma(3) on the products and (1 + gamma(3)) on the carried error),
/// with gamma(7) in place of gamma(3) on the products: the ray of the next
/// bounce goes back by the other float matrix, which is the inverse of this
/// one only to a few ulps.
inline void instance_to_scene(__global const float4* rows, float3 po, float3 eo, float3 ngo, float3 nso,
                              float3 dpduo, float3* p, float3* p_error, float3* ng, float3* ns, float3* dpdu) {
  __global const float4* m = rows + 3;  // scene-from-object
  *p = instance_point(m, po);
  float3 r0 = fabs(m[0].xyz), r1 = fabs(m[1].xyz), r2 = fabs(m[2].xyz);
  float3 apo = fabs(po);
  float3 products = (float3)(dot(r0, apo) + fabs(m[0].w), dot(r1, apo) + fabs(m[1].w), dot(r2, apo) + fabs(m[2].w));
  float3 carried = (float3)(dot(r0, eo), dot(r1, eo), dot(r2, eo));
  *p_error = spawn_gamma(7) * products + (1.0f + spawn_gamma(3)) * carried;
  float3 n = instance_normal(rows, ngo);
  float len = length(n);
  *ng = (len > 0.0f && isfinite(len)) ? n / len : (float3)(0.0f);
  float3 s = instance_normal(rows, nso);
  float slen = length(s);
  *ns = (slen > 0.0f && isfinite(slen)) ? s / slen : *ng;
  *dpdu = instance_vector(m, dpduo);
}

/// The scene-space surface at a hit (barycentrics b1, b2) on the geometry's
/// leaf-order triangle `tri` of the copy with rows `rows` (instance_to_scene).
inline void instance_surface(__global const float4* rows, __global const float4* tri_verts,
                             __global const uint4* tri_info, __global const float4* normals, uint tri, float b1,
                             float b2, float3* p, float3* p_error, float3* ng, float3* ns, float3* dpdu) {
  uint4 info = tri_info[tri];
  float3 p0, p1, p2, po, eo, ngo, nso;
  triangle_corners(tri_verts, tri, &p0, &p1, &p2);
  triangle_surface(p0, p1, p2, normals[info.x].xyz, normals[info.y].xyz, normals[info.z].xyz, b1, b2, &po, &eo, &ngo,
                   &nso);
  instance_to_scene(rows, po, eo, ngo, nso, p1 - p0, p, p_error, ng, ns, dpdu);
}

#endif  // WT_GEOMETRY_INSTANCE_CL
