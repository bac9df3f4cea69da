// The geometry interface: every primitive type but triangles is reached
// through the three switches below (ray test, surface at a hit, emitter
// sampling), one case per type, each compiled only when the scene has that
// type (WT_HAS_<TYPE>). Triangles keep their own BVH and vector leaf tests
// (kernels/bvh.cl); the other types share one BVH whose leaves are ranges
// of typed ids (prim_refs), traversed by kernels/bvh_prims.cl after the
// triangles'. docs/architecture.md, "Adding a geometry type", lists what a
// new type touches.
#ifndef WT_GEOMETRY_GEOMETRY_CL
#define WT_GEOMETRY_GEOMETRY_CL

#include "common.h"
#include "geometry/triangle.cl"
// The instance case (instance.cl) traverses triangles, which bring the alpha
// test and the surface it reads (materials/alpha.cl, textured.cl): included
// here, outside the switch below, because the host expands each include once,
// where it first appears (expandKernelSource), and a later includer (light
// sampling) needs textured.cl whether instances are compiled in or not.
#include "bvh.cl"

// SDF grids' light sampling uses a sphere's cone (sdf_grid.cl includes it too)
#if WT_HAS_SPHERES || WT_HAS_SDF_GRIDS
#include "geometry/sphere.cl"
#endif
#if WT_HAS_CURVES
#include "geometry/curve.cl"
#endif
#if WT_HAS_INSTANCES
#include "geometry/instance.cl"
#endif
#if WT_HAS_SDF_GRIDS
#include "geometry/sdf_grid.cl"
#endif
#if WT_HAS_DISPLACED
#include "geometry/displaced.cl"
#endif

/// Whether any type beside triangles is compiled in (the primitive BVH is traversed).
#define WT_HAS_PRIMITIVES (0 WT_GEOMETRY_TYPES(WT_GEOMETRY_OR_SWITCH))

/// The non-triangle primitives as the kernels see them (WtGeometry).
typedef struct GeometryScene {
  WtGeometry header;
  __global const WtBvh4Node* nodes;  ///< their BVH; leaves index refs
  __global const uint* refs;         ///< typed ids in leaf order
  __global const float4* data;       ///< per type's rows (WtGeometry::data_first)
  __global const uint4* info;        ///< per type's rows (WtGeometry::info_first); x = material
} GeometryScene;

/// The kernel parameters that carry a GeometryScene (host: bindGeometry, device/scene_args.h;
/// declared as kGeometryParams in device/kernel_args.h).
#define WT_GEOMETRY_PARAMS                                                                                    \
  WtGeometry geometry, __global const WtBvh4Node *prim_nodes, __global const uint *prim_refs,                 \
      __global const float4 *prim_data, __global const uint4 *prim_info
#define WT_GEOMETRY_SCENE {geometry, prim_nodes, prim_refs, prim_data, prim_info}

inline uint prim_type(uint prim) { return prim >> WT_PRIM_TYPE_SHIFT; }
inline uint prim_index(uint prim) { return prim & WT_PRIM_INDEX_MASK; }

/// The first row of primitive `prim` in prim_data.
inline __global const float4* geometry_data(GeometryScene g, uint prim) {
  return g.data + g.header.data_first[prim_type(prim)] + prim_index(prim);
}

#if WT_HAS_INSTANCES
/// Instance `prim`'s rows in prim_data (WT_INSTANCE_ROWS).
inline __global const float4* geometry_instance_rows(GeometryScene g, uint prim) {
  return g.data + g.header.data_first[WT_PRIM_INSTANCE] + WT_INSTANCE_ROWS * prim_index(prim);
}

/// Instance `prim`'s prim_info row: x its geometry's root node, y WT_INSTANCE_* flags.
inline uint4 geometry_instance_info(GeometryScene g, uint prim) {
  return g.info[g.header.info_first[WT_PRIM_INSTANCE] + prim_index(prim)];
}

/// The instance case of the ray tests. Not a case of geometry_intersect: an
/// instance's hit is a triangle of its geometry (hit->prim, leaf order) found
/// by the triangles' own traversal, and the primitive it belongs to is the
/// instance (the caller's hit_instance). The surface a ray leaves is a
/// (triangle, instance) pair: the triangle is skipped on that copy only.
inline bool geometry_instance_closest(BvhScene scene, GeometryScene g, uint prim, float3 o, float3 d, float tmin,
                                      uint skip, uint skip_instance, Hit* hit) {
#if WT_HAS_ALPHA
  scene.alpha.ray = rng_alpha_instance(scene.alpha.ray, prim);  // each copy's holes of its own (stochastic ones)
#endif
  return instance_closest(scene, geometry_instance_rows(g, prim), geometry_instance_info(g, prim).x, o, d, tmin,
                          hit->t, prim == skip_instance ? skip : WT_NO_HIT, hit);
}

inline bool geometry_instance_occluded(BvhScene scene, GeometryScene g, uint prim, float3 o, float3 d, float tmin,
                                       float tmax, uint skip, uint skip_instance) {
#if WT_HAS_ALPHA
  scene.alpha.ray = rng_alpha_instance(scene.alpha.ray, prim);
#endif
  return instance_occluded(scene, geometry_instance_rows(g, prim), geometry_instance_info(g, prim).x, o, d, tmin, tmax,
                           prim == skip_instance ? skip : WT_NO_HIT);
}
#endif

/// Ray (o, d) against primitive `prim` in (tmin, tmax): the distance and the
/// type's own hit parameters (u, v), which geometry_surface takes back. A
/// primitive the ray leaves (skip_a) or aims at (skip_b) is never met at the
/// ray's start. With `any_hit` (shadow rays) a type may return any hit in
/// the interval rather than its nearest (displaced meshes stop at the first).
inline bool geometry_intersect(GeometryScene g, uint prim, float3 o, float3 d, float tmin, float tmax, uint skip_a,
                               uint skip_b, bool any_hit, float* t, float* u, float* v) {
  bool leaving = prim == skip_a || prim == skip_b;
  *u = 0.0f;
  *v = 0.0f;
  switch (prim_type(prim)) {
#if WT_HAS_SPHERES
    case WT_PRIM_SPHERE:
      return sphere_intersect(*geometry_data(g, prim), o, d, tmin, tmax, leaving, t);
#endif
#if WT_HAS_CURVES
    case WT_PRIM_CURVE:
      return curve_intersect(g.data + g.header.data_first[WT_PRIM_CURVE], prim_index(prim),
                             g.data + g.header.data_first[WT_PRIM_CURVE] + 2u * prim_index(prim), o, d, tmin, tmax,
                             leaving, t, u);
#endif
#if WT_HAS_SDF_GRIDS
    case WT_PRIM_SDF_GRID:
      return sdf_intersect(g.data + g.header.data_first[WT_PRIM_SDF_GRID],
                           g.info + g.header.info_first[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * prim_index(prim), o, d,
                           tmin, tmax, t, u);
#endif
#if WT_HAS_DISPLACED
    case WT_PRIM_DISPLACED:
      return displaced_intersect(g.data + g.header.data_first[WT_PRIM_DISPLACED],
                                 g.info + g.header.info_first[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * prim_index(prim),
                                 o, d, tmin, tmax, any_hit, t, u, v);
#endif
    default:
      return false;
  }
}

/// geometry_intersect on entry `entry` of the primitive tree's leaves: a
/// curve segment's joints come from the leaf joints the leaf's reject has
/// just read, not from its own rows, a cache miss per segment tested.
inline bool geometry_intersect_entry(GeometryScene g, uint entry, uint prim, float3 o, float3 d, float tmin, float tmax,
                                     uint skip_a, uint skip_b, bool any_hit, float* t, float* u, float* v) {
#if WT_HAS_CURVES
  if (prim_type(prim) == WT_PRIM_CURVE) {
    *u = 0.0f;
    *v = 0.0f;
    __global const float4* rows = g.data + g.header.data_first[WT_PRIM_CURVE];
    __global const float4* joints = g.data + g.header.leaf_joints + WT_LEAF_JOINT_ROWS * entry;
    return curve_intersect(rows, prim_index(prim), joints, o, d, tmin, tmax, prim == skip_a || prim == skip_b, t, u);
  }
#endif
  return geometry_intersect(g, prim, o, d, tmin, tmax, skip_a, skip_b, any_hit, t, u, v);
}

/// The surface at a hit, for shading.
typedef struct SurfaceHit {
  float3 p;        ///< world position, computed from the primitive (not o + t d)
  float3 p_error;  ///< rounding error bound per coordinate of p
  float3 ng;       ///< unit geometric normal: the winding's for triangles, outward for closed types; zero: degenerate
  float3 ns;       ///< unit shading normal
  float2 uv;       ///< surface parameters: spheres by angle; curves along (0 to 1 from root to tip) and around; triangles their barycentrics (b1, b2) until texture coordinates reach the device; displaced meshes their texture coordinates
  float3 dpdu;     ///< dp/du, world (triangles: the edge p1 - p0)
  uint material;   ///< index into materials
} SurfaceHit;

/// The surface of a primitive that is not an instance's triangle, in the
/// space of the ray (o, d): geometry_surface's switch.
inline SurfaceHit geometry_local_surface(GeometryScene g, __global const float4* tri_verts,
                                         __global const uint4* tri_info, __global const float4* normals, uint prim,
                                         float3 o, float3 d, float4 hit) {
  SurfaceHit s;
  switch (prim_type(prim)) {
#if WT_HAS_SPHERES
    case WT_PRIM_SPHERE: {
      sphere_surface(*geometry_data(g, prim), o, d, hit.x, &s.p, &s.p_error, &s.ng, &s.uv, &s.dpdu);
      s.ns = s.ng;
      s.material = g.info[g.header.info_first[WT_PRIM_SPHERE] + prim_index(prim)].x;
      return s;
    }
#endif
#if WT_HAS_CURVES
    case WT_PRIM_CURVE: {
      uint4 info = g.info[g.header.info_first[WT_PRIM_CURVE] + prim_index(prim)];
      curve_surface(g.data + g.header.data_first[WT_PRIM_CURVE], prim_index(prim), info, o, d, hit.x, &s.p,
                    &s.p_error, &s.ng, &s.uv, &s.dpdu);
      s.ns = s.ng;
      s.material = info.x;
      return s;
    }
#endif
#if WT_HAS_SDF_GRIDS
    case WT_PRIM_SDF_GRID: {
      uint4 info = g.info[g.header.info_first[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * prim_index(prim)];
      sdf_surface(g.data + g.header.data_first[WT_PRIM_SDF_GRID], info, o, d, hit.x, hit.y, &s.p, &s.p_error, &s.ng,
                  &s.uv, &s.dpdu);
      s.ns = s.ng;
      s.material = info.x;
      return s;
    }
#endif
#if WT_HAS_DISPLACED
    case WT_PRIM_DISPLACED: {
      __global const uint4* tri = g.info + g.header.info_first[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * prim_index(prim);
      displaced_surface(g.data + g.header.data_first[WT_PRIM_DISPLACED], tri, hit.y, hit.z, &s.p, &s.p_error, &s.ng,
                        &s.ns, &s.uv, &s.dpdu);
      s.material = tri[0].x;
      return s;
    }
#endif
    default: {
      uint4 info = tri_info[prim];  // the corners' vertex indices and the material
      float3 p0, p1, p2;
      triangle_corners(tri_verts, prim, &p0, &p1, &p2);
      triangle_surface(p0, p1, p2, normals[info.x].xyz, normals[info.y].xyz, normals[info.z].xyz, hit.y, hit.z, &s.p,
                       &s.p_error, &s.ng, &s.ns);
      s.uv = (float2)(hit.y, hit.z);
      s.dpdu = p1 - p0;
      s.material = info.w;
      return s;
    }
  }
}

/// The surface where ray (o, d) hit primitive `prim`; `hit` is the stored
/// (t, u, v, prim); `instance` the instance hit (prim then its geometry's
/// leaf-order triangle or typed id), WT_NO_HIT for none.
inline SurfaceHit geometry_surface(GeometryScene g, __global const float4* tri_verts, __global const uint4* tri_info,
                                   __global const float4* normals, uint prim, uint instance, float3 o, float3 d,
                                   float4 hit) {
#if WT_HAS_INSTANCES
  if (instance != WT_NO_HIT) {
    SurfaceHit s;
    __global const float4* rows = geometry_instance_rows(g, instance);
    if (prim_type(prim) == WT_PRIM_TRIANGLE) {
      instance_surface(rows, tri_verts, tri_info, normals, prim, hit.y, hit.z, &s.p, &s.p_error, &s.ng, &s.ns,
                       &s.dpdu);
      s.uv = (float2)(hit.y, hit.z);
      s.material = tri_info[prim].w;
      return s;
    }
    // the other types: the surface in object space (t carries over), moved back
    s = geometry_local_surface(g, tri_verts, tri_info, normals, prim, instance_point(rows, o),
                               instance_vector(rows, d), hit);
    instance_to_scene(rows, s.p, s.p_error, s.ng, s.ns, s.dpdu, &s.p, &s.p_error, &s.ng, &s.ns, &s.dpdu);
    return s;
  }
#endif
  return geometry_local_surface(g, tri_verts, tri_info, normals, prim, o, d, hit);
}

/// A point of non-triangle emitter `prim` sampled from p, as solid angle:
/// the direction, the distance, where a shadow ray ends, and the pdf. False
/// when the type cannot be sampled from p or the sample carries nothing
/// (a back face where only the front emits: `two_sided` false).
inline bool geometry_sample_emitter(GeometryScene g, uint prim, float3 p, float u1, float u2, bool two_sided,
                                    float3* wi, float* distance, float3* target, float* pdf) {
  switch (prim_type(prim)) {
#if WT_HAS_SPHERES
    case WT_PRIM_SPHERE: {
      float4 sphere = *geometry_data(g, prim);
      *pdf = sphere_cone_pdf(sphere, p);
      return *pdf > 0.0f && sphere_sample_cone(sphere, p, u1, u2, wi, distance, target);
    }
#endif
#if WT_HAS_SDF_GRIDS
    case WT_PRIM_SDF_GRID:
      return sdf_sample_emitter(g.data + g.header.data_first[WT_PRIM_SDF_GRID],
                                g.info + g.header.info_first[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * prim_index(prim), p,
                                u1, u2, two_sided, wi, distance, target, pdf);
#endif
#if WT_HAS_DISPLACED
    case WT_PRIM_DISPLACED:
      return displaced_sample_emitter(
          g.data + g.header.data_first[WT_PRIM_DISPLACED],
          g.info + g.header.info_first[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * prim_index(prim), p, u1, u2,
          two_sided, wi, distance, target, pdf);
#endif
    default:
      return false;
  }
}

/// The solid-angle pdf with which geometry_sample_emitter reaches emitter
/// `prim` from `origin` (0: it cannot), before the emitter's selection, at
/// the hit `hit` (the stored (t, u, v, prim)) whose surface is p with unit
/// geometric normal ng.
inline float geometry_emitter_pdf(GeometryScene g, uint prim, float3 origin, float3 p, float3 ng, float4 hit) {
  switch (prim_type(prim)) {
#if WT_HAS_SPHERES
    case WT_PRIM_SPHERE:
      return sphere_cone_pdf(*geometry_data(g, prim), origin);
#endif
#if WT_HAS_SDF_GRIDS
    case WT_PRIM_SDF_GRID:
      return sdf_emitter_pdf(g.data + g.header.data_first[WT_PRIM_SDF_GRID],
                             g.info + g.header.info_first[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * prim_index(prim),
                             origin, p);
#endif
#if WT_HAS_DISPLACED
    case WT_PRIM_DISPLACED:
      return displaced_emitter_pdf(
          g.data + g.header.data_first[WT_PRIM_DISPLACED],
          g.info + g.header.info_first[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * prim_index(prim), origin, p, ng,
          hit.y, hit.z);
#endif
    default:
      return 0.0f;
  }
}

/// Where primitive `prim`'s entry is in the per-emitter tables
/// (emitter_pdf_area): triangles by their leaf-order index, the other types
/// after them.
inline uint geometry_emitter_slot(GeometryScene g, uint prim) {
  uint type = prim_type(prim);
  return type == WT_PRIM_TRIANGLE ? prim : g.header.emitter_first[type] + prim_index(prim);
}

#endif  // WT_GEOMETRY_GEOMETRY_CL
