// Stage 4 of a bounce: shadow rays queued by shade; an unblocked one adds
// its precomputed contribution to its path's radiance. For connect, entry i
// of the queue is shade item i's path or WT_NO_HIT (no shadow ray) and the
// count is the bounce's path count; connect_packet's queue is dense
// (WT_FLAG_COMPACT_SHADOWS); connect_stream takes either.
#include "bvh_packet.cl"
#include "bvh_prims.cl"
#include "bvh_prims_packet.cl"
#include "bvh_stream.cl"
#include "materials/bsdf.cl"

#if WT_HAS_THIN_SHADOWS
/// With smooth thin walls that shadow rays cross (WtMaterial::shadow_pass):
/// how many each shadow ray may cross (shade), and what weighs a wall.
#define WT_THIN_SHADOW_PARAMS                                                                                    \
  , __global const uint *shadow_walls, __global const WtMaterial *thin_materials,                               \
      __global const uint4 *thin_tri_info, __global const float4 *thin_normals, __global const float *thin_pbr_table
#define WT_THIN_WALLS {thin_materials, thin_tri_info, thin_normals, thin_pbr_table}

typedef struct ThinWalls {
  __global const WtMaterial* materials;
  __global const uint4* tri_info;
  __global const float4* normals;
  __global const float* pbr_table;
} ThinWalls;

/// What a shadow ray that something blocked still carries: the product of
/// the straight-through transmission (bsdf_thin_pass) of the walls it
/// crosses, at most `walls` of them, or 0 where any other surface, or one
/// wall more, is in the way. The closest hits one after another, so each
/// wall is weighed from the side the ray meets, as shade weighs a path that
/// crosses it; glass that bends light (a volume boundary) and rough walls
/// block, their light found by BSDF sampling and by NEE at their own vertices.
inline float3 connect_through_walls(BvhScene scene, GeometryScene g, ThinWalls t, float4 o, float4 d, uint2 skip,
                                    uint skip_instance, uint walls) {
  float3 pass = (float3)(1.0f);
  float tmin = o.w;
  uint skip_prim = skip.x;
  uint crossed = 0u;
  // each hit moves tmin on (hits are in (tmin, tmax)); walls <= --max-bounces ends the loop
  for (;;) {
    uint instance;
    Hit hit = scene_closest(scene, g, o.xyz, d.xyz, tmin, d.w, skip_prim, skip_instance, &instance);
    if (hit.prim == WT_NO_HIT) return pass;
    tmin = hit.t;
    skip_prim = hit.prim;
    skip_instance = instance;
    if (hit.prim == skip.y) continue;  // the light aimed at blocks nothing (scene_occluded skips it too)
    if (crossed == walls) return (float3)(0.0f);
    ++crossed;
    float4 h = (float4)(hit.t, hit.b1, hit.b2, as_float(hit.prim));
    SurfaceHit sh = geometry_surface(g, scene.tri_verts, t.tri_info, t.normals, hit.prim, instance, o.xyz, d.xyz, h);
    WtMaterial m = t.materials[sh.material];
    if (!m.shadow_pass || dot(sh.ng, sh.ng) == 0.0f) return (float3)(0.0f);
    // the shading normal as shade turns it: to the ray's side, else the geometric one
    float3 wo = -d.xyz, ng = sh.ng, ns = sh.ns;
    if (dot(ng, wo) < 0.0f) ng = -ng;
    if (dot(ns, ng) < 0.0f) ns = -ns;
    if (dot(ns, wo) <= 0.0f) ns = ng;
    // isotropic and without a coat normal: only the cosine matters
    float mu = fmin(dot(wo, ns), 1.0f);
    pass *= bsdf_thin_pass(bsdf_make(m, t.pbr_table, 0), (float3)(sqrt(fmax(1.0f - mu * mu, 0.0f)), 0.0f, mu));
    if (!(pass.x > 0.0f || pass.y > 0.0f || pass.z > 0.0f)) return (float3)(0.0f);
  }
}

/// Add a blocked shadow ray's contribution through the walls it may cross.
#define WT_CONNECT_THROUGH_WALLS(scene, g, path, skip_instance)                                                \
  do {                                                                                                          \
    ThinWalls walls_ = WT_THIN_WALLS;                                                                           \
    float3 pass_ = connect_through_walls(scene, g, walls_, shadow_o[path], shadow_d[path], shadow_skip[path],   \
                                         skip_instance, shadow_walls[path]);                                    \
    if (pass_.x > 0.0f || pass_.y > 0.0f || pass_.z > 0.0f)                                                      \
      radiance[path] += shadow_radiance[path] * (float4)(pass_, 0.0f);                                          \
  } while (0)
#else
#define WT_THIN_SHADOW_PARAMS
#endif

WT_KERNEL void connect(__global const uint* counters, __global const uint* shadow_queue,
                       __global const float4* shadow_o, __global const float4* shadow_d,
                       __global const float4* shadow_radiance, __global const WtBvhNode* nodes,
                       uint node_count, __global const float4* tri_verts,
                       __global float4* radiance, __global const uint2* shadow_skip,
                       __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS WT_THIN_SHADOW_PARAMS) {
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
#if WT_HAS_THIN_SHADOWS
  else
    WT_CONNECT_THROUGH_WALLS(scene, g, path, skip_instance);
#endif
}

/// connect for shadow-queue entries [n i, n i + n), n = WT_PACKET_WIDTH,
/// traced as one packet (kernels/bvh_packet.cl): for the shadow rays of
/// camera-ray hits, appended densely by shade. The same answers as connect.
WT_KERNEL void connect_packet(__global const uint* counters, __global const uint* shadow_queue,
                              __global const float4* shadow_o, __global const float4* shadow_d,
                              __global const float4* shadow_radiance, __global const WtBvhNode* nodes,
                              uint node_count, __global const float4* tri_verts,
                              __global float4* radiance, __global const uint2* shadow_skip,
                              __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS WT_THIN_SHADOW_PARAMS) {
  uint first = get_global_id(0) * WT_PACKET;
  uint count = counters[WT_COUNTER_SHADOW];
  if (first >= count) return;
  uint index[WT_PACKET];
  uint lanes = packet_from_queue(shadow_queue, first, count, index);
  BvhScene scene = {nodes, node_count, tri_verts};
  WT_ALPHA_BIND(scene, index[0]);  // packets set each lane's own (packet_set_alpha)
  int blocked[WT_PACKET];
  packet_vstore(packet_trace_occluded(scene, index, lanes, shadow_o, shadow_d, 0, shadow_skip), blocked);
#if WT_HAS_PRIMITIVES || WT_HAS_THIN_SHADOWS
  GeometryScene g = WT_GEOMETRY_SCENE;
#endif
#if WT_HAS_PRIMITIVES
  // the other primitive types as the same packet, for the rays no triangle blocks
  prims_packet_trace_occluded(scene, g, index, lanes, shadow_o, shadow_d, 0, shadow_skip,
                              WT_HAS_INSTANCES ? hit_instance : 0, blocked);
#endif
  for (uint l = 0; l < lanes; ++l) {
    if (!blocked[l]) {
      radiance[index[l]] += shadow_radiance[index[l]];
      continue;
    }
#if WT_HAS_THIN_SHADOWS
    // a blocked ray on its own through the walls it may cross
    WT_ALPHA_RAY(scene, index[l]);
    WT_CONNECT_THROUGH_WALLS(scene, g, index[l], WT_HAS_INSTANCES ? hit_instance[index[l]] : WT_NO_HIT);
#endif
  }
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
                              __global const uint* hit_instance, WT_GEOMETRY_PARAMS WT_ALPHA_PARAMS WT_THIN_SHADOW_PARAMS) {
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
#if WT_HAS_PRIMITIVES || WT_HAS_THIN_SHADOWS
  GeometryScene g = WT_GEOMETRY_SCENE;
#endif
  for (uint s = 0; s < n; s += WT_STREAM_RAYS) {
    uint m = min(n - s, (uint)WT_STREAM_RAYS);
    ulong blocked = bvh_occluded_stream(scene, order + s, m, shadow_o, shadow_d, (__global const uint*)shadow_skip, 2u);
    for (uint r = 0; r < m; ++r) {
#if WT_HAS_THIN_SHADOWS
      // a blocked ray on its own through the walls it may cross
      if ((blocked >> r) & 1ul) {
        WT_ALPHA_RAY(scene, order[s + r]);
        WT_CONNECT_THROUGH_WALLS(scene, g, order[s + r], WT_HAS_INSTANCES ? hit_instance[order[s + r]] : WT_NO_HIT);
        continue;
      }
#else
      if ((blocked >> r) & 1ul) continue;
#endif
      uint path = order[s + r];
#if WT_HAS_PRIMITIVES
      // the other primitive types ray by ray, for the rays no triangle blocks
      WT_ALPHA_RAY(scene, path);
      float4 o = shadow_o[path], d = shadow_d[path];
      uint2 skip = shadow_skip[path];
      if (bvh_prims_occluded(scene, g, o.xyz, d.xyz, o.w, d.w, skip.x, skip.y,
                             WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT)) {
#if WT_HAS_THIN_SHADOWS
        WT_CONNECT_THROUGH_WALLS(scene, g, path, WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT);
#endif
        continue;
      }
#endif
      radiance[path] += shadow_radiance[path];
    }
  }
}
