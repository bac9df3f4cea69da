// Test-only program root: every displaced base triangle tested against
// every ray, no BVH, with the surface at the hit
// (kernels/geometry/displaced.cl), and micro-vertices on their own, for
// tests/geometry/test_displaced.cpp.
#include "common.h"
#include "geometry/displaced.cl"

/// Per ray (origin xyz + tmin in w, direction xyz + tmax in w): out[3i] =
/// (t, the micro-triangle's unit normal), out[3i + 1] = (p_error, base
/// triangle as bits), out[3i + 2] = (shading normal, 0); t = -1 for a
/// miss. `rows` and `info` start at the type's first rows.
WT_KERNEL void test_displaced_closest(uint count, uint triangles, __global const float4* rows,
                                      __global const uint4* info, __global const float4* ray_o,
                                      __global const float4* ray_d, __global float4* out) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float3 o = ray_o[i].xyz, d = ray_d[i].xyz;
  float tmin = ray_o[i].w, best = ray_d[i].w;
  uint hit = 0xffffffffu;
  float li = 0.0f, lj = 0.0f;
  for (uint b = 0; b < triangles; ++b) {
    float t, u, v;
    if (displaced_intersect(rows, info + WT_DISP_INFO_ROWS * b, o, d, tmin, best, false, &t, &u, &v)) {
      best = t;
      hit = b;
      li = u;
      lj = v;
    }
  }
  if (hit == 0xffffffffu) {
    out[3 * i] = (float4)(-1.0f, 0.0f, 0.0f, 0.0f);
    out[3 * i + 1] = (float4)(0.0f, 0.0f, 0.0f, as_float(hit));
    out[3 * i + 2] = (float4)(0.0f);
    return;
  }
  float3 p, p_error, ng, ns, dpdu;
  float2 uv;
  displaced_surface(rows, info + WT_DISP_INFO_ROWS * hit, li, lj, &p, &p_error, &ng, &ns, &uv, &dpdu);
  out[3 * i] = (float4)(best, ng.x, ng.y, ng.z);
  out[3 * i + 1] = (float4)(p_error, as_float(hit));
  out[3 * i + 2] = (float4)(ns, 0.0f);
}

/// Micro-vertex (i, j) (query xyz: base triangle, i, j) as the intersection
/// computes it; with query w 1, from the map even where d is stored.
WT_KERNEL void test_displaced_vertex(uint count, __global const float4* rows, __global const uint4* info,
                                     __global const uint4* query, __global float4* out) {
  uint k = get_global_id(0);
  if (k >= count) return;
  uint4 q = query[k];
  __global const uint4* tri = info + WT_DISP_INFO_ROWS * q.x;
  DispMesh m = disp_mesh(rows, tri[0].y);
  DispTri t = disp_tri(rows, tri);
  if (q.w == 1u) t.d = 0;
  int n = 1 << m.level;
  out[k] = (float4)(disp_vertex(m, t, n, 1.0f / (float)n, (int)q.y, (int)q.z), 0.0f);
}

/// disp_slab_interval per case: slab[k] = (unit normal xyz, unused), bounds[k]
/// = (lo, hi), ray (origin, direction); out[k] = (enter, leave).
WT_KERNEL void test_displaced_slab(uint count, __global const float4* slab, __global const float2* bounds,
                                   __global const float4* ray_o, __global const float4* ray_d, __global float2* out) {
  uint k = get_global_id(0);
  if (k >= count) return;
  float enter, leave;
  disp_slab_interval(slab[k].xyz, bounds[k].x, bounds[k].y, ray_o[k].xyz, ray_d[k].xyz, &enter, &leave);
  out[k] = (float2)(enter, leave);
}
