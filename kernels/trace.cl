// Ray batches outside the wavefront loop, for tests and benchmarks: rays in,
// closest hits or occlusion flags out.
#include "bvh.cl"

__kernel void trace_closest(uint count, __global const float4* ray_o, __global const float4* ray_d,
                            __global const WtBvhNode* nodes, uint node_count,
                            __global const float4* tri_verts, __global float4* hits,
                            __global const uint* skip) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 o = ray_o[i];
  float4 d = ray_d[i];
  BvhScene scene = {nodes, node_count, tri_verts};
  Hit hit = bvh_closest(scene, o.xyz, d.xyz, o.w, d.w, skip[i]);
  hits[i] = (float4)(hit.t, hit.b1, hit.b2, as_float(hit.prim));
}

__kernel void trace_occluded(uint count, __global const float4* ray_o,
                             __global const float4* ray_d, __global const WtBvhNode* nodes,
                             uint node_count, __global const float4* tri_verts,
                             __global uint* occluded, __global const uint* skip) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 o = ray_o[i];
  float4 d = ray_d[i];
  BvhScene scene = {nodes, node_count, tri_verts};
  occluded[i] = bvh_occluded(scene, o.xyz, d.xyz, o.w, d.w, skip[i], WT_NO_HIT) ? 1u : 0u;
}
