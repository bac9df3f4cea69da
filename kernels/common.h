// Device-side helpers every stage includes: typed feature switches, vector
// conversions, robust ray spawning and shading frames.
#ifndef WT_COMMON_H
#define WT_COMMON_H

#include "shared/types.h"
#include "shared/rng.h"

// Feature switches come from the host (host/device/program.cpp, kernelDefines).
#ifndef WT_INTEGRATOR_MINIMAL
#error "WT_INTEGRATOR_MINIMAL is not defined: build options must come from kernelDefines()"
#endif
#ifndef WT_BVH_STACK_SIZE
#error "WT_BVH_STACK_SIZE is not defined: build options must come from kernelDefines()"
#endif

// Products must round separately: a fused multiply-add in the edge functions
// of the watertight triangle test breaks its exactness on shared edges.
#pragma OPENCL FP_CONTRACT OFF

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define WT_HAS_FP64 1
#else
#define WT_HAS_FP64 0
#endif

#define WT_NO_HIT 0xffffffffu
#define WT_PI 3.14159265358979323846f

inline float3 vec4_xyz(WtVec4 v) { return (float3)(v.x, v.y, v.z); }

inline float vec3_component(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

// Move a spawned ray's origin off the surface along the geometric normal by a
// few ULPs of the hit position (Wächter and Binder 2019), so no world-space
// epsilon is needed at any scale. Near the origin, where ULPs vanish, a small
// fixed offset takes over.
inline float3 ray_offset_origin(float3 p, float3 n_geometric) {
  const float kOrigin = 1.0f / 32.0f;
  const float kFloatScale = 1.0f / 65536.0f;
  const float kIntScale = 256.0f;
  int3 of_i = convert_int3(kIntScale * n_geometric);
  int3 p_bits = as_int3(p);
  float3 p_i = as_float3(p_bits + select(of_i, -of_i, p_bits < 0));
  float3 p_f = p + kFloatScale * n_geometric;
  return select(p_i, p_f, fabs(p) < kOrigin);
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
