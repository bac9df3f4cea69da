// BVH traversal: closest hit and any hit over the 4-wide node layout of
// shared/types.h (WtBvh4Node, node 0 the root). The buffer is declared as
// WtBvhNode* in the kernels' arguments and BvhScene; it holds WtBvh4Node.
#ifndef WT_BVH_CL
#define WT_BVH_CL

#include "common.h"
#include "geometry/triangle.cl"
#include "materials/alpha.cl"

/// The scene's geometry as the traversal sees it.
typedef struct BvhScene {
  __global const WtBvhNode* nodes;
  uint node_count;
  __global const float4* tri_verts;  ///< 3 per triangle, leaf order, world space
#if WT_HAS_ALPHA
  AlphaScene alpha;  ///< the alpha test, with the stream of the ray being traced (WT_ALPHA_BIND)
#endif
} BvhScene;

typedef struct Hit {
  float t;
  float b1, b2;
  uint prim;  ///< leaf-order triangle index, or WT_NO_HIT
#if WT_BVH_COST
  uint cost;  ///< nodes of the triangle tree visited (instances' and other primitives' trees not counted)
#endif
} Hit;

// Avoid 0 * inf = NaN in the slab test for axis-parallel rays.
inline float3 bvh_safe_rcp(float3 d) {
  const float kTiny = 1e-30f;
  float3 ds = select(d, copysign((float3)(kTiny), d), fabs(d) < kTiny);
  return 1.0f / ds;
}

/// Where a ray's near and far planes sit in a WtBvh4Node, per axis, as
/// float offsets from the node's start: the lo planes when the direction
/// is positive, the hi planes when it is negative. Picked once per ray, so
/// the slab test loads the planes it needs instead of choosing per node.
typedef struct RayPlanes {
  int near_x, far_x, near_y, far_y, near_z, far_z;
} RayPlanes;

inline RayPlanes bvh_ray_planes(float3 inv_d) {
  // lo_x at 0, hi_x at 4, lo_y at 8, hi_y at 12, lo_z at 16, hi_z at 20 (shared/types.h)
  RayPlanes p;
  p.near_x = inv_d.x < 0.0f ? 4 : 0;
  p.far_x = 4 - p.near_x;
  p.near_y = inv_d.y < 0.0f ? 12 : 8;
  p.far_y = 20 - p.near_y;
  p.near_z = inv_d.z < 0.0f ? 20 : 16;
  p.far_z = 36 - p.near_z;
  return p;
}

// Larger and smaller of two distances, without fmax and fmin's NaN rules
// (two more instructions each on PoCL). The planes' distances are never
// NaN for a finite ray (finite reciprocal directions, bvh_safe_rcp); a NaN
// tmin or tmax, which no triangle hit can satisfy either, now misses every
// box instead of every triangle: the same answer.
inline float4 bvh_max(float4 a, float4 b) { return a > b ? a : b; }
inline float4 bvh_min(float4 a, float4 b) { return a < b ? a : b; }

// Slab test of a node's four child boxes at once. The far distance is scaled
// up by 1 + 2*gamma(3) (Ize 2013), so rounding never culls a box the ray truly
// touches. Near and far planes are picked by the sign of the ray's direction
// (RayPlanes), so an empty slot's inverted box (lo = +inf, hi = -inf) is never entered.
inline int4 bvh4_box_hit(__global const WtBvh4Node* n, RayPlanes planes, float3 org, float3 inv_d, float tmin,
                         float tmax, float4* t_entry) {
  __global const float* f = (__global const float*)n;
  float4 tn_x = (vload4(0, f + planes.near_x) - org.x) * inv_d.x;
  float4 tf_x = (vload4(0, f + planes.far_x) - org.x) * inv_d.x;
  float4 tn_y = (vload4(0, f + planes.near_y) - org.y) * inv_d.y;
  float4 tf_y = (vload4(0, f + planes.far_y) - org.y) * inv_d.y;
  float4 tn_z = (vload4(0, f + planes.near_z) - org.z) * inv_d.z;
  float4 tf_z = (vload4(0, f + planes.far_z) - org.z) * inv_d.z;
  float4 enter = bvh_max(bvh_max(tn_x, tn_y), bvh_max(tn_z, (float4)(tmin)));
  float4 exit = bvh_min(bvh_min(tf_x, tf_y), tf_z) * 1.00000036f;
  exit = bvh_min(exit, (float4)(tmax));
  *t_entry = enter;
  return enter <= exit;
}

/// The nearest hit among a block's lanes (triangle_intersect4_k) that the
/// alpha test keeps: a lane whose triangle has a hole there is dropped and
/// the next nearest lane of the block taken, until one is kept or none is
/// left. Where WT_HAS_ALPHA is off, triangle_intersect4_k itself.
__attribute__((always_inline)) inline uint bvh_block_hit_k(BvhScene scene, float3 o_k, RayShear s, float tmin,
                                                           float tmax, uint block, uint lane_lo, uint lane_hi,
                                                           uint skip_a, uint skip_b, float* t, float* b1, float* b2) {
#if WT_HAS_ALPHA
  TriangleLanes h = triangle_test4_k(o_k, s, tmin, tmax, scene.tri_verts, block, lane_lo, lane_hi, skip_a, skip_b);
  if (!triangle_any4(h)) return WT_NO_HIT;
  uint flagged = alpha_block_bits(scene.alpha, block);
  for (;;) {
    // t, b1 and b2 are written for a hit kept only: callers keep an earlier block's there
    float tt, bb1, bb2;
    uint prim = triangle_nearest4(h, block, &tt, &bb1, &bb2);
    uint lane = prim & 3u;
    if (((flagged >> lane) & 1u) == 0u || alpha_keeps(scene.alpha, prim, bb1, bb2)) {
      *t = tt, *b1 = bb1, *b2 = bb2;
      return prim;
    }
    // a hole: the lane drops out (ok lanes are masked with &, never ~, as triangle_any4 says)
    h.ok &= (int4)(lane == 0u ? 0 : -1, lane == 1u ? 0 : -1, lane == 2u ? 0 : -1, lane == 3u ? 0 : -1);
    if (!triangle_any4(h)) return WT_NO_HIT;
  }
#else
  return triangle_intersect4_k(o_k, s, tmin, tmax, scene.tri_verts, block, lane_lo, lane_hi, skip_a, skip_b, t, b1,
                               b2);
#endif
}

/// bvh_block_hit_k for a ray whose origin is in world axes.
__attribute__((always_inline)) inline uint bvh_block_hit(BvhScene scene, float3 org, RayShear s, float tmin,
                                                         float tmax, uint block, uint lane_lo, uint lane_hi,
                                                         uint skip_a, uint skip_b, float* t, float* b1, float* b2) {
#if WT_HAS_ALPHA
  return bvh_block_hit_k(scene, triangle_origin_k(org, s), s, tmin, tmax, block, lane_lo, lane_hi, skip_a, skip_b, t,
                         b1, b2);
#else
  return triangle_intersect4(org, s, tmin, tmax, scene.tri_verts, block, lane_lo, lane_hi, skip_a, skip_b, t, b1, b2);
#endif
}

// A ray whose origin or direction is NaN or infinite has no slab test: the
// terms of an empty slot's inverted box become NaN on every axis, fmin and
// fmax drop them, the slot passes and traversal reads node WT_BVH4_EMPTY.
inline bool bvh_ray_is_finite(float3 org, float3 dir) { return all(isfinite(org)) && all(isfinite(dir)); }

/// Closest hit in (tmin, tmax), never on leaf-order triangle `skip` (the one
/// a spawned ray leaves; WT_NO_HIT for none); none for a ray that is not
/// finite. Skipping the surface left is what keeps a spawned ray off it: a
/// plane cannot be hit twice, and no distance threshold is needed that
/// would also drop real hits close by (a concave corner's other face).
/// With WT_HAS_ALPHA a hole the alpha test finds (bvh_block_hit) is no hit.
/// bvh_closest_root starts at node `root` instead of node 0: the root of a
/// geometry stored once for its placed copies (kernels/geometry/instance.cl),
/// its nodes after the scene's own tree in the same buffer.
inline Hit bvh_closest_root(BvhScene scene, uint root, float3 org, float3 dir, float tmin, float tmax, uint skip) {
  Hit hit;
  hit.t = tmax;
  hit.b1 = hit.b2 = 0.0f;
  hit.prim = WT_NO_HIT;
#if WT_BVH_COST
  hit.cost = 0u;
#endif
  if (scene.node_count == 0 || !bvh_ray_is_finite(org, dir)) return hit;
  __global const WtBvh4Node* nodes = (__global const WtBvh4Node*)scene.nodes;

  RayShear shear = triangle_ray_shear(dir);
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);
  // at most three pushes per level: WT_BVH_STACK_SIZE comes from bvh4StackEntries
  uint stack_node[WT_BVH_STACK_SIZE];
  float stack_t[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  for (;;) {
    __global const WtBvh4Node* n = &nodes[node];
#if WT_BVH_COST
    ++hit.cost;
#endif
    float4 t4;
    int4 hit4 = bvh4_box_hit(n, planes, org, inv_d, tmin, hit.t, &t4);
    float t_child[4] = {t4.s0, t4.s1, t4.s2, t4.s3};
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    // Leaves now (they shorten hit.t); inner children sorted nearest first.
    uint inner[4];
    float inner_t[4];
    int inner_count = 0;
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        // one vector test per block of four the leaf touches (WT_TRIANGLE_BLOCK)
        uint last = first + count - 1u;
        for (uint b = first >> 2; b <= last >> 2; ++b) {
          float t, b1, b2;
          uint prim = bvh_block_hit(scene, org, shear, tmin, hit.t, b, b == first >> 2 ? first & 3u : 0u,
                                    b == last >> 2 ? (last & 3u) + 1u : 4u, skip, skip, &t, &b1, &b2);
          if (prim != WT_NO_HIT) {
            hit.t = t;
            hit.b1 = b1;
            hit.b2 = b2;
            hit.prim = prim;
          }
        }
      } else {
        int j = inner_count++;
        for (; j > 0 && inner_t[j - 1] > t_child[k]; --j) {
          inner[j] = inner[j - 1];
          inner_t[j] = inner_t[j - 1];
        }
        inner[j] = first;
        inner_t[j] = t_child[k];
      }
    }
    // Descend into the nearest inner child still in front of the closest hit;
    // the others wait, farthest deepest.
    if (inner_count > 0 && inner_t[0] <= hit.t) {
      for (int k = inner_count - 1; k >= 1; --k) {
        if (inner_t[k] > hit.t) continue;
        stack_node[sp] = inner[k];
        stack_t[sp] = inner_t[k];
        ++sp;
      }
      node = inner[0];
      continue;
    }
    // Pop, skipping boxes entered beyond the closest hit found since the push.
    for (;;) {
      if (sp == 0) return hit;
      --sp;
      if (stack_t[sp] <= hit.t) break;
    }
    node = stack_node[sp];
  }
}

inline Hit bvh_closest(BvhScene scene, float3 org, float3 dir, float tmin, float tmax, uint skip) {
  return bvh_closest_root(scene, 0u, org, dir, tmin, tmax, skip);
}

/// Any hit in (tmin, tmax) on a triangle other than skip_a and skip_b (the
/// surface the shadow ray leaves, the emitter it aims at): true when the
/// segment is blocked, and for a ray that is not finite (no light is carried
/// along it); a hole the alpha test finds blocks nothing. From node `root`
/// (bvh_closest_root); bvh_occluded from node 0.
inline bool bvh_occluded_root(BvhScene scene, uint root, float3 org, float3 dir, float tmin, float tmax, uint skip_a,
                              uint skip_b) {
  if (!bvh_ray_is_finite(org, dir)) return true;
  if (scene.node_count == 0) return false;
  __global const WtBvh4Node* nodes = (__global const WtBvh4Node*)scene.nodes;
  RayShear shear = triangle_ray_shear(dir);
  float3 inv_d = bvh_safe_rcp(dir);
  RayPlanes planes = bvh_ray_planes(inv_d);

  uint stack_node[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = root;
  for (;;) {
    __global const WtBvh4Node* n = &nodes[node];
    float4 t4;
    int4 hit4 = bvh4_box_hit(n, planes, org, inv_d, tmin, tmax, &t4);
    int hit_child[4] = {hit4.s0, hit4.s1, hit4.s2, hit4.s3};
    int next = -1;
    for (int k = 0; k < 4; ++k) {
      if (!hit_child[k]) continue;
      uint first = n->child[k], count = n->count[k];
      if (count > 0) {
        uint last = first + count - 1u;
        for (uint b = first >> 2; b <= last >> 2; ++b) {
          float t, b1, b2;
          if (bvh_block_hit(scene, org, shear, tmin, tmax, b, b == first >> 2 ? first & 3u : 0u,
                            b == last >> 2 ? (last & 3u) + 1u : 4u, skip_a, skip_b, &t, &b1, &b2) != WT_NO_HIT)
            return true;
        }
      } else if (next < 0) {
        next = (int)first;
      } else {
        stack_node[sp++] = first;
      }
    }
    if (next >= 0) {
      node = (uint)next;
      continue;
    }
    if (sp == 0) return false;
    node = stack_node[--sp];
  }
}

inline bool bvh_occluded(BvhScene scene, float3 org, float3 dir, float tmin, float tmax, uint skip_a,
                         uint skip_b) {
  return bvh_occluded_root(scene, 0u, org, dir, tmin, tmax, skip_a, skip_b);
}

#endif  // WT_BVH_CL
