// A light tree over the scene's emissive triangles (Conty Estevez and Kulla
// 2018, "Importance Sampling of Many Lights with Adaptive Tree Splitting"):
// a binary tree whose nodes bound their emitters' positions and normals and
// carry their power, so that next-event estimation can pick an emitter with
// probability proportional to an estimate of its contribution at the
// shading point, instead of to its power alone. Built on the host
// (binned surface-area-orientation heuristic), descended on the device
// (kernels/lights/light_tree.cl).
#pragma once

#include "shared/light_tree.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <span>
#include <vector>

namespace wt {

/// One emitter as the tree sees it.
struct LightTreeEmitter {
  glm::vec3 p0, p1, p2;   ///< corners (the emitting side is the counter-clockwise front unless twoSided)
  double power = 0.0;     ///< estimated power (luminance), as the light list's
  bool twoSided = false;
  std::uint32_t light = 0;  ///< index into the light list
  glm::vec3 p3{0.0f};     ///< a rectangle's fourth corner (quad only; p0, p1, p2 its first half)
  bool quad = false;      ///< a rectangle light (WT_LIGHT_QUAD): bounds and centroid take p3 too
};

struct LightTree {
  std::vector<WtLightNode> nodes;  ///< node 0 is the root; empty when there are no emitters
  std::vector<std::uint32_t> leafOfEmitter;  ///< per emitter given to buildLightTree: its leaf node
};

/// Build the tree; emitters with zero power are kept out (leafOfEmitter =
/// 0xffffffff for them).
LightTree buildLightTree(std::span<const LightTreeEmitter> emitters);

}  // namespace wt
