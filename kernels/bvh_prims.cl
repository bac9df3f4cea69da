// Traversal of the BVH over the primitives other than triangles
// (kernels/geometry/geometry.cl): one ray at a time, each leaf entry a typed
// id tested through geometry_intersect. The scene's closest hit is the
// triangles' (kernels/bvh.cl, bvh_packet.cl) narrowed by this one; without
// such primitives (WT_HAS_PRIMITIVES 0) none of it is compiled.
#ifndef WT_BVH_PRIMS_CL
#define WT_BVH_PRIMS_CL

#include "bvh.cl"
#include "geometry/geometry.cl"

#if WT_HAS_PRIMITIVES

/// Slab test of an oriented node's four child boxes (WT_BVH4_ORIENTED, a
/// WtBvh4Oriented): the ray rotated into the node's frame, then
/// bvh4_box_hit's test on the boxes' grid planes, widened by the rounding of
/// the rotation and the planes: of the origin (relative to the frame's
/// centre) and of the direction over the distance to the boxes, which the
/// grid's far corner bounds. Distances along the ray are the same in the frame.
inline int4 bvh4_frame_hit(__global const WtBvh4Node* node, float3 org, float3 dir, float tmin, float tmax,
                           float4* t_entry) {
  __global const WtBvh4Oriented* n = (__global const WtBvh4Oriented*)node;
  __global const float* f = (__global const float*)n;
  float4 r0 = vload4(0, f), r1 = vload4(1, f), r2 = vload4(2, f);
  float3 q0 = vload3(0, f + 12), qs = vload3(0, f + 15);
  float3 w = org - (float3)(r0.w, r1.w, r2.w);
  float3 o = (float3)(dot(r0.xyz, w), dot(r1.xyz, w), dot(r2.xyz, w));
  float3 inv_d = bvh_safe_rcp((float3)(dot(r0.xyz, dir), dot(r1.xyz, dir), dot(r2.xyz, dir)));
  float3 reach = fmax(fabs(q0), fabs(q0 + 255.0f * qs));
  float3 m = (2e-6f * (fabs(w.x) + fabs(w.y) + fabs(w.z) + reach.x + reach.y + reach.z)) * fabs(inv_d);
  // plane = origin + byte * step: t = (origin - o) / d + byte * (step / d)
  float3 a = (q0 - o) * inv_d, s = qs * inv_d;
  RayPlanes planes = bvh_ray_planes(inv_d);
  __global const uchar* g = (__global const uchar*)n->grid;
  float4 tn_x = a.x + convert_float4(vload4(0, g + planes.near_x)) * s.x - m.x;
  float4 tf_x = a.x + convert_float4(vload4(0, g + planes.far_x)) * s.x + m.x;
  float4 tn_y = a.y + convert_float4(vload4(0, g + planes.near_y)) * s.y - m.y;
  float4 tf_y = a.y + convert_float4(vload4(0, g + planes.far_y)) * s.y + m.y;
  float4 tn_z = a.z + convert_float4(vload4(0, g + planes.near_z)) * s.z - m.z;
  float4 tf_z = a.z + convert_float4(vload4(0, g + planes.far_z)) * s.z + m.z;
  float4 enter = bvh_max(bvh_max(tn_x, tn_y), bvh_max(tn_z, (float4)(tmin)));
  float4 exit = bvh_min(bvh_min(tf_x, tf_y), tf_z) * 1.00000036f;
  exit = bvh_min(exit, (float4)(tmax));
  *t_entry = enter;
  // an empty slot's grid box is inverted by whole steps, which the widening could bridge on a thin axis
  return (enter <= exit) & (vload4(0, n->child) != (uint4)(WT_BVH4_EMPTY));
}

/// The ray's unit direction for prims_leaf_missed.
inline float3 prims_ray_unit(float3 dir) {
#if WT_HAS_CURVES
  return normalize(dir);
#else
  return dir;
#endif
}

/// The leaf entries first + k (k < 4, k < count) that certainly miss the
/// ray through org along unit dn, as bit k: curve segments passed wide, read
/// from the leaf joints (WtGeometry::leaf_joints), four at once.
inline uint prims_leaf_missed(GeometryScene g, uint first, uint count, float3 org, float3 dn) {
#if WT_HAS_CURVES
  int4 m = curve_segments_missed4(g.data + g.header.leaf_joints + WT_LEAF_JOINT_ROWS * first, org, dn);
  uint bits = (m.s0 ? 1u : 0u) | (m.s1 ? 2u : 0u) | (m.s2 ? 4u : 0u) | (m.s3 ? 8u : 0u);
  return count >= 4 ? bits : bits & ((1u << count) - 1u);
#else
  return 0u;
#endif
}

/// Ask for what a hit child holds before the slot loop reads it, so that its
/// miss overlaps the other children's work: a leaf's joint rows (the eight its
/// reject reads) and refs, an inner node's two lines.
inline void prims_prefetch_child(GeometryScene g, uint first, uint count) {
#if !WT_NO_PREFETCH
  if (count > 0) {
    __global const float4* j = g.data + g.header.leaf_joints + WT_LEAF_JOINT_ROWS * first;
    __builtin_prefetch(j, 0, 3);
    __builtin_prefetch(j + 4, 0, 3);
    __builtin_prefetch(j + 7, 0, 3);
    __builtin_prefetch(g.refs + first, 0, 3);
  } else {
    __global const char* c = (__global const char*)&g.nodes[first & ~WT_BVH4_ORIENTED];
    __builtin_prefetch(c, 0, 3);
    __builtin_prefetch(c + 64, 0, 3);
  }
#endif
}

/// Node `node` of the primitive tree (its WT_BVH4_ORIENTED bit included)
/// and its child boxes' slab test.
inline __global const WtBvh4Node* bvh_prims_node(GeometryScene g, uint node, RayPlanes planes, float3 org,
                                                 float3 dir, float3 inv_d, float tmin, float tmax, int4* hit4,
                                                 float4* t4) {
  __global const WtBvh4Node* n = &g.nodes[node & ~WT_BVH4_ORIENTED];
  *hit4 = (node & WT_BVH4_ORIENTED) ? bvh4_frame_hit(n, org, dir, tmin, tmax, t4)
                                    : bvh4_box_hit(n, planes, org, inv_d, tmin, tmax, t4);
  return n;
}

#if WT_HAS_INSTANCES
/// Narrow `hit` to a nearer primitive of the geometry whose tree starts at
/// node `root` (a geometry of other types stored once), the ray in its object space:
/// the tree holds no instances. `skip`: the primitive the ray leaves on this
/// copy (WT_NO_HIT when it leaves another).
inline bool bvh_prims_closest_root(GeometryScene g, uint root, float3 org, float3 dir, float tmin, uint skip,
                                   Hit* hit) {
  if (!bvh_ray_is_finite(org, dir)) return false;
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);
  float3 dn = prims_ray_unit(dir);
  uint stack_node[WT_BVH_STACK_SIZE];
  float stack_t[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  bool found = false;
  for (;;) {
    float4 t4;
    int4 hit4;
    __global const WtBvh4Node* n = bvh_prims_node(g, node, planes, org, dir, inv_d, tmin, hit->t, &hit4, &t4);
    float t_child[4] = {t4.s0, t4.s1, t4.s2, t4.s3};
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    for (int k = 0; k < 4; ++k)
      if (hit_child[k]) prims_prefetch_child(g, n->child[k], n->count[k]);
    uint next = WT_BVH4_EMPTY;  // (uint: oriented nodes' indices have the top bit set)
    float next_t = INFINITY;
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        uint missed = prims_leaf_missed(g, first, count, org, dn);
        for (uint i = first; i < first + count; ++i) {
          if (i - first < 4u && (missed >> (i - first) & 1u)) continue;
          uint prim = g.refs[i];
          float t, u, v;
          if (geometry_intersect_entry(g, i, prim, org, dir, tmin, hit->t, skip, WT_NO_HIT, false, &t, &u, &v)) {
            hit->t = t;
            hit->b1 = u;
            hit->b2 = v;
            hit->prim = prim;
            found = true;
          }
        }
      } else if (t_child[k] < next_t) {
        if (next != WT_BVH4_EMPTY) {
          stack_node[sp] = next;
          stack_t[sp++] = next_t;
        }
        next = first;
        next_t = t_child[k];
      } else {
        stack_node[sp] = first;
        stack_t[sp++] = t_child[k];
      }
    }
    if (next != WT_BVH4_EMPTY && next_t <= hit->t) {
      node = next;
      continue;
    }
    for (;;) {
      if (sp == 0) return found;
      --sp;
      if (stack_t[sp] <= hit->t) break;
    }
    node = stack_node[sp];
  }
}

/// Whether a primitive of the geometry whose tree starts at `root` blocks (tmin, tmax), the ray in its object space.
inline bool bvh_prims_occluded_root(GeometryScene g, uint root, float3 org, float3 dir, float tmin, float tmax,
                                    uint skip) {
  if (!bvh_ray_is_finite(org, dir)) return true;
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);
  float3 dn = prims_ray_unit(dir);
  uint stack_node[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  for (;;) {
    float4 t4;
    int4 hit4;
    __global const WtBvh4Node* n = bvh_prims_node(g, node, planes, org, dir, inv_d, tmin, tmax, &hit4, &t4);
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        uint missed = prims_leaf_missed(g, first, count, org, dn);
        for (uint i = first; i < first + count; ++i) {
          if (i - first < 4u && (missed >> (i - first) & 1u)) continue;
          float t, u, v;
          if (geometry_intersect_entry(g, i, g.refs[i], org, dir, tmin, tmax, skip, WT_NO_HIT, true, &t, &u, &v)) return true;
        }
      } else {
        stack_node[sp++] = first;
      }
    }
    if (sp == 0) return false;
    node = stack_node[--sp];
  }
}

/// An instance's closest hit, of either kind: triangles (its geometry's
/// leaf-order triangle in hit->prim) or the other types (its geometry's
/// typed id), the ray moved into the copy's object space (unnormalised, so
/// t carries over). True when it narrowed `hit`.
inline bool bvh_prims_instance_closest(BvhScene scene, GeometryScene g, uint prim, float3 org, float3 dir, float tmin,
                                       uint skip, uint skip_instance, Hit* hit) {
  uint4 info = geometry_instance_info(g, prim);
  if (!(info.y & WT_INSTANCE_PRIMITIVES)) return geometry_instance_closest(scene, g, prim, org, dir, tmin, skip,
                                                                           skip_instance, hit);
  __global const float4* rows = geometry_instance_rows(g, prim);
  return bvh_prims_closest_root(g, info.x, instance_point(rows, org), instance_vector(rows, dir), tmin,
                                prim == skip_instance ? skip : WT_NO_HIT, hit);
}

inline bool bvh_prims_instance_occluded(BvhScene scene, GeometryScene g, uint prim, float3 org, float3 dir, float tmin,
                                        float tmax, uint skip, uint skip_instance) {
  uint4 info = geometry_instance_info(g, prim);
  if (!(info.y & WT_INSTANCE_PRIMITIVES)) return geometry_instance_occluded(scene, g, prim, org, dir, tmin, tmax, skip,
                                                                            skip_instance);
  __global const float4* rows = geometry_instance_rows(g, prim);
  return bvh_prims_occluded_root(g, info.x, instance_point(rows, org), instance_vector(rows, dir), tmin, tmax,
                                 prim == skip_instance ? skip : WT_NO_HIT);
}
#endif

/// Narrow `hit` (the triangles' closest hit, hit->t its distance or tmax) to
/// a nearer primitive in (tmin, hit->t), never at the start of the surface
/// the ray leaves: `skip` (on instance `skip_instance` when that is not
/// WT_NO_HIT). An instance's hit sets *hit_instance (which the caller sets
/// to WT_NO_HIT first); `scene` holds the instanced geometries' trees.
inline void bvh_prims_closest(BvhScene scene, GeometryScene g, float3 org, float3 dir, float tmin, uint skip,
                              uint skip_instance, Hit* hit, uint* hit_instance) {
  if (g.header.node_count == 0 || !bvh_ray_is_finite(org, dir)) return;
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);
  float3 dn = prims_ray_unit(dir);
  uint stack_node[WT_BVH_STACK_SIZE];
  float stack_t[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = 0;
  for (;;) {
    float4 t4;
    int4 hit4;
    __global const WtBvh4Node* n = bvh_prims_node(g, node, planes, org, dir, inv_d, tmin, hit->t, &hit4, &t4);
    float t_child[4] = {t4.s0, t4.s1, t4.s2, t4.s3};
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    for (int k = 0; k < 4; ++k)
      if (hit_child[k]) prims_prefetch_child(g, n->child[k], n->count[k]);
    uint next = WT_BVH4_EMPTY;  // (uint: oriented nodes' indices have the top bit set)
    float next_t = INFINITY;
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        uint missed = prims_leaf_missed(g, first, count, org, dn);
        for (uint i = first; i < first + count; ++i) {
          if (i - first < 4u && (missed >> (i - first) & 1u)) continue;
          uint prim = g.refs[i];
#if WT_HAS_INSTANCES
          if (prim_type(prim) == WT_PRIM_INSTANCE) {
            if (bvh_prims_instance_closest(scene, g, prim, org, dir, tmin, skip, skip_instance, hit))
              *hit_instance = prim;
            continue;
          }
#endif
          float t, u, v;
          if (geometry_intersect_entry(g, i, prim, org, dir, tmin, hit->t, skip, WT_NO_HIT, false, &t, &u, &v)) {
            hit->t = t;
            hit->b1 = u;
            hit->b2 = v;
            hit->prim = prim;
            *hit_instance = WT_NO_HIT;
          }
        }
      } else if (t_child[k] < next_t) {
        // the nearest inner child next; the one it displaces waits
        if (next != WT_BVH4_EMPTY) {
          stack_node[sp] = next;
          stack_t[sp++] = next_t;
        }
        next = first;
        next_t = t_child[k];
      } else {
        stack_node[sp] = first;
        stack_t[sp++] = t_child[k];
      }
    }
    if (next != WT_BVH4_EMPTY && next_t <= hit->t) {
      node = next;
      continue;
    }
    for (;;) {
      if (sp == 0) return;
      --sp;
      if (stack_t[sp] <= hit->t) break;
    }
    node = stack_node[sp];
  }
}

/// Whether a primitive blocks (tmin, tmax), never at the start of skip_a
/// (on instance skip_instance when that is not WT_NO_HIT) or skip_b.
inline bool bvh_prims_occluded(BvhScene scene, GeometryScene g, float3 org, float3 dir, float tmin, float tmax,
                               uint skip_a, uint skip_b, uint skip_instance) {
  if (g.header.node_count == 0) return false;
  if (!bvh_ray_is_finite(org, dir)) return true;
#if WT_HAS_CURVES || WT_HAS_SPHERES
  // The convex primitive the ray leaves, first: headed out, its test ends at
  // once; headed in (a shadow ray through a fibre), its far wall blocks it,
  // which a walk in slot order finds late.
  if (skip_instance == WT_NO_HIT && (prim_type(skip_a) == WT_PRIM_CURVE || prim_type(skip_a) == WT_PRIM_SPHERE) &&
      skip_a != WT_NO_HIT) {
    float t, u, v;
    if (geometry_intersect(g, skip_a, org, dir, tmin, tmax, skip_a, skip_b, true, &t, &u, &v)) return true;
  }
#endif
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);
  float3 dn = prims_ray_unit(dir);
  uint stack_node[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = 0;
  for (;;) {
    float4 t4;
    int4 hit4;
    __global const WtBvh4Node* n = bvh_prims_node(g, node, planes, org, dir, inv_d, tmin, tmax, &hit4, &t4);
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        uint missed = prims_leaf_missed(g, first, count, org, dn);
        for (uint i = first; i < first + count; ++i) {
          if (i - first < 4u && (missed >> (i - first) & 1u)) continue;
          uint prim = g.refs[i];
#if WT_HAS_INSTANCES
          if (prim_type(prim) == WT_PRIM_INSTANCE) {
            if (bvh_prims_instance_occluded(scene, g, prim, org, dir, tmin, tmax, skip_a, skip_instance)) return true;
            continue;
          }
#endif
          float t, u, v;
          if (geometry_intersect_entry(g, i, prim, org, dir, tmin, tmax, skip_a, skip_b, true, &t, &u, &v)) return true;
        }
      } else {
        stack_node[sp++] = first;
      }
    }
    if (sp == 0) return false;
    node = stack_node[--sp];
  }
}

#endif  // WT_HAS_PRIMITIVES

/// The scene's closest hit in (tmin, tmax): triangles, then the other types.
/// The ray leaves `skip` (on instance skip_instance); *hit_instance is the
/// instance hit, WT_NO_HIT for none (always, without instances).
inline Hit scene_closest(BvhScene scene, GeometryScene g, float3 org, float3 dir, float tmin, float tmax, uint skip,
                         uint skip_instance, uint* hit_instance) {
  Hit hit = bvh_closest(scene, org, dir, tmin, tmax, skip);
  *hit_instance = WT_NO_HIT;
#if WT_HAS_PRIMITIVES
  bvh_prims_closest(scene, g, org, dir, tmin, skip, skip_instance, &hit, hit_instance);
#endif
  return hit;
}

/// Whether anything in the scene blocks (tmin, tmax).
inline bool scene_occluded(BvhScene scene, GeometryScene g, float3 org, float3 dir, float tmin, float tmax,
                           uint skip_a, uint skip_b, uint skip_instance) {
  if (bvh_occluded(scene, org, dir, tmin, tmax, skip_a, skip_b)) return true;
#if WT_HAS_PRIMITIVES
  return bvh_prims_occluded(scene, g, org, dir, tmin, tmax, skip_a, skip_b, skip_instance);
#else
  return false;
#endif
}

#endif  // WT_BVH_PRIMS_CL
