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

/// One light of the scene's light list, 64 bytes.
typedef struct WtLight {
  WtVec4 position;   ///< point/spot: world position; triangle: w = 1 when both faces emit
  WtVec4 direction;  ///< spot/directional: unit world direction the light travels in
  WtVec4 intensity;  ///< point/spot: cd per channel; directional: lux; triangle: nits (the material's emission)
  wt_uint type;      ///< WT_LIGHT_*
  wt_uint triangle;  ///< WT_LIGHT_TRIANGLE: leaf-order triangle index
  float cos_inner;   ///< spot: cosine of the inner cone angle (full intensity inside)
  float cos_outer;   ///< spot: cosine of the outer cone angle (zero outside)
} WtLight;

/// One slot of the alias table that picks a light with probability
/// proportional to its estimated power (Walker 1977, Vose 1991).
typedef struct WtAliasSlot {
  float threshold;  ///< keep this slot's light when u < threshold
  wt_uint alias;    ///< otherwise take this light
  float pmf;        ///< probability of choosing light i (this slot's own light), for MIS
  wt_uint pad0;
} WtAliasSlot;

/// Integrator switches that may change between renders without a rebuild.
#define WT_MIS_BALANCE 0
#define WT_MIS_POWER 1

#endif  // WT_SHARED_LIGHTS_H
