// Device-side helpers every stage includes: typed feature switches, vector
// conversions, robust ray spawning and shading frames.
#ifndef WT_COMMON_H
#define WT_COMMON_H

#include "shared/types.h"
#include "shared/rng.h"
#include "shared/spawn.h"

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
