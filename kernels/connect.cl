// Stage 4 of a bounce: shadow rays queued by shade; an unblocked one adds
// its precomputed contribution to its path's radiance. For connect, entry i
// of the queue is shade item i's path or WT_NO_HIT (no shadow ray) and the
// count is the bounce's path count; connect_packet's queue is dense
// (WT_FLAG_COMPACT_SHADOWS); connect_stream takes either.
#include "bvh_packet.cl"
#include "bvh_prims.cl"
#include "bvh_prims_packet.cl"
#include "bvh_stream.cl"

WT_KERNEL void connect(__global const uint* counters, __global const uint* shadow_queue,
                       __global const float4* shadow_o, __global const float4* shadow_d,
                       __global const float4* shadow_radiance, __global const WtBvhNode* nodes,
                       uint node_count, __global const float4* tri_verts,
                       __global float4* radiance, __global const uint2* shadow_skip,
                       __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint i = get_global_id(0);
  if (i >= counters[WT_COUNTER_SHADOW]) return;
  uint path = shadow_queue[i];
  if (path == WT_NO_HIT) return;
  float4 o = shadow_o[path];
  float4 d = shadow_d[path];
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, path);
  GeometryScene g = WT_GEOMETRY_SCENE;
  uint2 skip = shadow_skip[path];
  // the shadow ray leaves the path's hit: skip.x on the instance hit
  uint skip_instance = WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT;
  if (!scene_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, skip.x, skip.y, skip_instance))
    radiance[path] += shadow_radiance[path];
}

/// connect for shadow-queue entries [n i, n i + n), n = WT_PACKET_WIDTH,
/// traced as one packet (kernels/bvh_packet.cl): for the shadow rays of
/// camera-ray hits, appended densely by shade. The same answers as connect.
WT_KERNEL void connect_packet(__global const uint* counters, __global const uint* shadow_queue,
                              __global const float4* shadow_o, __global const float4* shadow_d,
                              __global const float4* shadow_radiance, __global const WtBvhNode* nodes,
                              uint node_count, __global const float4* tri_verts,
                              __global float4* radiance, __global const uint2* shadow_skip,
                              __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint first = get_global_id(0) * WT_PACKET;
  uint count = counters[WT_COUNTER_SHADOW];
  if (first >= count) return;
  uint index[WT_PACKET];
  uint lanes = packet_from_queue(shadow_queue, first, count, index);
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, index[0]);  // packets set each lane's own (packet_set_alpha)
  int blocked[WT_PACKET];
  packet_vstore(packet_trace_occluded(scene, index, lanes, shadow_o, shadow_d, 0, shadow_skip), blocked);
#if WT_HAS_PRIMITIVES
  // the other primitive types as the same packet, for the rays no triangle blocks
  GeometryScene g = WT_GEOMETRY_SCENE;
  prims_packet_trace_occluded(scene, g, index, lanes, shadow_o, shadow_d, 0, shadow_skip,
                              WT_HAS_INSTANCES ? hit_instance : 0, blocked);
#endif
  for (uint l = 0; l < lanes; ++l)
    if (!blocked[l]) radiance[index[l]] += shadow_radiance[index[l]];
}

/// connect for shadow-queue entries [w i, w i + w), w = WT_STREAM_WINDOW,
/// traced as streams (kernels/bvh_stream.cl), grouped by octant as the
/// bench's trace_occluded_stream groups them: for incoherent shadow rays on a
/// CPU (Renderer's traversal choice). The same answers as connect.
WT_KERNEL void connect_stream(__global const uint* counters, __global const uint* shadow_queue,
                              __global const float4* shadow_o, __global const float4* shadow_d,
                              __global const float4* shadow_radiance, __global const WtBvhNode* nodes,
                              uint node_count, __global const float4* tri_verts,
                              __global float4* radiance, __global const uint2* shadow_skip,
                              __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS) {
  uint first = get_global_id(0) * WT_STREAM_WINDOW;
  uint count = counters[WT_COUNTER_SHADOW];
  if (first >= count) return;
  uint end = min(first + (uint)WT_STREAM_WINDOW, count);
  // the window's shadow rays (entries without one are WT_NO_HIT)
  uint paths[WT_STREAM_WINDOW], order[WT_STREAM_WINDOW];
  uint n = 0u;
  for (uint i = first; i < end; ++i) {
    uint path = shadow_queue[i];
    if (path != WT_NO_HIT) paths[n++] = path;
  }
  if (n == 0u) return;
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, paths[0]);  // the stream sets each ray's own (bvh_occluded_stream)
#if WT_STREAM_PREFETCH
  for (uint i = 0; i < n; ++i) order[i] = paths[i];
#else
  stream_sort_by_octant(paths, n, shadow_d, order);
#endif
#if WT_HAS_PRIMITIVES
  GeometryScene g = WT_GEOMETRY_SCENE;
#endif
  for (uint s = 0; s < n; s += WT_STREAM_RAYS) {
    uint m = min(n - s, (uint)WT_STREAM_RAYS);
    ulong blocked = bvh_occluded_stream(scene, order + s, m, shadow_o, shadow_d, (__global const uint*)shadow_skip, 2u);
    for (uint r = 0; r < m; ++r) {
      if ((blocked >> r) & 1ul) continue;
      uint path = order[s + r];
#if WT_HAS_PRIMITIVES
      // the other primitive types ray by ray, for the rays no triangle blocks
      WT_ALPHA_RAY(scene, path);
      float4 o = shadow_o[path], d = shadow_d[path];
      uint2 skip = shadow_skip[path];
      if (bvh_prims_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, skip.x, skip.y,
                             WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT))
        continue;
#endif
      radiance[path] += shadow_radiance[path];
    }
  }
}
