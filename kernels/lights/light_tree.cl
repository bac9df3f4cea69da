// The light tree over emissive triangles (host/render/light_tree.h): pick an
// emitter by descending from the root, choosing each child with probability
// proportional to its importance at the shading point, and the probability
// of that choice for an emitter found by BSDF sampling (MIS), by walking up
// from its leaf with the same ratios.
#ifndef WT_LIGHTS_LIGHT_TREE_CL
#define WT_LIGHTS_LIGHT_TREE_CL

#include "common.h"
#include "shared/light_tree.h"

/// Importance of sibling nodes pair[0] and pair[1] at p (unit normal n):
/// light_tree_importance for both at once, one per lane, its early returns
/// as selects. Both children are needed at every step down (or up) the tree;
/// one importance is a chain of dependent roots and divisions, and two side
/// by side take about as long as one.
inline float2 light_tree_importance2(__global const WtLightNode* pair, float3 p, float3 n) {
  __global const WtLightNode* a = pair;
  __global const WtLightNode* b = pair + 1;
  float2 power = (float2)(a->power, b->power);
  float2 lo_x = (float2)(a->lo_x, b->lo_x), lo_y = (float2)(a->lo_y, b->lo_y), lo_z = (float2)(a->lo_z, b->lo_z);
  float2 hi_x = (float2)(a->hi_x, b->hi_x), hi_y = (float2)(a->hi_y, b->hi_y), hi_z = (float2)(a->hi_z, b->hi_z);
  float2 ex = hi_x - lo_x, ey = hi_y - lo_y, ez = hi_z - lo_z;
  float2 r2 = 0.25f * (ex * ex + ey * ey + ez * ez);
  float2 tx = 0.5f * (lo_x + hi_x) - p.x, ty = 0.5f * (lo_y + hi_y) - p.y, tz = 0.5f * (lo_z + hi_z) - p.z;
  float2 d2 = tx * tx + ty * ty + tz * tz;
  float2 inv_d = 1.0f / sqrt(d2), inv_d2 = inv_d * inv_d;
  float2 wx = tx * inv_d, wy = ty * inv_d, wz = tz * inv_d;
  float2 sin_u2 = r2 * inv_d2;
  float2 cos_u = sqrt(fmax(0.0f, 1.0f - sin_u2)), sin_u = fmin((float2)(a->radius, b->radius) * inv_d, 1.0f);
  // receiver (light_tree_cos_minus); a zero normal bounds nothing
  float2 cos_a = n.x * wx + n.y * wy + n.z * wz;
  float2 sin_a = sqrt(fmax(0.0f, 1.0f - cos_a * cos_a));
  int no_normal = n.x == 0.0f && n.y == 0.0f && n.z == 0.0f;
  float2 cos_i = select(cos_a * cos_u + sin_a * sin_u, (float2)(1.0f), (cos_a >= cos_u) | (int2)(-no_normal));
  // emitter
  float2 cos_o = (float2)(a->cos_theta_o, b->cos_theta_o), sin_o = (float2)(a->sin_theta_o, b->sin_theta_o);
  float2 cos_ou = cos_o * cos_u - sin_o * sin_u;
  float2 cos_theta = -((float2)(a->axis_x, b->axis_x) * wx + (float2)(a->axis_y, b->axis_y) * wy +
                       (float2)(a->axis_z, b->axis_z) * wz);
  float2 sin_theta = sqrt(fmax(0.0f, 1.0f - cos_theta * cos_theta));
  float2 sin_ou = sin_o * cos_u + cos_o * sin_u;
  float2 cos_e = select(cos_theta * cos_ou + sin_theta * sin_ou, (float2)(1.0f), !(cos_o > -cos_u) | !(cos_theta < cos_ou));
  float2 importance = select(power * cos_i * cos_e * inv_d2, (float2)(0.0f), !(cos_i > 0.0f) | !(cos_e > 0.0f));
  importance = select(importance, power / fmax(r2, 1e-30f), d2 <= r2);
  return select(importance, (float2)(0.0f), !(power > 0.0f));
}

/// The light list index of an emitter picked at p (unit normal n) with
/// uniform u; *pmf its probability. WT_NO_HIT (pmf 0) when nothing below the
/// root can reach p.
inline uint light_tree_pick(__global const WtLightNode* nodes, float3 p, float3 n, float u, float* pmf) {
  uint k = 0u;
  float prob = 1.0f;
  while (!nodes[k].leaf) {
    uint c = nodes[k].child;
    float2 importance = light_tree_importance2(&nodes[c], p, n);
    float il = importance.x, ir = importance.y;
    float sum = il + ir;
    if (!(sum > 0.0f)) {
      *pmf = 0.0f;
      return WT_NO_HIT;
    }
    float pl = il / sum;
    if (u < pl) {
      u = u / pl;
      prob *= pl;
      k = c;
    } else {
      u = (u - pl) / (1.0f - pl);
      prob *= ir / sum;  // as light_tree_pmf computes it, not 1 - pl
      k = c + 1u;
    }
    u = fmin(u, 0x1.fffffep-1f);  // keep the rescaled uniform below 1
  }
  *pmf = prob;
  return nodes[k].child;
}

/// Probability that light_tree_pick at p (normal n) returns the emitter of leaf `leaf`.
inline float light_tree_pmf(__global const WtLightNode* nodes, uint leaf, float3 p, float3 n) {
  float prob = 1.0f;
  uint k = leaf;
  while (nodes[k].parent != WT_LIGHT_NODE_NONE) {
    uint parent = nodes[k].parent, c = nodes[parent].child;
    float2 importance = light_tree_importance2(&nodes[c], p, n);
    float il = importance.x, ir = importance.y;
    float sum = il + ir;
    if (!(sum > 0.0f)) return 0.0f;
    prob *= (k == c ? il : ir) / sum;
    k = parent;
  }
  return prob;
}

#endif  // WT_LIGHTS_LIGHT_TREE_CL
