// A material at a triangle's hit: its factors times what the vertex colours
// and its textures say there, and the shading normal bent by its normal map.
// Textures are read at a mip level chosen by the path's footprint: the
// width of the ray cone at the camera hit (Akenine-Moller et al. 2019), and
// at later hits the path spread of Muller et al. 2021 (section 3.4), which
// adds sqrt(d^2 / (p(w) |cos|)) per segment, so a diffuse bounce (a wide
// pdf) reads a coarse level and a mirror keeps the footprint it had.
#ifndef WT_MATERIALS_TEXTURED_CL
#define WT_MATERIALS_TEXTURED_CL

#include "common.h"
#include "materials/texture.cl"

/// The per-vertex attributes and textures (host: bindSurface, device/scene_args.h): a
/// kernel that takes WT_SURFACE_PARAMS makes its SurfaceScene with
/// WT_SURFACE_SCENE. Buffers a scene does not use hold one dummy entry.
#define WT_SURFACE_PARAMS                                                                                    \
  __global const float4 *vertex_uv, __global const float4 *vertex_color, __global const float4 *vertex_tangent, \
      __global const WtTextureRef *material_textures, __global const WtTexture *textures,                     \
      __global const WtTextureLevel *texture_levels, __global const uint *texels
#define WT_SURFACE_SCENE {vertex_uv, vertex_color, vertex_tangent, material_textures, textures, texture_levels, texels}

typedef struct SurfaceScene {
  __global const float4* uv;       ///< per vertex: xy TEXCOORD_0, zw TEXCOORD_1
  __global const float4* color;    ///< per vertex: COLOR_0
  __global const float4* tangent;  ///< per vertex: xyz unit tangent (zero: none), w the bitangent's side
  __global const WtTextureRef* refs;  ///< WT_TEXTURE_SLOTS per material
  __global const WtTexture* textures;
  __global const WtTextureLevel* levels;
  __global const uint* texels;
} SurfaceScene;

/// What a triangle's vertices give its hit point.
typedef struct SurfacePoint {
  float4 uv;         ///< xy TEXCOORD_0, zw TEXCOORD_1
  float2 uv_scale;   ///< per set: sqrt(uv area / world area) of the triangle, uv units per world unit
  float4 color;      ///< COLOR_0; 1 without
  float3 tangent;    ///< world, unit; zero: none
  float sign;        ///< the bitangent is sign * cross(n, tangent)
  float footprint;   ///< world width of the path's footprint here; 0: the finest level
} SurfacePoint;

/// The attributes at barycentrics (b1, b2) of the triangle with vertices
/// `v` and corners p0, p1, p2, all in one space (an instance's: its object
/// space, whose tangent the caller moves into the world).
inline SurfacePoint surface_point(SurfaceScene ss, uint4 v, float b1, float b2, float3 p0, float3 p1, float3 p2,
                                  float footprint) {
  SurfacePoint sp;
  float b0 = 1.0f - b1 - b2;
  sp.color = (float4)(1.0f);
#if WT_HAS_VERTEX_COLORS
  sp.color = b0 * ss.color[v.x] + b1 * ss.color[v.y] + b2 * ss.color[v.z];
#endif
  sp.uv = (float4)(0.0f);
  sp.uv_scale = (float2)(0.0f);
  sp.tangent = (float3)(0.0f);
  sp.sign = 1.0f;
  sp.footprint = footprint;
#if WT_HAS_TEXTURES
  float4 t0 = ss.uv[v.x], t1 = ss.uv[v.y], t2 = ss.uv[v.z];
  sp.uv = b0 * t0 + b1 * t1 + b2 * t2;
  float world_area = length(cross(p1 - p0, p2 - p0));
  float4 e1 = t1 - t0, e2 = t2 - t0;
  float2 uv_area = (float2)(fabs(e1.x * e2.y - e1.y * e2.x), fabs(e1.z * e2.w - e1.w * e2.z));
  if (world_area > 0.0f && isfinite(world_area)) sp.uv_scale = sqrt(uv_area / world_area);
#endif
#if WT_HAS_TEXTURES || WT_HAS_ANISOTROPY
  // the tangent: normal maps and the anisotropy direction
  float4 g0 = ss.tangent[v.x], g1 = ss.tangent[v.y], g2 = ss.tangent[v.z];
  float3 t = b0 * g0.xyz + b1 * g1.xyz + b2 * g2.xyz;
  float len = length(t);
  if (len > 0.0f && isfinite(len)) {
    sp.tangent = t / len;
    sp.sign = g0.w < 0.0f ? -1.0f : 1.0f;
  }
#endif
  return sp;
}

#if WT_HAS_TEXTURES
/// Slot `slot` of material `material` at the point.
inline float4 material_texture(SurfaceScene ss, uint material, uint slot, SurfacePoint sp) {
  WtTextureRef r = ss.refs[material * WT_TEXTURE_SLOTS + slot];
  float2 st = r.texcoord == 1u ? sp.uv.zw : sp.uv.xy;
  float2 uv = (float2)(r.transform_u.x * st.x + r.transform_u.y * st.y + r.transform_u.z,
                       r.transform_v.x * st.x + r.transform_v.y * st.y + r.transform_v.z);
  // the transform scales the footprint by the square root of its area change
  float stretch = sqrt(fabs(r.transform_u.x * r.transform_v.y - r.transform_u.y * r.transform_v.x));
  float per_world = (r.texcoord == 1u ? sp.uv_scale.y : sp.uv_scale.x) * stretch;
  float lod = texture_lod(ss.textures, ss.levels, r.texture, sp.footprint * per_world);
  return texture_sample(ss.textures, ss.levels, ss.texels, r.texture, uv, lod);
}
#endif

#if WT_HAS_TEXTURES
/// Unit normal n bent by the tangent-space normal map in `slot` (its xy
/// scaled by the slot's scale); n itself where the point has no tangent.
inline float3 normal_mapped(SurfaceScene ss, uint index, uint slot, SurfacePoint sp, float3 n) {
  if (!(dot(sp.tangent, sp.tangent) > 0.0f)) return n;
  float4 t = material_texture(ss, index, slot, sp);
  float scale = ss.refs[index * WT_TEXTURE_SLOTS + slot].scale;
  float3 mapped = (float3)((2.0f * t.x - 1.0f) * scale, (2.0f * t.y - 1.0f) * scale, 2.0f * t.z - 1.0f);
  float3 tangent = sp.tangent - n * dot(n, sp.tangent);
  float tl = length(tangent);
  if (!(tl > 0.0f)) return n;
  tangent /= tl;
  float3 bitangent = sp.sign * cross(n, tangent);
  float3 bent = mapped.x * tangent + mapped.y * bitangent + mapped.z * n;
  float bl = length(bent);
  return bl > 0.0f && isfinite(bl) ? bent / bl : n;
}
#endif

/// Material `index` (`m`) at the point: base colour and alpha times COLOR_0
/// and the base colour texture, roughness and metallic times their texture's
/// green and blue, emission and transmission times theirs; `ns` (the
/// interpolated normal, unit) bent by the normal map where there is one.
inline WtMaterial material_at(SurfaceScene ss, uint index, WtMaterial m, SurfacePoint sp, float3* ns) {
  m.base_color.x *= sp.color.x, m.base_color.y *= sp.color.y, m.base_color.z *= sp.color.z;
  m.alpha *= sp.color.w;
#if WT_HAS_TEXTURES
  uint mask = m.texture_mask;
  if (mask == 0u) return m;
  if (mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_BASE_COLOR, sp);
    m.base_color.x *= t.x, m.base_color.y *= t.y, m.base_color.z *= t.z;
    m.alpha *= t.w;
  }
  if (mask & (1u << WT_TEXTURE_SLOT_METALLIC_ROUGHNESS)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_METALLIC_ROUGHNESS, sp);
    m.roughness *= t.y;
    m.base_color.w *= t.z;
  }
  if (mask & (1u << WT_TEXTURE_SLOT_EMISSIVE)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_EMISSIVE, sp);
    m.emission.x *= t.x, m.emission.y *= t.y, m.emission.z *= t.z;
  }
  if (mask & (1u << WT_TEXTURE_SLOT_TRANSMISSION)) {
    m.transmission *= material_texture(ss, index, WT_TEXTURE_SLOT_TRANSMISSION, sp).x;
  }
  // the layers' textures (their factors are zero where a layer is absent: the loader reads no texture there)
  if (mask & (1u << WT_TEXTURE_SLOT_SPECULAR)) m.specular.w *= material_texture(ss, index, WT_TEXTURE_SLOT_SPECULAR, sp).w;
  if (mask & (1u << WT_TEXTURE_SLOT_SPECULAR_COLOR)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_SPECULAR_COLOR, sp);
    m.specular.x *= t.x, m.specular.y *= t.y, m.specular.z *= t.z;
  }
  if (mask & (1u << WT_TEXTURE_SLOT_CLEARCOAT)) m.clearcoat *= material_texture(ss, index, WT_TEXTURE_SLOT_CLEARCOAT, sp).x;
  if (mask & (1u << WT_TEXTURE_SLOT_CLEARCOAT_ROUGHNESS))
    m.clearcoat_roughness *= material_texture(ss, index, WT_TEXTURE_SLOT_CLEARCOAT_ROUGHNESS, sp).y;
  if (mask & (1u << WT_TEXTURE_SLOT_SHEEN_COLOR)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_SHEEN_COLOR, sp);
    m.sheen.x *= t.x, m.sheen.y *= t.y, m.sheen.z *= t.z;
  }
  if (mask & (1u << WT_TEXTURE_SLOT_SHEEN_ROUGHNESS)) m.sheen.w *= material_texture(ss, index, WT_TEXTURE_SLOT_SHEEN_ROUGHNESS, sp).w;
#if WT_HAS_IRIDESCENCE
  // KHR_materials_iridescence: factor times r; thickness mix(minimum, maximum, g) into w
  if (mask & (1u << WT_TEXTURE_SLOT_IRIDESCENCE)) m.iridescence.x *= material_texture(ss, index, WT_TEXTURE_SLOT_IRIDESCENCE, sp).x;
  if (mask & (1u << WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS)) {
    float g = material_texture(ss, index, WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS, sp).y;
    m.iridescence.w = m.iridescence.z + (m.iridescence.w - m.iridescence.z) * g;
  }
#endif
  if (mask & (1u << WT_TEXTURE_SLOT_NORMAL)) *ns = normal_mapped(ss, index, WT_TEXTURE_SLOT_NORMAL, sp, *ns);
#endif
  return m;
}

#if WT_HAS_TEXTURES && WT_HAS_CLEARCOAT
/// KHR_materials_clearcoat's clearcoatNormalTexture: the coat's normal,
/// world, from the interpolated normal n (the tangent space the base's normal
/// map bends too); zero where the material has none (the coat then follows
/// the shading normal).
inline float3 clearcoat_normal(SurfaceScene ss, uint index, uint mask, SurfacePoint sp, float3 n) {
  if (!(mask & (1u << WT_TEXTURE_SLOT_CLEARCOAT_NORMAL))) return (float3)(0.0f);
  return normal_mapped(ss, index, WT_TEXTURE_SLOT_CLEARCOAT_NORMAL, sp, n);
}
#endif

#if WT_HAS_ANISOTROPY
/// KHR_materials_anisotropy at the point: m's strength times the anisotropy
/// texture's blue, and the returned direction in world space (not unit, not
/// yet in the shading normal's plane): the texture's rg as a direction in
/// [-1,1]^2 of tangent-bitangent space, else the tangent (1, 0), rotated by
/// anisotropy_rotation counter-clockwise; the bitangent sign * cross(n,
/// tangent) with n the interpolated normal. Zero where the point has no
/// tangent (shade then keeps its arbitrary frame).
inline float3 anisotropy_direction(SurfaceScene ss, uint index, WtMaterial* m, SurfacePoint sp, float3 n) {
  if (!(m->anisotropy > 0.0f)) return (float3)(0.0f);
  float2 d = (float2)(1.0f, 0.0f);
#if WT_HAS_TEXTURES
  if (m->texture_mask & (1u << WT_TEXTURE_SLOT_ANISOTROPY)) {
    float4 t = material_texture(ss, index, WT_TEXTURE_SLOT_ANISOTROPY, sp);
    d = (float2)(2.0f * t.x - 1.0f, 2.0f * t.y - 1.0f);
    m->anisotropy *= t.z;
  }
#endif
  if (!(dot(sp.tangent, sp.tangent) > 0.0f)) return (float3)(0.0f);
  float c = cos(m->anisotropy_rotation), s = sin(m->anisotropy_rotation);
  float2 r = (float2)(c * d.x - s * d.y, s * d.x + c * d.y);
  return r.x * sp.tangent + r.y * (sp.sign * cross(n, sp.tangent));
}

/// The local frame's x axis along the anisotropy direction `dir` (from
/// anisotropy_direction) projected into the plane of the shading normal
/// `ns`; *t and *b unchanged where it has no length there.
inline void anisotropy_frame(float3 dir, float3 ns, float3* t, float3* b) {
  float3 x = dir - ns * dot(ns, dir);
  float len = length(x);
  if (!(len > 1e-6f) || !isfinite(len)) return;
  *t = x / len;
  *b = cross(ns, *t);
}
#endif

/// A normal map can tilt the shading normal `ns` so far that the mirror
/// direction of wo falls below the surface (ng, on wo's side), where a
/// smooth material's reflection is lost and the bump's rim turns black:
/// tilt it back towards ng, by bisection, until that direction clears the
/// surface (the fix Cycles makes for the same artefact).
inline float3 shading_normal_reflecting(float3 ns, float3 ng, float3 wo) {
  float clearance = fmin(0.01f, 0.5f * dot(wo, ng));
  if (dot(2.0f * dot(wo, ns) * ns - wo, ng) >= clearance) return ns;
  float lo = 0.0f, hi = 1.0f;
  for (int i = 0; i < 12; ++i) {
    float t = 0.5f * (lo + hi);
    float3 n = normalize(mix(ns, ng, t));
    if (dot(2.0f * dot(wo, n) * n - wo, ng) >= clearance) hi = t;
    else lo = t;
  }
  return normalize(mix(ns, ng, hi));
}

#endif  // WT_MATERIALS_TEXTURED_CL
