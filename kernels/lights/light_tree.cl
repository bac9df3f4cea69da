// The light tree over emissive triangles (host/render/light_tree.h): pick an
// emitter by descending from the root, choosing each child with probability
// proportional to its importance at the shading point, and the probability
// of that choice for an emitter found by BSDF sampling (MIS), by walking up
// from its leaf with the same ratios.
#ifndef WT_LIGHTS_LIGHT_TREE_CL
#define WT_LIGHTS_LIGHT_TREE_CL

#include "common.h"
#include "shared/light_tree.h"

inline float light_tree_node_importance(__global const WtLightNode* node, float3 p, float3 n) {
  return light_tree_importance(node, p.x, p.y, p.z, n.x, n.y, n.z);
}

/// The light list index of an emitter picked at p (unit normal n) with
/// uniform u; *pmf its probability. WT_NO_HIT (pmf 0) when nothing below the
/// root can reach p.
inline uint light_tree_pick(__global const WtLightNode* nodes, float3 p, float3 n, float u, float* pmf) {
  uint k = 0u;
  float prob = 1.0f;
  while (!nodes[k].leaf) {
    uint c = nodes[k].child;
    float il = light_tree_node_importance(&nodes[c], p, n), ir = light_tree_node_importance(&nodes[c + 1u], p, n);
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
    float il = light_tree_node_importance(&nodes[c], p, n), ir = light_tree_node_importance(&nodes[c + 1u], p, n);
    float sum = il + ir;
    if (!(sum > 0.0f)) return 0.0f;
    prob *= (k == c ? il : ir) / sum;
    k = parent;
  }
  return prob;
}

#endif  // WT_LIGHTS_LIGHT_TREE_CL
