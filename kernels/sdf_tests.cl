// Test-only program root: every SDF brick tested against every ray, no BVH,
// with the surface at the hit (kernels/geometry/sdf_grid.cl), for
// tests/geometry/test_sdf_grid.cpp.
#include "common.h"
#include "geometry/sdf_grid.cl"

/// Per ray (origin xyz + tmin in w, direction xyz + tmax in w): out[2i] =
/// (t, unit normal) and out[2i + 1] = (p_error, brick index as bits); t = -1
/// for a miss. `rows` and `info` start at the type's first rows.
WT_KERNEL void test_sdf_closest(uint count, uint bricks, __global const float4* rows, __global const uint4* info,
                                __global const float4* ray_o, __global const float4* ray_d, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 o = ray_o[i].xyz, d = ray_d[i].xyz;
  float tmin = ray_o[i].w, best = ray_d[i].w;
  uint hit = 0xffffffffu;
  float cell = 0.0f;
  for (uint b = 0; b < bricks; ++b) {
    float t, c;
    if (sdf_intersect(rows, info + WT_SDF_INFO_ROWS * b, o, d, tmin, best, &t, &c)) {
      best = t;
      hit = b;
      cell = c;
    }
  }
  if (hit == 0xffffffffu) {
    out[2 * i] = (float4)(-1.0f, 0.0f, 0.0f, 0.0f);
    out[2 * i + 1] = (float4)(0.0f, 0.0f, 0.0f, as_float(hit));
    return;
  }
  float3 p, p_error, n, dpdu;
  float2 uv;
  sdf_surface(rows, info[WT_SDF_INFO_ROWS * hit], o, d, best, cell, &p, &p_error, &n, &uv, &dpdu);
  out[2 * i] = (float4)(best, n.x, n.y, n.z);
  out[2 * i + 1] = (float4)(p_error, as_float(hit));
}
