// Stage 2: closest hit for every path in the input queue.
#include "bvh_packet.cl"
#include "bvh_prims.cl"
#include "bvh_prims_packet.cl"
#include "aov.cl"

WT_KERNEL void extend(__global const uint* counters, uint queue_slot, __global const uint* queue,
                      __global const float4* ray_o, __global const float4* ray_d,
                      __global const WtBvhNode* nodes, uint node_count,
                      __global const float4* tri_verts, __global float4* hits,
                      __global const uint* ray_skip, __global uint* hit_instance, __global float4* aov_sample,
                      WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint i = get_global_id(0);
  if (i >= counters[queue_slot]) return;
  uint path = queue[i];
  float4 o = ray_o[path];
  float4 d = ray_d[path];
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, path);
  GeometryScene g = WT_GEOMETRY_SCENE;
  // the ray leaves the path's last hit: ray_skip on the instance hit then
  uint instance;
  Hit hit = scene_closest(scene, g, o.xyz, d.xyz, o.w, d.w, ray_skip[path],
                          WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT, &instance);
  hits[path] = (float4)(hit.t, hit.b1, hit.b2, as_float(hit.prim));
#if WT_HAS_INSTANCES
  hit_instance[path] = instance;
#endif
#if WT_BVH_COST
  // a camera ray (the only rays that leave no surface): its count for the bvh-cost view
  if (ray_skip[path] == WT_NO_HIT) aov_sample[WT_AOV_SAMPLE_SLOTS * path + 3u].z = (float)hit.cost;
#endif
}

/// extend for queue entries [n i, n i + n), n = WT_PACKET_WIDTH, traced as
/// one packet (kernels/bvh_packet.cl): for queues whose neighbouring entries
/// are neighbouring pixels' camera rays. The same hits as extend.
WT_KERNEL void extend_packet(__global const uint* counters, uint queue_slot, __global const uint* queue,
                             __global const float4* ray_o, __global const float4* ray_d,
                             __global const WtBvhNode* nodes, uint node_count,
                             __global const float4* tri_verts, __global float4* hits,
                             __global const uint* ray_skip, __global uint* hit_instance, __global float4* aov_sample,
                      WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint first = get_global_id(0) * WT_PACKET;
  uint count = counters[queue_slot];
  if (first >= count) return;
  uint index[WT_PACKET];
  uint lanes = packet_from_queue(queue, first, count, index);
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, index[0]);  // packets set each lane's own (packet_set_alpha)
  packet_trace_closest(scene, index, lanes, ray_o, ray_d, ray_skip, hits);
#if WT_HAS_PRIMITIVES
  // the other primitive types as the same packet, in front of the triangles' hits
  GeometryScene g = WT_GEOMETRY_SCENE;
  prims_packet_trace_closest(scene, g, index, lanes, ray_o, ray_d, ray_skip, WT_HAS_INSTANCES ? hit_instance : 0,
                             hits);
#endif
}
