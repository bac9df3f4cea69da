// Stage 3: at each path's hit, emission (MIS-weighted against light
// sampling), next-event estimation into the shadow queue, then (below the
// bounce limits) a new direction from the material and Russian roulette;
// surviving paths are appended to the output queue.
#include "common.h"
#include "geometry/geometry.cl"
#include "lights/light_sampling.cl"
#include "lights/light_tree.cl"
#include "sampler.cl"
#include "materials/bsdf.cl"
#include "materials/textured.cl"
#include "aov.cl"

#if WT_HAS_THIN_SHADOWS
/// With smooth thin walls that shadow rays cross: how many each shadow ray
/// may cross (kernels/connect.cl).
#define WT_THIN_SHADOW_SHADE_PARAMS , __global uint *shadow_walls
#else
#define WT_THIN_SHADOW_SHADE_PARAMS
#endif
#if WT_HAS_QUAD_LIGHTS
/// With rectangle lights: per leaf-order triangle, the light-list index of
/// the WT_LIGHT_QUAD it is half of (WT_NO_QUAD: none), for the pdf of its emission.
#define WT_QUAD_SHADE_PARAMS , __global const uint *emitter_quad
#else
#define WT_QUAD_SHADE_PARAMS
#endif

/// Whether a vertex weighs by the power heuristic where the frame as a whole
/// does not: WT_FLAG_POWER_LAMBERTIAN at a Lambertian vertex. Both of its
/// techniques must use the same heuristic: its light sample here, the light
/// its BSDF sample finds by the sign of the pdf it leaves (shade_emission_weight).
inline bool shade_power_here(WtFrameParams frame, bool lambertian) {
  return lambertian && (frame.flags & WT_FLAG_POWER_LAMBERTIAN) && !(frame.flags & WT_FLAG_POWER_HEURISTIC);
}

/// Weight of emission found by BSDF sampling (pdf_bsdf, solid angle) from a
/// light that NEE could also have sampled with pdf_light (0: NEE cannot).
inline float shade_emission_weight(WtFrameParams frame, float pdf_bsdf, float pdf_light) {
  // camera rays, and lights NEE never samples, count in full
  if (frame.bounce == 0 || pdf_bsdf == 0.0f || pdf_light <= 0.0f) return 1.0f;
  if (WT_INTEGRATOR_MINIMAL || !(frame.flags & WT_FLAG_NEE)) return 1.0f;
  // NEE without MIS already counted this light
  if (!(frame.flags & WT_FLAG_MIS)) return 0.0f;
  // a negative pdf: the vertex weighed its light sample by the power heuristic (shade_power_here)
  return pdf_bsdf < 0.0f ? mis_weight(-pdf_bsdf, pdf_light, frame.flags | WT_FLAG_POWER_HEURISTIC)
                         : mis_weight(pdf_bsdf, pdf_light, frame.flags);
}

#if WT_HAS_TRANSMISSION
/// What medium `id` (WT_MEDIUM_NONE: air) absorbs along `distance` (world
/// units; an infinite one crosses no absorbing medium unblocked: 1).
inline float3 shade_absorption(__global const WtMaterial* materials, uint id, float distance) {
  if (id == WT_MEDIUM_NONE || isinf(distance)) return (float3)(1.0f);
  float3 sigma = vec4_xyz(materials[id].volume);
  return sigma.x > 0.0f || sigma.y > 0.0f || sigma.z > 0.0f ? exp(-sigma * distance) : (float3)(1.0f);
}
#endif

/// With WT_FLAG_CHECK_NONFINITE, note the first non-finite value any path
/// makes (which path, bounce and quantity) for the host to stop at.
inline void shade_check_finite(WtFrameParams frame, __global uint* counters, uint path, float3 v, uint what) {
  if (!(frame.flags & WT_FLAG_CHECK_NONFINITE) || (isfinite(v.x) && isfinite(v.y) && isfinite(v.z))) return;
  if (atomic_cmpxchg(&counters[WT_COUNTER_FIRST_NONFINITE], 0xffffffffu, path) == 0xffffffffu)
    counters[WT_COUNTER_NONFINITE_WHERE] = frame.bounce | (what << 16);
}

#if WT_HAS_TEXTURES || WT_HAS_VERTEX_COLORS || WT_HAS_ANISOTROPY
/// The surface point the material reads at a triangle's hit (barycentrics
/// b1, b2), in world space: an instance's corners and tangent taken out of
/// object space, the bitangent's sign flipped on a mirrored copy. Shade and
/// the thin-wall shadow rays (connect.cl) read materials through it.
inline SurfacePoint triangle_surface_point(GeometryScene g, __global const float4* tri_verts, SurfaceScene ss,
                                           uint4 info, uint prim, uint instance, float b1, float b2,
                                           float footprint) {
  float3 p0, p1, p2;
  triangle_corners(tri_verts, prim, &p0, &p1, &p2);
#if WT_HAS_INSTANCES
  __global const float4* to_world = instance != WT_NO_HIT ? geometry_instance_rows(g, instance) + 3 : 0;
  if (to_world) p0 = instance_point(to_world, p0), p1 = instance_point(to_world, p1), p2 = instance_point(to_world, p2);
#endif
  SurfacePoint sp = surface_point(ss, info, b1, b2, p0, p1, p2, footprint);
#if WT_HAS_INSTANCES
  if (to_world && dot(sp.tangent, sp.tangent) > 0.0f) {
    sp.tangent = normalize(instance_vector(to_world, sp.tangent));
    if (geometry_instance_info(g, instance).y & WT_INSTANCE_MIRRORED) sp.sign = -sp.sign;
  }
#endif
  return sp;
}
#endif

/// shade's parameters, the same for one path per work-item and for lanes
#define WT_SHADE_KERNEL_PARAMS \
  WtFrameParams frame, WtEnvironment environment, __global const float4* env_texels, \
  __global const float* env_marginal_cdf, __global const float* env_conditional_cdf, \
  __global uint* counters, uint in_slot, uint out_slot, \
  __global const uint* queue_in, __global uint* queue_out, \
  __global float4* ray_o, __global float4* ray_d, \
  __global const float4* hits, __global float4* throughput, \
  __global float4* radiance, __global const uint4* tri_info, \
  __global const float4* tri_verts, __global const float4* normals, \
  __global const WtMaterial* materials, __global const WtLight* lights, \
  __global const WtAliasSlot* alias, __global const float* emitter_pdf_area, \
  __global uint* shadow_queue, __global float4* shadow_o, \
  __global float4* shadow_d, __global float4* shadow_radiance, \
  __global const float* pbr_table, __global ushort4* bounce_counts, \
  __global uint* ray_skip, __global uint2* shadow_skip, \
  __global const WtLightNode* light_tree, __global const uint* emitter_leaf, \
  __global float4* prev_normal, __global const uint* hit_instance, WT_GEOMETRY_PARAMS, \
  __global float2* ray_cone, __global float4* aov_sample, __global uint4* aov_ids, \
  __global uint4* media, WT_SURFACE_PARAMS WT_THIN_SHADOW_SHADE_PARAMS WT_QUAD_SHADE_PARAMS

#if WT_SHADE_LANES && WT_HAS_TRANSMISSION
/// WT_SHADE_KERNEL_PARAMS' names, to pass them on
#define WT_SHADE_KERNEL_ARGS                                                                                       \
  frame, environment, env_texels, env_marginal_cdf, env_conditional_cdf, counters, in_slot, out_slot, queue_in,   \
      queue_out, ray_o, ray_d, hits, throughput, radiance, tri_info, tri_verts, normals, materials, lights, alias,  \
      emitter_pdf_area, shadow_queue, shadow_o, shadow_d, shadow_radiance, pbr_table, bounce_counts, ray_skip,     \
      shadow_skip, light_tree, emitter_leaf, prev_normal, hit_instance, geometry, prim_nodes, prim_refs, prim_data, \
      prim_info, ray_cone, aov_sample, aov_ids, media, vertex_uv, vertex_color, vertex_tangent, material_textures,  \
      textures, texture_levels, texels WT_QUAD_SHADE_ARGS
#if WT_HAS_QUAD_LIGHTS
#define WT_QUAD_SHADE_ARGS , emitter_quad
#else
#define WT_QUAD_SHADE_ARGS
#endif
/// One path (queue entry i), shade.cl's whole estimator: the lanes kernel's
/// paths at transmitting surfaces other than its glass, inside a medium or past false hits.
/// Not inlined, so its private values stay out of the lanes' work-group frame.
__attribute__((noinline)) void shade_path(uint i, WT_SHADE_KERNEL_PARAMS);
#endif
#if WT_SHADE_LANES
#include "shade_lanes.cl"
#endif
#if !WT_SHADE_LANES || WT_HAS_TRANSMISSION
#if WT_SHADE_LANES
__attribute__((noinline)) void shade_path(uint i, WT_SHADE_KERNEL_PARAMS) {
#else
WT_KERNEL void shade(WT_SHADE_KERNEL_PARAMS) {
  uint i = get_global_id(0);
#endif
  if (i >= counters[in_slot]) return;
  // Without WT_FLAG_COMPACT_SHADOWS entry i of the shadow queue is this
  // item's shadow ray, if it makes one: no atomic counter, whose increments
  // from the two threads contended (docs/lab/2026-12-02-performance-log.md, "Queue atomics").
  // Without WT_FLAG_SHADOW_QUEUE the host runs no connect stage and the
  // shadow buffers hold one entry: nothing may be written there.
  const bool compact_shadows = (frame.flags & WT_FLAG_COMPACT_SHADOWS) != 0u;
  if (!compact_shadows && (frame.flags & WT_FLAG_SHADOW_QUEUE)) shadow_queue[i] = WT_NO_HIT;
  uint path = queue_in[i];
  float4 hit = hits[path];
  uint prim = as_uint(hit.w);
  float4 state = throughput[path];
  float3 beta = state.xyz;
  float pdf_prev = state.w;  // solid-angle pdf of the BSDF sample that made this ray; 0 for camera rays
  float3 dir = ray_d[path].xyz;
#if WT_HAS_TRANSMISSION
  // the path's bounces so far (below); false hits it passed for free took
  // wavefront passes but are no bounces (shared/media.h): its own bounce is
  // the pass less them, for the limits, roulette and its sampler dimensions.
  // A private copy: PoCL shares a by-value argument among a group's items.
  ushort4 counts = bounce_counts[path];
  WtFrameParams path_frame = frame;
  path_frame.bounce -= media_false_hits(counts.w);
#define frame path_frame
#endif

  EnvScene env = {environment, env_texels, env_marginal_cdf, env_conditional_cdf};
  GeometryScene g = WT_GEOMETRY_SCENE;
  SurfaceScene ss = WT_SURFACE_SCENE;
  LightScene ls = {lights, alias, frame.light_count, tri_verts, env, g, tri_info, ss};

#if WT_AOV
  __global float4* aov = aov_sample + WT_AOV_SAMPLE_SLOTS * path;
  if (frame.bounce == 0u) {
    aov_begin(aov);
    if (frame.sample == 0u) aov_ids[path] = (uint4)(WT_NO_HIT);
  }
#endif

  // miss: the environment (camera rays see it unless it is hidden)
  if (prim == WT_NO_HIT) {
#if WT_AOV
    aov_miss(aov, frame.bounce == 0u && (frame.flags & WT_FLAG_ENV_HIDDEN) ? (float3)(0.0f) : env_eval(env, dir));
#endif
    if (frame.bounce == 0 && (frame.flags & WT_FLAG_ENV_HIDDEN)) return;
    float3 le = env_eval(env, dir);
    float w = shade_emission_weight(frame, pdf_prev, frame.env_pmf * env_pdf(env, dir));
    shade_check_finite(frame, counters, path, beta * le * w, WT_NONFINITE_EMISSION);
    radiance[path] += (float4)(beta * le * w, 0.0f);
    return;
  }

  // an instance's hit: prim is its geometry's triangle. The path's next rays
  // leave (prim, instance): ray_skip and shadow_skip name the triangle, and
  // extend and connect read the instance from hit_instance, which stays as it
  // is until the next extend.
  uint instance = WT_HAS_INSTANCES ? hit_instance[path] : WT_NO_HIT;
  SurfaceHit surface = geometry_surface(g, tri_verts, tri_info, normals, prim, instance, ray_o[path].xyz, dir, hit);
  WtMaterial material = materials[surface.material];
  float3 p = surface.p, p_error = surface.p_error, ng = surface.ng, ns = surface.ns;
  if (dot(ng, ng) == 0.0f) return;  // degenerate triangle: absorb
  // the path's footprint here (textured.cl): its spread so far and this segment's cone
  float footprint = 0.0f;
  float cone_angle = 0.0f;
#if WT_HAS_TEXTURES
  if (frame.flags & WT_FLAG_TEXTURE_FOOTPRINT) {
    float2 cone = ray_cone[path];
    float dir_len = length(dir);
    float cos_hit = fabs(dot(ng, dir)) / dir_len;
    footprint = cone.x + hit.x * dir_len * cone.y * rsqrt(fmax(cos_hit, 1e-4f));
    cone_angle = cone.y;
  }
#endif
#if WT_AOV
  float2 aov_uv = (float2)(hit.y, hit.z);  // barycentrics unless the triangle has TEXCOORD_0
#endif
#if WT_HAS_ANISOTROPY
  float3 aniso_dir = (float3)(0.0f);  // the anisotropy direction, world (textured.cl); zero: none
#endif
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
  float3 coat_ns = (float3)(0.0f);  // the coat's own normal, world (textured.cl); zero: the shading normal's
#endif
#if WT_HAS_TEXTURES || WT_HAS_VERTEX_COLORS || WT_HAS_ANISOTROPY
  // triangles (an instance's too) carry vertex attributes and textures
  if (prim_type(prim) == WT_PRIM_TRIANGLE) {
    SurfacePoint sp = triangle_surface_point(g, tri_verts, ss, tri_info[prim], prim, instance, hit.y, hit.z, footprint);
#if WT_AOV && WT_HAS_TEXTURES
    aov_uv = sp.uv.xy;
#endif
#if WT_HAS_ANISOTROPY
    aniso_dir = anisotropy_direction(ss, surface.material, &material, sp, ns);  // before a normal map bends ns
#endif
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
    coat_ns = clearcoat_normal(ss, surface.material, material.texture_mask, sp, ns);  // before the base's map bends ns
#endif
    material = material_at(ss, surface.material, material, sp, &ns);
  }
#endif
  // ng is the winding's normal here: a ray meeting its back side comes from inside
  bool inside = dot(ng, dir) > 0.0f;
#if WT_HAS_TRANSMISSION
  // the volumes the path is inside (shared/media.h) and what this hit is to them
  uint4 media_in = media[path];
  WtMediaStack stack = {{media_in.x, media_in.y, media_in.z, media_in.w}};
  int current = media_current(&stack, materials);
#if WT_HAS_THIN_SHADOWS
  float3 absorbed = (float3)(1.0f);  // by the medium along this segment (undone where the ray goes on below)
#endif
  bool boundary = media_is_boundary(materials, surface.material);
  WtMediaCrossing crossing = {1u, 1.0f, 1.0f, WT_MEDIUM_NONE, WT_MEDIUM_NONE};
  if (boundary) crossing = media_crossing(&stack, materials, surface.material, !inside);
  // the medium the path is in absorbs along the way (Beer-Lambert): the
  // stack's current one, or the boundary's own when leaving one the stack lacks
  if (current >= 0 || (inside && boundary)) {
    float3 sigma = vec4_xyz(current >= 0 ? materials[stack.id[current]].volume : material.volume);
#if WT_HAS_THIN_SHADOWS
    if (sigma.x > 0.0f || sigma.y > 0.0f || sigma.z > 0.0f) {
      absorbed = exp(-sigma * (hit.x * length(dir)));
      beta *= absorbed;
    }
#else
    if (sigma.x > 0.0f || sigma.y > 0.0f || sigma.z > 0.0f) beta *= exp(-sigma * (hit.x * length(dir)));
#endif
  }
  // a false hit: the surface lies inside a medium that outranks it. The
  // path passes it unchanged and without a bounce of its own (it still takes
  // a wavefront pass; up to WT_MAX_FALSE_HITS, then each counts as one); pdf
  // 0 makes what it finds count in full, since NEE from the last vertex was
  // blocked by this surface.
  if (!crossing.real) {
    if (media_false_hits(counts.w) < WT_MAX_FALSE_HITS) {
      counts.w += (ushort)WT_FALSE_HIT_STEP;
      bounce_counts[path] = counts;
    } else if (frame.bounce >= frame.max_bounces) {
      return;
    }
    media_cross(&stack, materials, surface.material, !inside);
    media[path] = (uint4)(stack.id[0], stack.id[1], stack.id[2], stack.id[3]);
    throughput[path] = (float4)(beta, 0.0f);
#if WT_HAS_TEXTURES
    ray_cone[path] = (float2)(footprint, cone_angle);
#endif
    ray_skip[path] = prim;
    ray_o[path] = (float4)(ray_offset_origin(p, p_error, inside ? ng : -ng), 0.0f);
    queue_out[atomic_inc(&counters[out_slot])] = path;
    return;
  }
#endif

  // emission: the front face only unless the material is double-sided
  float3 le = vec4_xyz(material.emission);
  bool emits = material.emission.w != 0.0f || !inside;
  if (emits && (le.x > 0.0f || le.y > 0.0f || le.z > 0.0f)) {
    // the probability that NEE at the previous vertex would have picked this
    // emitter: its selection probability over its area, by the light tree's
    // choice at that vertex when the tree holds it (camera rays need none)
    float select = frame.bounce > 0u ? emitter_pdf_area[geometry_emitter_slot(g, prim)] : 0.0f;
    float pdf_light;
#if WT_HAS_PRIMITIVES
    if (prim_type(prim) != WT_PRIM_TRIANGLE) {
      pdf_light = select > 0.0f ? select * geometry_emitter_pdf(g, prim, ray_o[path].xyz, p, ng, hit) : 0.0f;
    } else
#endif
    {
#if WT_HAS_LIGHT_TREE
      uint leaf = emitter_leaf[prim];
      if (select > 0.0f && leaf != WT_LIGHT_NODE_NONE)
        select *= light_tree_pmf(light_tree, leaf, ray_o[path].xyz, prev_normal[path].xyz);
#endif
      float3 p0, p1, p2;
#if WT_HAS_QUAD_LIGHTS
      // half of a rectangle light: the pdf its sampler has, from the same corners
      uint quad = emitter_quad[prim];
      if (quad != WT_NO_QUAD) {
        light_quad_rect(lights[quad], &p0, &p1, &p2);
        pdf_light = light_quad_pdf(select, ray_o[path].xyz, p0, p1, p2, hit.x, dir, ng);
      } else {
        triangle_corners(tri_verts, prim, &p0, &p1, &p2);
        pdf_light = light_triangle_pdf(select, ray_o[path].xyz, p0, p1, p2, hit.x, dir, ng);
      }
#else
      triangle_corners(tri_verts, prim, &p0, &p1, &p2);
      pdf_light = light_triangle_pdf(select, ray_o[path].xyz, p0, p1, p2, hit.x, dir, ng);
#endif
    }
    float3 emitted = beta * le * shade_emission_weight(frame, pdf_prev, pdf_light);
    shade_check_finite(frame, counters, path, emitted, WT_NONFINITE_EMISSION);
    radiance[path] += (float4)(emitted, 0.0f);
  }
#if WT_AOV
  {
    // the guides' normal faces the ray, as the shading frame below does
    float3 n_aov = ns;
    if (dot(n_aov, dir) > 0.0f) n_aov = -n_aov;
    aov_surface(aov, material, n_aov);
    if (frame.bounce == 0u) {
      aov_camera_hit(aov, p, hit.x * length(dir), aov_uv);
      if (frame.sample == 0u) aov_ids[path] = (uint4)(surface.material, instance, prim, 0u);
    }
  }
#endif
  if (frame.bounce >= frame.max_bounces) return;

  float3 wo = -dir;
  if (dot(ng, wo) < 0.0f) ng = -ng;
  if (dot(ns, ng) < 0.0f) ns = -ns;
  // a shading normal turned away from the viewer gives way to the geometric one
  if (dot(ns, wo) <= 0.0f) ns = ng;
#if WT_HAS_TEXTURES
  if (material.texture_mask & (1u << WT_TEXTURE_SLOT_NORMAL)) ns = shading_normal_reflecting(ns, ng, wo);
#endif
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
  // the coat's normal faces the viewer and reflects above the surface, as ns does
  if (dot(coat_ns, coat_ns) > 0.0f) {
    if (dot(coat_ns, ng) < 0.0f) coat_ns = -coat_ns;
    if (dot(coat_ns, wo) <= 0.0f) coat_ns = ng;
    coat_ns = shading_normal_reflecting(coat_ns, ng, wo);
  }
#endif
  float3 frame_t, frame_b;
  frame_from_normal(ns, &frame_t, &frame_b);
#if WT_HAS_ANISOTROPY
  anisotropy_frame(aniso_dir, ns, &frame_t, &frame_b);
#endif
  float3 wo_local = (float3)(dot(wo, frame_t), dot(wo, frame_b), dot(wo, ns));
  // the path's diffuse, specular and transmission bounces so far (x, y, z);
  // w: the channel it carries alone past a dispersive interface, plus 1 (0:
  // all), and with transmission its free false hits (shared/media.h)
#if !WT_HAS_TRANSMISSION
  ushort4 counts = bounce_counts[path];
#endif
  Bsdf bsdf = bsdf_make(material, pbr_table, inside);
#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
  if (dot(coat_ns, coat_ns) > 0.0f)
    bsdf_coat_normal(&bsdf, (float3)(dot(coat_ns, frame_t), dot(coat_ns, frame_b), dot(coat_ns, ns)));
#endif
  // the index of the medium the path is in on each side of this surface (for roulette)
  float n_near = 1.0f, n_far = 1.0f;
#if WT_HAS_TRANSMISSION
  n_near = n_far = media_ior(&stack, materials, current);
  // a volume boundary refracts by the indices the stack gives its two sides
  // (n far / n near: the material's own index against air outside every other volume)
  if (boundary) {
    float ior_near = crossing.ior_near, ior_far = crossing.ior_far;
    float dispersion_near = crossing.near_id == WT_MEDIUM_NONE ? 0.0f : materials[crossing.near_id].dispersion;
    float dispersion_far = crossing.far_id == WT_MEDIUM_NONE ? 0.0f : materials[crossing.far_id].dispersion;
    if (dispersion_near > 0.0f || dispersion_far > 0.0f) {
      // KHR_materials_dispersion: the first such interface picks the channel the path carries alone
      // (three times as strong, so the mean over the pick is unbiased), each index at its wavelength
      if ((counts.w & WT_DISPERSION_BITS) == 0u) {
        uint c = min((uint)(sampler_get(frame, path, WT_DIM_WAVELENGTH) * 3.0f), 2u);
        counts.w = (ushort)(counts.w | (c + 1u));
        beta = (float3)(c == 0u ? 3.0f * beta.x : 0.0f, c == 1u ? 3.0f * beta.y : 0.0f, c == 2u ? 3.0f * beta.z : 0.0f);
      }
      ior_near = media_channel_ior(ior_near, dispersion_near, (counts.w & WT_DISPERSION_BITS) - 1u);
      ior_far = media_channel_ior(ior_far, dispersion_far, (counts.w & WT_DISPERSION_BITS) - 1u);
    }
    bsdf.eta = ior_far / ior_near;
    n_near = ior_near, n_far = ior_far;
    bsdf.smooth = bsdf.mirror || fabs(bsdf.eta - 1.0f) < 1e-3f;
  }
#endif
  float3 origin = ray_offset_origin(p, p_error, ng);

  // the lobes this path may still scatter by: its bounces so far against their limits
  uint lobes = ((uint)counts.x < frame.max_diffuse_bounces ? WT_LOBE_DIFFUSE : 0u) |
               ((uint)counts.y < frame.max_specular_bounces ? WT_LOBE_SPECULAR : 0u) |
               ((uint)counts.z < frame.max_transmission_bounces ? WT_LOBE_TRANSMISSION : 0u);
  if (lobes == 0u) return;
  // light may come through the surface: lights behind it count, rays leave from its far side,
  // and the light tree gives up its receiver-normal bound (a zero normal)
  bool through = bsdf_transmits(bsdf) && (lobes & WT_LOBE_TRANSMISSION);
  float3 origin_far = through ? ray_offset_origin(p, p_error, -ng) : origin;
  float3 tree_normal = through ? (float3)(0.0f) : ng;
  // the shading uniforms by Sobol pairs (sampler_get2; shared/dims.h pairs them)
  float2 u_pick_rr = sampler_get2(frame, path, WT_DIM_LIGHT_PICK);   // (LIGHT_PICK, RUSSIAN_ROULETTE)
  float2 u_lobe_tree = sampler_get2(frame, path, WT_DIM_BSDF_LOBE);  // (BSDF_LOBE, LIGHT_TREE)

  // next-event estimation: the full light list by power (path), or one
  // uniformly chosen analytic light (minimal)
  uint nee_count = WT_INTEGRATOR_MINIMAL ? frame.analytic_count
                                         : ((frame.flags & WT_FLAG_NEE) ? frame.light_count : 0u);
  if (nee_count > 0u) {
    float u_pick = u_pick_rr.x;
    float pmf;
    uint index;
    if (WT_INTEGRATOR_MINIMAL) {
      index = min((uint)(u_pick * (float)nee_count), nee_count - 1u);
      pmf = 1.0f / (float)nee_count;
    } else {
      index = light_pick(ls, u_pick, &pmf);
      // the light tree entry: an emitter by its importance here
#if WT_HAS_LIGHT_TREE
      if (ls.lights[index].type == WT_LIGHT_TREE) {
        float pmf_tree;
        index = light_tree_pick(light_tree, origin, tree_normal, u_lobe_tree.y, &pmf_tree);
        pmf *= pmf_tree;
      }
#endif
    }
    LightSample s;
    float2 u_light = sampler_get2(frame, path, WT_DIM_LIGHT_U);  // (LIGHT_U, LIGHT_V)
    float u1 = u_light.x, u2 = u_light.y;
    float3 f_cos = (float3)(0.0f);
    float pdf_bsdf = 0.0f;
    if (pmf > 0.0f && light_sample(ls, index, p, u1, u2, &s) && (dot(ng, s.wi) > 0.0f || through)) {
      float3 wi_local = (float3)(dot(s.wi, frame_t), dot(s.wi, frame_b), dot(s.wi, ns));
      f_cos = bsdf_eval(bsdf, wo_local, wi_local, lobes, &pdf_bsdf);
    }
    if (f_cos.x > 0.0f || f_cos.y > 0.0f || f_cos.z > 0.0f) {
      float pdf_light = s.pdf * pmf;
      float w = (s.is_delta || !(frame.flags & WT_FLAG_MIS) || WT_INTEGRATOR_MINIMAL)
                    ? 1.0f
                    : mis_weight(pdf_light, pdf_bsdf,
                                 frame.flags | (shade_power_here(frame, bsdf.model == WT_MATERIAL_DIFFUSE)
                                                    ? WT_FLAG_POWER_HEURISTIC
                                                    : 0u));
      float3 contribution = beta * f_cos * s.radiance * (w / pdf_light);
#if WT_HAS_TRANSMISSION
      // the medium on the shadow ray's side absorbs along it, as along a path's segment
      // (it crosses no volume boundary: those block it)
      contribution *= shade_absorption(materials,
                                       boundary ? (dot(ng, s.wi) > 0.0f ? crossing.near_id : crossing.far_id)
                                                : (current >= 0 ? stack.id[current] : WT_MEDIUM_NONE),
                                       s.distance);
#endif
      shade_check_finite(frame, counters, path, contribution, WT_NONFINITE_LIGHT);
      if (contribution.x > 0.0f || contribution.y > 0.0f || contribution.z > 0.0f) {
        // Aim from the offset origin at the target (the sampled point pushed
        // off the light's surface) and stop a relative margin short of it, so
        // the light's own surface never occludes. (Keeping the direction from
        // the unoffset point raised the ray by the offset, which at grazing
        // angles crossed the light's plane before the margin: found by a
        // square emitter 0.1 above a plane.)
        float3 shadow_origin = dot(ng, s.wi) > 0.0f ? origin : origin_far;
        float3 shadow_dir = s.wi;
        float tmax = INFINITY;
        if (!isinf(s.distance)) {
          float3 to_target = s.target - shadow_origin;
          float len = length(to_target);
          shadow_dir = to_target / len;
          tmax = len * (1.0f - WT_SHADOW_MARGIN);
        }
        // a zero-length connection (the light point is the origin) carries nothing
        if (tmax > 0.0f) {
          shadow_queue[compact_shadows ? atomic_inc(&counters[WT_COUNTER_SHADOW]) : i] = path;
          shadow_o[path] = (float4)(shadow_origin, 0.0f);
          shadow_d[path] = (float4)(shadow_dir, tmax);
          shadow_radiance[path] = (float4)(contribution, 0.0f);
          shadow_skip[path] = (uint2)(prim, s.prim);
#if WT_HAS_THIN_SHADOWS
          // It crosses as many thin walls as a path leaving here along s.wi
          // could pass straight through: each is a transmission bounce,
          // below --max-bounces and the transmission limit (a path through
          // more would stop at a wall, so NEE must not find its light either).
          int walls_bounces = (int)frame.max_bounces - 1 - (int)frame.bounce;
          int walls_transmission = (int)frame.max_transmission_bounces - (int)counts.z - (dot(ng, s.wi) > 0.0f ? 0 : 1);
          shadow_walls[path] = (uint)max(min(walls_bounces, walls_transmission), 0);
#endif
        }
      }
    }
  }

  // the next direction from the BSDF; one below the geometric surface is absorbed
  BsdfSample bs;
  float2 u_bsdf = sampler_get2(frame, path, WT_DIM_BSDF_U);  // (BSDF_U, BSDF_V)
  if (!bsdf_sample(bsdf, wo_local, lobes, u_lobe_tree.x, u_bsdf.x, u_bsdf.y, &bs)) return;
  float3 wi = bs.wi.x * frame_t + bs.wi.y * frame_b + bs.wi.z * ns;
  bool crossed = (bs.lobe & WT_LOBE_TRANSMISSION) != 0u;
  if (crossed ? dot(wi, ng) >= 0.0f : dot(wi, ng) <= 0.0f) return;
  beta *= bs.weight;
  if (bs.lobe & WT_LOBE_DIFFUSE) counts.x++;
  else if (crossed) counts.z++;
  else counts.y++;

  // Russian roulette: survive with probability from the throughput, reweight.
  // The throughput counts n^2 less inside a medium of index n (radiance
  // scaling at each crossing), which comes back on the way out: undone here,
  // so paths inside glass are not culled for it.
  if (!WT_INTEGRATOR_MINIMAL && (frame.flags & WT_FLAG_RR) && frame.bounce >= frame.rr_min_depth) {
    float n = crossed ? n_far : n_near;
    float q = fmin(fmax(beta.x, fmax(beta.y, beta.z)) * n * n, 0.95f);
    if (u_pick_rr.y >= q) return;
    beta /= q;
  }
  shade_check_finite(frame, counters, path, beta, WT_NONFINITE_THROUGHPUT);
  if (beta.x <= 0.0f && beta.y <= 0.0f && beta.z <= 0.0f) return;
#if WT_HAS_THIN_SHADOWS
  // Straight through a wall shadow rays cross: the ray goes on from where it
  // came (the last vertex, or the camera) past this hit, keeping that
  // vertex's pdf, normal and cone, so a light it finds is weighed against
  // NEE from that vertex, which reached the light through this wall
  // (connect.cl). ray_skip keeps it off this surface and tmin off the ones
  // before; the media stack is the same on both sides of a thin wall, and
  // the medium absorbs along the whole ray at its next hit.
  if ((bs.lobe & WT_LOBE_DELTA) && crossed && material.shadow_pass) {
    throughput[path] = (float4)(beta / absorbed, pdf_prev);
    bounce_counts[path] = counts;
    ray_skip[path] = prim;
    ray_o[path].w = hit.x;
    queue_out[atomic_inc(&counters[out_slot])] = path;
    return;
  }
#endif

  // the pdf's sign carries the vertex's MIS heuristic to the light the ray may find
  throughput[path] = (float4)(beta, shade_power_here(frame, bsdf.model == WT_MATERIAL_DIFFUSE) ? -bs.pdf : bs.pdf);
#if WT_HAS_TEXTURES
  // the next segment's cone: as wide as the sample's pdf says, narrowed for
  // the pixel's later samples as the camera's cone is (generate.cl), so the
  // mean converges to unfiltered textures at every bounce; a delta sample
  // keeps the angle it came with
  ray_cone[path] = (float2)(footprint, bs.pdf > 0.0f ? rsqrt(bs.pdf * ((float)frame.sample + 1.0f)) : cone_angle);
#endif
  bounce_counts[path] = counts;
#if WT_HAS_TRANSMISSION
  if (crossed && boundary) {
    media_cross(&stack, materials, surface.material, !inside);
    media[path] = (uint4)(stack.id[0], stack.id[1], stack.id[2], stack.id[3]);
  }
#endif
  ray_skip[path] = prim;
  prev_normal[path] = (float4)(tree_normal, 0.0f);  // for the light tree's pmf if the ray finds an emitter
  ray_o[path] = (float4)(crossed ? origin_far : origin, 0.0f);
  ray_d[path] = (float4)(wi, INFINITY);
  uint slot = atomic_inc(&counters[out_slot]);
  queue_out[slot] = path;
}
#if WT_HAS_TRANSMISSION
#undef frame
#endif
#endif  // !WT_SHADE_LANES || WT_HAS_TRANSMISSION
