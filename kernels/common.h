// Device-side helpers every render stage includes: the feature switches (switches.h),
// base.h, vector conversions, robust ray spawning and shading frames.
#ifndef WT_COMMON_H
#define WT_COMMON_H

#include "switches.h"
#include "shared/types.h"
#include "shared/rng.h"
#include "shared/spawn.h"
#include "shared/media.h"
#include "shared/trig.h"

// after the shared headers: FP_CONTRACT OFF above them would change their arithmetic
#include "base.h"

#define WT_NO_HIT 0xffffffffu
#define WT_PI 3.14159265358979323846f

/// atan2 for finite arguments, within 2 ulp of the true angle plus about
/// 1e-7 rad (Cephes' atanf: reduction to |t| <= tan(pi/8), a degree-9 odd
/// polynomial), without the library's handling of infinities, which made
/// PoCL's atan2 a visible share of an environment-lit render
/// (docs/lab/2026-12-02-performance-log.md, "atan2 in shading"). atan2(0, 0) is 0 (or pi for
/// x = -0), as the library's; NaN in, NaN out.
inline float wt_atan2(float y, float x) {
  float ax = fabs(x), ay = fabs(y);
  // atan(ay / ax) in [0, pi/2]
  float t = ay / ax;  // inf for ax = 0 < ay; NaN for 0 / 0
  float base = 0.0f;
  if (t > 2.414213562373095f) {
    base = 0.5f * WT_PI;
    t = -1.0f / t;  // -0 for t = inf
  } else if (t > 0.4142135623730950f) {
    base = 0.25f * WT_PI;
    t = (t - 1.0f) / (t + 1.0f);
  }
  float z = t * t;
  float a = base + ((((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z - 3.33329491539e-1f) * z * t + t);
  if (ax == 0.0f && ay == 0.0f) a = 0.0f;  // 0 / 0
  if (signbit(x)) a = WT_PI - a;
  return copysign(a, y);
}

inline float3 vec4_xyz(WtVec4 v) { return (float3)(v.x, v.y, v.z); }

inline float vec3_component(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

// Origin of a ray leaving surface point p (error bound p_error per axis) on
// the side unit normal n points to: p pushed along n past its rounding error
// (shared/spawn.h). Scale-invariant: the offset follows the coordinates'
// magnitude, so no world-space epsilon is needed anywhere.
inline float3 ray_offset_origin(float3 p, float3 p_error, float3 n) {
  float d = spawn_offset_distance(n.x, n.y, n.z, p_error.x, p_error.y, p_error.z);
  float3 offset = d * n;
  return (float3)(spawn_offset_coordinate(p.x, offset.x), spawn_offset_coordinate(p.y, offset.y),
                  spawn_offset_coordinate(p.z, offset.z));
}

// Orthonormal basis around a unit vector (Duff et al. 2017).
inline void frame_from_normal(float3 n, float3* t, float3* b) {
  float sign = copysign(1.0f, n.z);
  float a = -1.0f / (sign + n.z);
  float c = n.x * n.y * a;
  *t = (float3)(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
  *b = (float3)(c, sign + n.y * n.y * a, -n.y);
}

#endif  // WT_COMMON_H
