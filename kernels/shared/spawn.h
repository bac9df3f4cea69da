// Robust ray spawning, shared by host (bench ray sets, stress suite, tests) and kernels.
//
// A surface point computed in float carries a rounding error bound per
// coordinate. A ray leaving the surface starts from the point pushed along the
// geometric normal just past that bound, and rounded away once more, so its
// origin lies strictly on the intended side of the true surface at any scale
// and any distance from the world origin; no world-space epsilon is involved
// (the error-bound offsets of pbrt-v4, Pharr, Jakob and Humphreys, 4th ed.,
// sec. 6.8.6). Traversal also never tests the primitive a ray leaves (the
// ray's skip index, kernels/geometry/triangle.cl), which together make a
// spawned ray miss the surface it left.
#ifndef WT_SHARED_SPAWN_H
#define WT_SHARED_SPAWN_H

#include "shared/types.h"

#ifdef __OPENCL_C_VERSION__
#define WT_SPAWN_INLINE inline
#define WT_FLOAT_TO_BITS(x) as_uint(x)
#define WT_BITS_TO_FLOAT(x) as_float(x)
#else
#include <bit>
#include <cmath>
#define WT_SPAWN_INLINE static inline
#define WT_FLOAT_TO_BITS(x) std::bit_cast<wt_uint>(x)
#define WT_BITS_TO_FLOAT(x) std::bit_cast<float>(x)
#endif

/// gamma(n) = n u / (1 - n u), u = 2^-24: the relative error bound of n
/// successive float roundings (Higham 2002).
WT_SPAWN_INLINE float spawn_gamma(int n) {
  const float u = 5.9604644775390625e-8f;
  return ((float)n * u) / (1.0f - (float)n * u);
}

/// The next float above v (v itself for +inf); -0 and +0 both step to the
/// smallest positive denormal.
WT_SPAWN_INLINE float spawn_next_up(float v) {
  if (v == INFINITY) return v;
  if (v == 0.0f) v = 0.0f;
  wt_uint bits = WT_FLOAT_TO_BITS(v);
  bits = v >= 0.0f ? bits + 1u : bits - 1u;
  return WT_BITS_TO_FLOAT(bits);
}

/// The next float below v (v itself for -inf).
WT_SPAWN_INLINE float spawn_next_down(float v) {
  if (v == -INFINITY) return v;
  if (v == 0.0f) v = -0.0f;
  wt_uint bits = WT_FLOAT_TO_BITS(v);
  bits = v > 0.0f ? bits - 1u : bits + 1u;
  return WT_BITS_TO_FLOAT(bits);
}

/// Distance to push a point with per-axis error bound e along unit normal n:
/// the bound's extent along n, |n| . e.
WT_SPAWN_INLINE float spawn_offset_distance(float nx, float ny, float nz, float ex, float ey, float ez) {
  return fabs(nx) * ex + fabs(ny) * ey + fabs(nz) * ez;
}

/// One coordinate moved by `offset` and rounded once more away from where it
/// was, so rounding in the addition cannot take back part of the offset.
WT_SPAWN_INLINE float spawn_offset_coordinate(float p, float offset) {
  float moved = p + offset;
  if (offset > 0.0f) return spawn_next_up(moved);
  if (offset < 0.0f) return spawn_next_down(moved);
  return moved;
}

/// Error bound of one coordinate of b0 p0 + b1 p1 + b2 p2 evaluated in float
/// with b0 = 1 - b1 - b2 also in float: gamma(7) sum |b_i p_i| for the products
/// and sums, plus gamma(2) |p0| for the rounding of b0 (whose error is
/// absolute, so it does not shrink with b0).
WT_SPAWN_INLINE float spawn_barycentric_error(float b0, float b1, float b2, float p0, float p1, float p2) {
  return spawn_gamma(7) * (fabs(b0 * p0) + fabs(b1 * p1) + fabs(b2 * p2)) + spawn_gamma(2) * fabs(p0);
}

/// Shadow rays end this fraction of the distance short of their target, on
/// top of the target's own offset off the light's surface.
#define WT_SHADOW_MARGIN 1e-4f

#endif  // WT_SHARED_SPAWN_H
