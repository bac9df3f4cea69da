// Every compile-time switch the kernels read, declared once. Each comes from
// the host (kernelDefines in host/device/program.cpp, from the scene's
// feature set in host/render/feature_set.h); a build without one fails here,
// naming it, so no switch can silently take a default, and one out of its
// type's range (a boolean not 0 or 1, a packet width not 8 or 16) fails too.
// Kernels test them with #if, so code for an absent feature is not compiled.
#ifndef WT_SWITCHES_H
#define WT_SWITCHES_H

// A boolean switch: defined, and 0 or 1.
#define WT_SWITCH_IS_BOOL(x) ((x) == 0 || (x) == 1)

#ifndef WT_INTEGRATOR_MINIMAL
#error "WT_INTEGRATOR_MINIMAL not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_INTEGRATOR_MINIMAL)
#error "WT_INTEGRATOR_MINIMAL must be 0 or 1"
#endif
#ifndef WT_BVH_STACK_SIZE
#error "WT_BVH_STACK_SIZE not set (kernelDefines)"
#elif WT_BVH_STACK_SIZE < 32 || WT_BVH_STACK_SIZE % 32 != 0
#error "WT_BVH_STACK_SIZE must be a positive multiple of 32"
#endif
#ifndef WT_PACKET_WIDTH
#error "WT_PACKET_WIDTH not set (kernelDefines)"
#elif WT_PACKET_WIDTH != 8 && WT_PACKET_WIDTH != 16
#error "WT_PACKET_WIDTH must be 8 or 16"
#endif
#ifndef WT_STREAM_PREFETCH
#error "WT_STREAM_PREFETCH not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_STREAM_PREFETCH)
#error "WT_STREAM_PREFETCH must be 0 or 1"
#endif
#ifndef WT_HAS_PBR
#error "WT_HAS_PBR not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_PBR)
#error "WT_HAS_PBR must be 0 or 1"
#endif
#ifndef WT_HAS_TRANSMISSION
#error "WT_HAS_TRANSMISSION not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_TRANSMISSION)
#error "WT_HAS_TRANSMISSION must be 0 or 1"
#endif
#ifndef WT_HAS_SPECULAR
#error "WT_HAS_SPECULAR not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_SPECULAR)
#error "WT_HAS_SPECULAR must be 0 or 1"
#endif
#ifndef WT_HAS_CLEARCOAT
#error "WT_HAS_CLEARCOAT not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_CLEARCOAT)
#error "WT_HAS_CLEARCOAT must be 0 or 1"
#endif
#ifndef WT_HAS_SHEEN
#error "WT_HAS_SHEEN not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_SHEEN)
#error "WT_HAS_SHEEN must be 0 or 1"
#endif
#ifndef WT_HAS_ANISOTROPY
#error "WT_HAS_ANISOTROPY not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_ANISOTROPY)
#error "WT_HAS_ANISOTROPY must be 0 or 1"
#endif
#ifndef WT_HAS_IRIDESCENCE
#error "WT_HAS_IRIDESCENCE not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_IRIDESCENCE)
#error "WT_HAS_IRIDESCENCE must be 0 or 1"
#endif
// A material that shadow rays cross (WtMaterial::shadow_pass: a smooth thin
// wall): connect weighs them through it, shade continues a path straight
// through it from its last vertex (kernels/connect.cl). Needs transmission.
#ifndef WT_HAS_THIN_SHADOWS
#error "WT_HAS_THIN_SHADOWS not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_THIN_SHADOWS)
#error "WT_HAS_THIN_SHADOWS must be 0 or 1"
#elif WT_HAS_THIN_SHADOWS && !WT_HAS_TRANSMISSION
#error "WT_HAS_THIN_SHADOWS needs WT_HAS_TRANSMISSION"
#endif
// Two emissive triangles make a rectangle light (WT_LIGHT_QUAD): NEE
// samples it as one, by solid angle, and shade takes WT_QUAD_SHADE_PARAMS.
#ifndef WT_HAS_QUAD_LIGHTS
#error "WT_HAS_QUAD_LIGHTS not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_QUAD_LIGHTS)
#error "WT_HAS_QUAD_LIGHTS must be 0 or 1"
#endif
#ifndef WT_HAS_LIGHT_TREE
#error "WT_HAS_LIGHT_TREE not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_LIGHT_TREE)
#error "WT_HAS_LIGHT_TREE must be 0 or 1"
#endif
#ifndef WT_HAS_OTHER_LIGHTS
#error "WT_HAS_OTHER_LIGHTS not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_OTHER_LIGHTS)
#error "WT_HAS_OTHER_LIGHTS must be 0 or 1"
#endif
#ifndef WT_HAS_TEXTURES
#error "WT_HAS_TEXTURES not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_TEXTURES)
#error "WT_HAS_TEXTURES must be 0 or 1"
#endif
#ifndef WT_HAS_VERTEX_COLORS
#error "WT_HAS_VERTEX_COLORS not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_VERTEX_COLORS)
#error "WT_HAS_VERTEX_COLORS must be 0 or 1"
#endif
#ifndef WT_HAS_ALPHA
#error "WT_HAS_ALPHA not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_HAS_ALPHA)
#error "WT_HAS_ALPHA must be 0 or 1"
#endif
// The geometry types' switches (WT_HAS_SPHERES, ...), one per row of
// kernels/geometry/types.def. A macro cannot produce #error, so a static
// assertion names the switch: WT_SWITCH_SET_AND_BOOL(x) is 1 only where x
// expands to 0 or 1 (pasted onto WT_SWITCH_PROBE_, only those two make a
// second argument); undefined, it stays a name and gives 0.
#define WT_SWITCH_SECOND_(a, b, ...) b
#define WT_SWITCH_SECOND(...) WT_SWITCH_SECOND_(__VA_ARGS__)
#define WT_SWITCH_PROBE_0 ~, 1
#define WT_SWITCH_PROBE_1 ~, 1
#define WT_SWITCH_VALUE_IS_BOOL(v) WT_SWITCH_SECOND(WT_SWITCH_PROBE_##v, 0, ~)
#define WT_SWITCH_SET_AND_BOOL(x) WT_SWITCH_VALUE_IS_BOOL(x)
#define WT_GEOMETRY_CHECK_SWITCH(TAG, ID, NAME, FEATURE, SWITCH, GATHER, AREA) \
  _Static_assert(WT_SWITCH_SET_AND_BOOL(WT_HAS_##SWITCH), "WT_HAS_" #SWITCH " not set (kernelDefines), or not 0 or 1");
#include "geometry/types.def"
WT_GEOMETRY_TYPES(WT_GEOMETRY_CHECK_SWITCH)

// Arbitrary output variables (kernels/aov.cl): shade and accumulate record
// them only when a render asks (RenderSettings::aovs); off, no code exists.
#ifndef WT_AOV
#error "WT_AOV not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_AOV)
#error "WT_AOV must be 0 or 1"
#endif
// The bvh-cost debug view: closest-hit traversal counts the nodes it visits
// (Hit::cost), extend records a camera ray's count; off, no code exists.
#ifndef WT_BVH_COST
#error "WT_BVH_COST not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_BVH_COST)
#error "WT_BVH_COST must be 0 or 1"
#elif WT_BVH_COST && !WT_AOV
#error "WT_BVH_COST needs WT_AOV (the count goes to aov_sample)"
#endif
// Shade over 8 or 16 (WT_SHADE_LANES_WIDTH) paths per work-item on vector
// lanes (kernels/shade_lanes.cl): only for triangles, Lambertian or
// metallic-roughness without extensions other than transmission (whose
// paths shade.cl's code shades one lane at a time), textures, vertex
// colours, holes or AOVs, under the path integrator.
#ifndef WT_SHADE_LANES
#error "WT_SHADE_LANES not set (kernelDefines)"
#elif !WT_SWITCH_IS_BOOL(WT_SHADE_LANES)
#error "WT_SHADE_LANES must be 0 or 1"
#elif WT_SHADE_LANES && (WT_HAS_SPECULAR || WT_HAS_CLEARCOAT || WT_HAS_SHEEN || \
                         WT_HAS_ANISOTROPY || WT_HAS_IRIDESCENCE || WT_HAS_THIN_SHADOWS || WT_HAS_TEXTURES || WT_HAS_VERTEX_COLORS || WT_HAS_ALPHA || WT_AOV || \
                         WT_INTEGRATOR_MINIMAL WT_GEOMETRY_TYPES(WT_GEOMETRY_OR_SWITCH))
#error "WT_SHADE_LANES needs untextured Lambertian or plain metallic-roughness triangles under the path integrator"
#elif WT_SHADE_LANES && WT_SHADE_LANES_WIDTH != 8 && WT_SHADE_LANES_WIDTH != 16
#error "WT_SHADE_LANES_WIDTH must be 8 or 16 (kernelDefines)"
#endif

// Not features (the image is the same either way), so they may be left out
// and take these values: workarounds for the kernel checker, set by
// buildProgram under Oclgrind only, and the packet leaf test's lane limit,
// which kernel A/B runs may override (kernels/bvh_packet.cl says why 2 for 8).
#ifndef WT_AVOID_BITREVERSE
#define WT_AVOID_BITREVERSE 0
#endif
#ifndef WT_FOLD_THROUGH_MEMORY
#define WT_FOLD_THROUGH_MEMORY 0
#endif
#ifndef WT_NO_PREFETCH
#define WT_NO_PREFETCH 0
#endif
#ifndef WT_NO_CTZ
#define WT_NO_CTZ 0
#endif
#ifndef WT_NO_SRET_INLINE
#define WT_NO_SRET_INLINE 0
#endif
// A struct-returning function to inline: LLVM marks its result with
// llvm.experimental.noalias.scope.decl where it stays in memory (always
// unoptimised), which Oclgrind lacks (tests/oclgrind/noalias_scope.cl).
#if WT_NO_SRET_INLINE
#define WT_INLINE_STRUCT __attribute__((noinline)) inline
#else
#define WT_INLINE_STRUCT __attribute__((always_inline)) inline
#endif
#ifndef WT_PACKET_LEAF_LANES
#define WT_PACKET_LEAF_LANES (WT_PACKET_WIDTH == 8 ? 2 : 0)
#endif

#endif  // WT_SWITCHES_H
