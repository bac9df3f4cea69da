// glTF alpha modes, decided inside traversal: a candidate hit on a triangle
// whose material is MASK and whose coverage there is below alphaCutoff is a
// hole, and on a BLEND material it is one with probability 1 - coverage
// (stochastic transparency, Enderton et al. 2010); traversal then goes on as
// if the triangle were not there. Closest-hit rays (extend, the trace_*
// kernels) and shadow rays (connect, packets and streams) run the same test,
// so a cut-out leaf casts a cut-out shadow and a shadow ray through n blended
// surfaces passes with the product of their transparencies on average.
//
// Coverage is the material's alpha factor times COLOR_0's alpha times the
// base colour texture's alpha, read at the finest level (no footprint:
// traversal knows none). Only triangles carry it; other geometry types are
// opaque.
//
// The cost: without WT_HAS_ALPHA (no triangle's material can have a hole,
// SceneBuffers::hasAlpha) none of this is compiled and the traversal code is
// what it was. With it, a candidate hit reads one bit per triangle
// (alpha_bits, set where the material can have a hole there), and only a
// flagged triangle's hit reads tri_info, the material's 16-byte alpha row
// (shared/alpha.h) and, where its alpha varies, the texture.
#ifndef WT_MATERIALS_ALPHA_CL
#define WT_MATERIALS_ALPHA_CL

#include "common.h"
#include "shared/alpha.h"
// outside the switch: the host expands each include once, where it first
// appears (expandKernelSource), whatever the preprocessor later keeps
#include "materials/textured.cl"

#if WT_HAS_ALPHA

/// The kernel parameters the alpha test reads, after WT_GEOMETRY_PARAMS
/// (host: bindAlpha, device/scene_args.h, by name): the launch's key for stochastic
/// transparency (rng_alpha_key), the flag bits, tri_info, the materials and
/// the surface attributes. They exist only where WT_HAS_ALPHA is set, so
/// kernels without it keep their arguments.
#define WT_ALPHA_PARAMS                                                                                        \
  , uint alpha_key, __global const uint *alpha_bits, __global const uint4 *alpha_tri_info,                     \
      __global const WtAlphaMaterial *alpha_materials, WT_SURFACE_PARAMS

/// What the alpha test reads, and the stream of the ray it tests.
typedef struct AlphaScene {
  __global const uint* bits;            ///< bit t of word t / 32: leaf-order triangle t may have a hole
  __global const uint4* tri_info;       ///< per leaf-order triangle: vertices and material
  __global const WtAlphaMaterial* materials;  ///< per material (SceneBuffers::alphaMaterials)
  SurfaceScene surface;
  uint key;  ///< the launch's key (rng_alpha_key)
  uint ray;  ///< the ray's stream (rng_alpha_ray of the key and the ray's index): BLEND's numbers
} AlphaScene;

/// Set BvhScene `scene`'s alpha test from the kernel's WT_ALPHA_PARAMS, for
/// ray (or path) `ray_index` of the launch.
#define WT_ALPHA_BIND(scene, ray_index)                                                                  \
  do {                                                                                                   \
    SurfaceScene alpha_surface_ = WT_SURFACE_SCENE;                                                      \
    (scene).alpha.bits = alpha_bits;                                                                     \
    (scene).alpha.tri_info = alpha_tri_info;                                                             \
    (scene).alpha.materials = alpha_materials;                                                           \
    (scene).alpha.surface = alpha_surface_;                                                              \
    (scene).alpha.key = alpha_key;                                                                       \
    (scene).alpha.ray = rng_alpha_ray(alpha_key, (ray_index));                                           \
  } while (0)
/// The same scene for another ray of the launch.
#define WT_ALPHA_RAY(scene, ray_index) ((scene).alpha.ray = rng_alpha_ray((scene).alpha.key, (ray_index)))

/// Whether leaf-order triangle `prim` may have a hole (its bit).
inline bool alpha_flagged(AlphaScene a, uint prim) { return ((a.bits[prim >> 5] >> (prim & 31u)) & 1u) != 0u; }

/// The bits of block `block`'s four triangles (WT_TRIANGLE_BLOCK), lane l at bit l.
inline uint alpha_block_bits(AlphaScene a, uint block) { return (a.bits[block >> 3] >> ((block & 7u) * 4u)) & 15u; }

/// What a flagged triangle's test needs whatever the point: its vertices
/// (w: its material) and its material's alpha row.
typedef struct AlphaTriangle {
  uint4 v;
  WtAlphaMaterial m;
} AlphaTriangle;

// Inlined, its result stays in memory in optimised builds (extend's alpha
// test), and LLVM marks it with llvm.experimental.noalias.scope.decl, which
// Oclgrind does not define (tests/oclgrind/noalias_scope.cl): under Oclgrind it is called.
#if WT_NO_SRET_INLINE
__attribute__((noinline))
#endif
inline AlphaTriangle alpha_triangle(AlphaScene a, uint prim) {
  AlphaTriangle tri;
  tri.v = a.tri_info[prim];
  tri.m = a.materials[tri.v.w];
  return tri;
}

/// Whether the triangle's coverage is the same everywhere (the factor): no
/// texture to read and no COLOR_0 compiled in.
inline bool alpha_uniform(AlphaTriangle tri) { return !WT_HAS_VERTEX_COLORS && (!WT_HAS_TEXTURES || !tri.m.texture); }

/// The triangle's coverage at barycentrics (b1, b2): the alpha factor,
/// COLOR_0's alpha and the base colour texture's alpha at the finest level.
inline float alpha_coverage(AlphaScene a, AlphaTriangle tri, float b1, float b2) {
  float alpha = tri.m.factor;
#if WT_HAS_VERTEX_COLORS || WT_HAS_TEXTURES
  float b0 = 1.0f - b1 - b2;
  uint4 v = tri.v;
#endif
#if WT_HAS_VERTEX_COLORS
  alpha *= b0 * a.surface.color[v.x].w + b1 * a.surface.color[v.y].w + b2 * a.surface.color[v.z].w;
#endif
#if WT_HAS_TEXTURES
  if (tri.m.texture) {
    SurfacePoint sp;
    sp.uv = b0 * a.surface.uv[v.x] + b1 * a.surface.uv[v.y] + b2 * a.surface.uv[v.z];
    sp.uv_scale = (float2)(0.0f);
    sp.color = (float4)(1.0f);
    sp.tangent = (float3)(0.0f);
    sp.sign = 1.0f;
    sp.footprint = 0.0f;  // the finest level
    alpha *= material_texture(a.surface, v.w, WT_TEXTURE_SLOT_BASE_COLOR, sp).w;
  }
#endif
  return alpha;
}

/// Whether coverage `coverage` of triangle `prim` is there for the ray whose
/// stream is a.ray: MASK where it reaches the cutoff, BLEND with probability
/// equal to it (a number of the ray's stream and the triangle, so that
/// every traversal of the ray decides the same), OPAQUE always.
inline bool alpha_covered(AlphaScene a, AlphaTriangle tri, uint prim, float coverage) {
  if (tri.m.mode == WT_ALPHA_MASK) return coverage >= tri.m.cutoff;
  if (tri.m.mode == WT_ALPHA_BLEND) return rng_alpha_uniform(a.ray, prim) < coverage;
  return true;
}

/// Whether a hit at barycentrics (b1, b2) of flagged triangle `prim` is kept.
inline bool alpha_keeps(AlphaScene a, uint prim, float b1, float b2) {
  AlphaTriangle tri = alpha_triangle(a, prim);
  return alpha_covered(a, tri, prim, alpha_coverage(a, tri, b1, b2));
}

#else
#define WT_ALPHA_PARAMS
#define WT_ALPHA_BIND(scene, ray_index) \
  do {                                  \
  } while (0)
#define WT_ALPHA_RAY(scene, ray_index) ((void)0)
#endif  // WT_HAS_ALPHA

#endif  // WT_MATERIALS_ALPHA_CL
