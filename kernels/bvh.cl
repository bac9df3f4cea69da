// BVH traversal: closest hit and any hit over the binary node layout of
// shared/types.h (children adjacent, node 0 the root).
#ifndef WT_BVH_CL
#define WT_BVH_CL

#include "common.h"
#include "geometry/triangle.cl"

/// The scene's geometry as the traversal sees it.
typedef struct BvhScene {
  __global const WtBvhNode* nodes;
  uint node_count;
  __global const float4* tri_verts;  ///< 3 per triangle, leaf order, world space
} BvhScene;

typedef struct Hit {
  float t;
  float b1, b2;
  uint prim;  ///< leaf-order triangle index, or WT_NO_HIT
} Hit;

// Avoid 0 * inf = NaN in the slab test for axis-parallel rays.
inline float3 bvh_safe_rcp(float3 d) {
  const float kTiny = 1e-30f;
  float3 ds = select(d, copysign((float3)(kTiny), d), fabs(d) < kTiny);
  return 1.0f / ds;
}

// Slab test. The far distance is scaled up by 1 + 2*gamma(3) (Ize 2013), so
// rounding never culls a box the ray truly touches.
inline bool bvh_box_hit(__global const WtBvhNode* n, float3 org, float3 inv_d, float tmin,
                        float tmax, float* t_entry) {
  float3 lo = (float3)(n->lo_x, n->lo_y, n->lo_z);
  float3 hi = (float3)(n->hi_x, n->hi_y, n->hi_z);
  float3 t0 = (lo - org) * inv_d;
  float3 t1 = (hi - org) * inv_d;
  float3 tn = fmin(t0, t1);
  float3 tf = fmax(t0, t1);
  float enter = fmax(fmax(tn.x, tn.y), fmax(tn.z, tmin));
  float exit = fmin(fmin(tf.x, tf.y), tf.z) * 1.00000036f;
  exit = fmin(exit, tmax);
  *t_entry = enter;
  return enter <= exit;
}

/// Closest hit in (tmin, tmax).
inline Hit bvh_closest(BvhScene scene, float3 org, float3 dir, float tmin, float tmax) {
  Hit hit;
  hit.t = tmax;
  hit.b1 = hit.b2 = 0.0f;
  hit.prim = WT_NO_HIT;
  if (scene.node_count == 0) return hit;

  RayShear shear = triangle_ray_shear(dir);
  float3 inv_d = bvh_safe_rcp(dir);
  float t_entry;
  if (!bvh_box_hit(&scene.nodes[0], org, inv_d, tmin, tmax, &t_entry)) return hit;

  uint stack_node[WT_BVH_STACK_SIZE];
  float stack_t[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = 0;
  for (;;) {
    __global const WtBvhNode* n = &scene.nodes[node];
    if (n->count > 0) {
      uint end = n->first + n->count;
      for (uint i = n->first; i < end; ++i) {
        float t, b1, b2;
        if (triangle_intersect(org, shear, tmin, hit.t, scene.tri_verts[3 * i].xyz,
                               scene.tri_verts[3 * i + 1].xyz, scene.tri_verts[3 * i + 2].xyz, &t,
                               &b1, &b2)) {
          hit.t = t;
          hit.b1 = b1;
          hit.b2 = b2;
          hit.prim = i;
        }
      }
    } else {
      uint left = n->first;
      float t_left, t_right;
      bool hit_left = bvh_box_hit(&scene.nodes[left], org, inv_d, tmin, hit.t, &t_left);
      bool hit_right = bvh_box_hit(&scene.nodes[left + 1], org, inv_d, tmin, hit.t, &t_right);
      if (hit_left && hit_right) {
        // Visit the nearer child first; the farther one waits with its entry distance.
        bool left_first = t_left <= t_right;
        stack_node[sp] = left_first ? left + 1 : left;
        stack_t[sp] = left_first ? t_right : t_left;
        ++sp;
        node = left_first ? left : left + 1;
        continue;
      }
      if (hit_left || hit_right) {
        node = hit_left ? left : left + 1;
        continue;
      }
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

/// Any hit in (tmin, tmax): true when the segment is blocked.
inline bool bvh_occluded(BvhScene scene, float3 org, float3 dir, float tmin, float tmax) {
  if (scene.node_count == 0) return false;
  RayShear shear = triangle_ray_shear(dir);
  float3 inv_d = bvh_safe_rcp(dir);
  float t_entry;
  if (!bvh_box_hit(&scene.nodes[0], org, inv_d, tmin, tmax, &t_entry)) return false;

  uint stack_node[WT_BVH_STACK_SIZE];
  int sp = 0;
  uint node = 0;
  for (;;) {
    __global const WtBvhNode* n = &scene.nodes[node];
    if (n->count > 0) {
      uint end = n->first + n->count;
      for (uint i = n->first; i < end; ++i) {
        float t, b1, b2;
        if (triangle_intersect(org, shear, tmin, tmax, scene.tri_verts[3 * i].xyz,
                               scene.tri_verts[3 * i + 1].xyz, scene.tri_verts[3 * i + 2].xyz, &t,
                               &b1, &b2))
          return true;
      }
    } else {
      uint left = n->first;
      float t_left, t_right;
      bool hit_left = bvh_box_hit(&scene.nodes[left], org, inv_d, tmin, tmax, &t_left);
      bool hit_right = bvh_box_hit(&scene.nodes[left + 1], org, inv_d, tmin, tmax, &t_right);
      if (hit_left && hit_right) {
        stack_node[sp++] = left + 1;
        node = left;
        continue;
      }
      if (hit_left || hit_right) {
        node = hit_left ? left : left + 1;
        continue;
      }
    }
    if (sp == 0) return false;
    node = stack_node[--sp];
  }
}

#endif  // WT_BVH_CL
