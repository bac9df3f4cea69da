// sin and cos of pi x for the samplers, host and device alike: the angles
// they need are turns of a uniform (2 pi u) or a fraction of a solid angle,
// whose reduction to the first octant is exact when done in units of pi,
// so no library call's argument reduction (a visible share of shading on
// PoCL, docs/lab/2026-12-05-shade-speed.md) is needed.
#ifndef WT_SHARED_TRIG_H
#define WT_SHARED_TRIG_H

#ifdef __OPENCL_C_VERSION__
#define WT_TRIG_INLINE inline
#else
#include <cmath>
#define WT_TRIG_INLINE static inline
#endif

/// sin(pi x), and cos(pi x) in *cos_out, for |x| < 2^22: within 2 ulp of
/// 1 of the true values (Cephes' sinf and cosf polynomials on
/// [-pi/4, pi/4] after an exact reduction by quarter turns). sin(pi k) is
/// exactly 0 and cos(pi k) exactly +-1 for integer k.
WT_TRIG_INLINE float wt_sincospi(float x, float* cos_out) {
  // x = k / 2 + r, |r| <= 1/4: both steps exact (2x is, and x - k/2 is a
  // multiple of x's ulp below 1/4)
  float k = (float)rint(2.0f * x);
  float r = x - 0.5f * k;
  float t = 3.14159265358979323846f * r;
  float t2 = t * t;
  float s = t + t * t2 * (-1.6666654611e-1f + t2 * (8.3321608736e-3f + t2 * -1.9515295891e-4f));
  float c = 1.0f - 0.5f * t2 +
            t2 * t2 * (4.166664568298827e-2f + t2 * (-1.388731625493765e-3f + t2 * 2.443315711809948e-5f));
  // the quarter turns: (s, c) rotated by k pi / 2
  int q = (int)k & 3;
  float sin_v = (q & 1) ? c : s, cos_v = (q & 1) ? s : c;
  if (q == 2 || q == 3) sin_v = -sin_v;
  if (q == 1 || q == 2) cos_v = -cos_v;
  *cos_out = cos_v;
  return sin_v;
}

#endif  // WT_SHARED_TRIG_H
