// Ray batches outside the wavefront loop, for tests and benchmarks: rays in,
// closest hits or occlusion flags out. A program of its own (Tracer), built
// only where rays are traced outside a render.
#include "bvh.cl"
#include "bvh_packet.cl"
#include "bvh_stream.cl"
#include "bvh_prims.cl"
#include "bvh_prims_packet.cl"

#if WT_HAS_PRIMITIVES
/// Rays [first, end) that no triangle blocks, against the other primitive types.
inline void trace_prims_occluded(uint first, uint end, __global const float4* ray_o, __global const float4* ray_d,
                                 __global const uint* skip, __global const uint* skip_instance,
                                 __global uint* occluded, BvhScene scene, GeometryScene g) {
  for (uint i = first; i < end; ++i) {
    if (occluded[i]) continue;
    WT_ALPHA_RAY(scene, i);
    float4 o = ray_o[i], d = ray_d[i];
    occluded[i] = bvh_prims_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, skip[i], WT_NO_HIT, skip_instance[i]) ? 1u : 0u;
  }
}
#endif

WT_KERNEL void trace_closest(uint count, __global const float4* ray_o, __global const float4* ray_d,
                             __global const WtBvhNode* nodes, uint node_count,
                             __global const float4* tri_verts, __global float4* hits,
                             __global const uint* skip, __global uint* instances, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 o = ray_o[i];
  float4 d = ray_d[i];
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, i);
  GeometryScene g = WT_GEOMETRY_SCENE;
  uint instance;
  Hit hit = scene_closest(scene, g, o.xyz, d.xyz, o.w, d.w, skip[i], WT_HAS_INSTANCES ? instances[i] : WT_NO_HIT,
                          &instance);
  hits[i] = (float4)(hit.t, hit.b1, hit.b2, as_float(hit.prim));
#if WT_HAS_INSTANCES
  instances[i] = instance;  // in: the instance of the surface the ray leaves; out: the instance hit
#endif
}

WT_KERNEL void trace_occluded(uint count, __global const float4* ray_o,
                              __global const float4* ray_d, __global const WtBvhNode* nodes,
                              uint node_count, __global const float4* tri_verts,
                              __global uint* occluded, __global const uint* skip, __global uint* instances,
                              WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint i = get_global_id(0);
  if (i >= count) return;
  float4 o = ray_o[i];
  float4 d = ray_d[i];
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, i);
  GeometryScene g = WT_GEOMETRY_SCENE;
  occluded[i] = scene_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, skip[i], WT_NO_HIT,
                               WT_HAS_INSTANCES ? instances[i] : WT_NO_HIT) ? 1u : 0u;
}

// Any hit for incoherent rays as streams (kernels/bvh_stream.cl): work-item
// i takes rays [WT_STREAM_WINDOW i, WT_STREAM_WINDOW (i + 1)).
WT_KERNEL void trace_occluded_stream(uint count, __global const float4* ray_o,
                                     __global const float4* ray_d, __global const WtBvhNode* nodes,
                                     uint node_count, __global const float4* tri_verts,
                                     __global uint* occluded, __global const uint* skip,
                                     __global uint* instances, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint i = get_global_id(0);
  if (i >= (count + WT_STREAM_WINDOW - 1u) / WT_STREAM_WINDOW) return;
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, i);  // the stream sets each ray's own (bvh_occluded_stream)
  uint first = i * WT_STREAM_WINDOW;
  bvh_occluded_window(scene, first, min(first + WT_STREAM_WINDOW, count), ray_o, ray_d, skip, occluded);
#if WT_HAS_PRIMITIVES
  GeometryScene g = WT_GEOMETRY_SCENE;
  trace_prims_occluded(first, min(first + WT_STREAM_WINDOW, count), ray_o, ray_d, skip, instances, occluded, scene, g);
#endif
}

// The same queries, WT_PACKET_WIDTH consecutive rays per work-item
// (kernels/bvh_packet.cl): work-item i traces rays [n i, n i + n).
WT_KERNEL void trace_closest_packet(uint count, __global const float4* ray_o, __global const float4* ray_d,
                                    __global const WtBvhNode* nodes, uint node_count,
                                    __global const float4* tri_verts, __global float4* hits,
                                    __global const uint* skip, __global uint* instances, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint first = get_global_id(0) * WT_PACKET;
  if (first >= count) return;
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, first);  // packets set each lane's own (packet_set_alpha)
  uint index[WT_PACKET];
  for (uint l = 0; l < WT_PACKET; ++l) index[l] = first + l;
  packet_trace_closest(scene, index, min(count - first, (uint)WT_PACKET), ray_o, ray_d, skip, hits);
#if WT_HAS_PRIMITIVES
  // the other primitive types as the same packet (kernels/bvh_prims_packet.cl)
  GeometryScene g = WT_GEOMETRY_SCENE;
  prims_packet_trace_closest(scene, g, index, min(count - first, (uint)WT_PACKET), ray_o, ray_d, skip, instances,
                             hits);
#endif
}

WT_KERNEL void trace_occluded_packet(uint count, __global const float4* ray_o, __global const float4* ray_d,
                                     __global const WtBvhNode* nodes, uint node_count,
                                     __global const float4* tri_verts, __global uint* occluded,
                                     __global const uint* skip, __global uint* instances, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint first = get_global_id(0) * WT_PACKET;
  if (first >= count) return;
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, first);  // packets set each lane's own (packet_set_alpha)
  uint index[WT_PACKET];
  for (uint l = 0; l < WT_PACKET; ++l) index[l] = first + l;
  uint lanes = min(count - first, (uint)WT_PACKET);
  pint blocked_lanes = packet_trace_occluded(scene, index, lanes, ray_o, ray_d, skip, 0);
#if WT_HAS_PRIMITIVES
  {
    int lane_blocked[WT_PACKET];
    packet_vstore(blocked_lanes, lane_blocked);
    GeometryScene g = WT_GEOMETRY_SCENE;
    prims_packet_trace_occluded(scene, g, index, lanes, ray_o, ray_d, skip, 0, instances, lane_blocked);
    blocked_lanes = packet_vload(lane_blocked);
  }
#endif
  puint blocked = as_puint(blocked_lanes) & 1u;
  if (lanes == WT_PACKET) {
    packet_vstore(blocked, occluded + first);
  } else {
    uint lane_blocked[WT_PACKET];
    packet_vstore(blocked, lane_blocked);
    for (uint l = 0; l < lanes; ++l) occluded[first + l] = lane_blocked[l];
  }
}
