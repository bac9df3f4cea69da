// Light layouts shared by host and kernels. Units follow glTF, which is
// photometric throughout: emitted radiance in nits (cd/m^2), point and spot
// intensity in candela (cd = lm/sr), directional illuminance in lux (lm/m^2).
// The renderer computes with these numbers as they are (radiance = nits); a
// radiometric reading only divides everything by the same 683 lm/W.
#ifndef WT_SHARED_LIGHTS_H
#define WT_SHARED_LIGHTS_H

#include "shared/types.h"

#define WT_LIGHT_TRIANGLE 0     ///< an emissive triangle of the scene
#define WT_LIGHT_POINT 1        ///< KHR_lights_punctual point
#define WT_LIGHT_SPOT 2         ///< KHR_lights_punctual spot
#define WT_LIGHT_DIRECTIONAL 3  ///< KHR_lights_punctual directional
#define WT_LIGHT_ENVIRONMENT 4  ///< the environment (constant or map), at most one
#define WT_LIGHT_TREE 5         ///< the light tree over the emissive triangles (kernels/lights/light_tree.cl), at most one
#define WT_LIGHT_PRIMITIVE 6    ///< an emissive primitive of another type (a sphere, a displaced base triangle, an SDF brick), sampled by geometry_sample_emitter
#define WT_LIGHT_QUAD 7         ///< two emissive triangles that make a rectangle (host/render/light_list.h, findQuadLights), sampled as one (WT_HAS_QUAD_LIGHTS)

/// One light of the scene's light list, 64 bytes.
typedef struct WtLight {
  WtVec4 position;   ///< point/spot: world position; triangle: w = 1 when both faces emit, y = 1 when its material's emission is textured (materials/textured.cl); quad: xyz the corner c at the rectangle's right angle, w as a triangle's
  WtVec4 direction;  ///< spot/directional: unit world direction the light travels in; triangle: x its material's WT_ALPHA_* where it may have holes (0: none), y alphaCutoff, z the alpha factor, w = 1 when the base colour texture's alpha counts (lights/light_sampling.cl); primitive: w = 1 when both faces emit; quad: xyz the edge e1 from c, w the second half's leaf-order index (its bits)
  WtVec4 intensity;  ///< point/spot: cd per channel; directional: lux; triangle, quad: nits (the material's emission); quad: w the x of the edge e2 from c
  wt_uint type;      ///< WT_LIGHT_*
  wt_uint triangle;  ///< WT_LIGHT_TRIANGLE: leaf-order triangle index; WT_LIGHT_QUAD: its first half's; WT_LIGHT_PRIMITIVE: the primitive's typed id (WT_PRIM_TYPE_SHIFT)
  float cos_inner;   ///< spot: cosine of the inner cone angle (full intensity inside); quad: e2's y
  float cos_outer;   ///< spot: cosine of the outer cone angle (zero outside); quad: e2's z
} WtLight;

/// One slot of the alias table that picks a light with probability
/// proportional to its estimated power (Walker 1977, Vose 1991).
typedef struct WtAliasSlot {
  float threshold;  ///< keep this slot's light when u < threshold
  wt_uint alias;    ///< otherwise take this light
  float pmf;        ///< probability of choosing light i (this slot's own light), for MIS
  wt_uint pad0;
} WtAliasSlot;

/// A node of the light tree over emissive triangles (host/render/light_tree.h):
/// the bounds and normal cone of the emitters below it and their total
/// power. An inner node's two children are adjacent (child, child + 1); a
/// leaf holds one emitter. 64 bytes.
typedef struct WtLightNode {
  float lo_x, lo_y, lo_z;  ///< bounds of the emitters below, world
  float power;             ///< their total estimated power (luminance)
  float hi_x, hi_y, hi_z;
  wt_uint child;           ///< inner: the first child; leaf: the emitter's index in the light list
  float axis_x, axis_y, axis_z;  ///< unit axis of the cone holding the emitters' front normals
  float cos_theta_o;       ///< cosine of the cone's half-angle; -1: any direction (a two-sided emitter below)
  wt_uint leaf;            ///< 1 for a leaf
  wt_uint parent;          ///< WT_LIGHT_NODE_NONE at the root
  float sin_theta_o;       ///< sine of the cone's half-angle (0 for -1), so that the importance takes no root for it
  float radius;            ///< half the bounds' diagonal: the bounding sphere's radius
} WtLightNode;
#define WT_LIGHT_NODE_NONE 0xffffffffu
/// LightList::emitterQuad of a triangle that is no rectangle's half.
#define WT_NO_QUAD 0xffffffffu

/// Integrator switches that may change between renders without a rebuild.
#define WT_MIS_BALANCE 0
#define WT_MIS_POWER 1

#endif  // WT_SHARED_LIGHTS_H
