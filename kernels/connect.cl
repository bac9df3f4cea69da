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
// expanded where shade.cl first includes it (expandKernelSource): no change to the program
#include "materials/textured.cl"

#if WT_HAS_THIN_SHADOWS
/// With smooth thin walls that shadow rays cross (WtMaterial::shadow_pass):
/// how many each shadow ray may cross (shade), and what weighs a wall: its
/// material, normals and (triangles) the vertex colours and textures that
/// tint it.
#define WT_THIN_SHADOW_PARAMS                                                                                    \
  , __global const uint *shadow_walls, __global const WtMaterial *thin_materials,                               \
      __global const uint4 *thin_tri_info, __global const float4 *thin_normals, __global const float *thin_pbr_table, \
      __global const float4 *thin_vertex_uv, __global const float4 *thin_vertex_color,                           \
      __global const float4 *thin_vertex_tangent, __global const WtTextureRef *thin_material_textures,           \
      __global const WtTexture *thin_textures, __global const WtTextureLevel *thin_texture_levels,               \
      __global const uint *thin_texels
#define WT_THIN_WALLS                                                                                            \
  {thin_materials, thin_tri_info, thin_normals, thin_pbr_table,                                                  \
   {thin_vertex_uv, thin_vertex_color, thin_vertex_tangent, thin_material_textures, thin_textures,              \
    thin_texture_levels, thin_texels}}

typedef struct ThinWalls {
  __global const WtMaterial* materials;
  __global const uint4* tri_info;
  __global const float4* normals;
  __global const float* pbr_table;
  SurfaceScene surface;  ///< vertex colours and textures (textured.cl)
} ThinWalls;

#if WT_HAS_TEXTURES || WT_HAS_VERTEX_COLORS
/// Material `index` (`m`) at a triangle's hit (barycentrics b) as shade
/// reads it (material_at): tinted by COLOR_0 and its textures, *ns bent by
/// its normal map, *coat_ns the coat's own normal (zero: none). Textures
/// are read at their finest level: a shadow ray has no footprint of its
/// own, and the finest level is what the paths' filtered reads converge to
/// (their cones narrow with the sample index).
inline WtMaterial connect_wall_material(GeometryScene g, __global const float4* tri_verts, ThinWalls t, uint prim,
                                        uint instance, float2 b, uint index, WtMaterial m, float3* ns,
                                        float3* coat_ns) {
  *coat_ns = (float3)(0.0f);
  if (prim_type(prim) != WT_PRIM_TRIANGLE) return m;
  SurfacePoint sp = triangle_surface_point(g, tri_verts, t.surface, t.tri_info[prim], prim, instance, b.x, b.y, 0.0f);
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
  *coat_ns = clearcoat_normal(t.surface, index, m.texture_mask, sp, *ns);  // before the base's map bends ns
#endif
  return material_at(t.surface, index, m, sp, ns);
}
#endif

/// What a shadow ray that something blocked still carries: the product of
/// the straight-through transmission (bsdf_thin_pass) of the walls it
/// crosses, at most `walls` of them, or 0 where any other surface, or one
/// wall more, is in the way. The closest hits one after another, so each
/// wall is weighed from the side the ray meets, at the point it meets, as
/// shade weighs a path that crosses it; glass that bends light (a volume
/// boundary) and rough walls block, their light found by BSDF sampling and
/// by NEE at their own vertices.
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
    // the normals and the material as shade has them at this point
    float3 wo = -d.xyz, ng = sh.ng, ns = sh.ns;
#if WT_HAS_TEXTURES || WT_HAS_VERTEX_COLORS
    float3 coat_ns;
    m = connect_wall_material(g, scene.tri_verts, t, hit.prim, instance, (float2)(hit.b1, hit.b2), sh.material, m, &ns,
                              &coat_ns);
#endif
    if (dot(ng, wo) < 0.0f) ng = -ng;
    if (dot(ns, ng) < 0.0f) ns = -ns;
    if (dot(ns, wo) <= 0.0f) ns = ng;
#if WT_HAS_TEXTURES
    if (m.texture_mask & (1u << WT_TEXTURE_SLOT_NORMAL)) ns = shading_normal_reflecting(ns, ng, wo);
#endif
    Bsdf b = bsdf_make(m, t.pbr_table, 0);
    float3 frame_t, frame_b;
    frame_from_normal(ns, &frame_t, &frame_b);
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
    if (dot(coat_ns, coat_ns) > 0.0f) {
      if (dot(coat_ns, ng) < 0.0f) coat_ns = -coat_ns;
      if (dot(coat_ns, wo) <= 0.0f) coat_ns = ng;
      coat_ns = shading_normal_reflecting(coat_ns, ng, wo);
      bsdf_coat_normal(&b, (float3)(dot(coat_ns, frame_t), dot(coat_ns, frame_b), dot(coat_ns, ns)));
    }
#endif
    // isotropic (no anisotropy on such walls): the frame's turn about ns does not matter
    pass *= bsdf_thin_pass(b, (float3)(dot(wo, frame_t), dot(wo, frame_b), dot(wo, ns)));
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
