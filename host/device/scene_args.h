// The scene's buffers bound by name to the kernel-side parameter groups
// (WT_GEOMETRY_PARAMS, WT_SURFACE_PARAMS, WT_ALPHA_PARAMS) of a kernel
// declared for KernelArgs.
#pragma once

#include "device/kernel_args.h"
#include "device/scene_buffers.h"

#include <cstdint>

namespace wt {

template <class Decl>
void bindGeometry(KernelArgs<Decl>& k, const SceneBuffers& s) {
  k.set("geometry", s.geometry)
      .set("prim_nodes", s.primNodes)
      .set("prim_refs", s.primRefs)
      .set("prim_data", s.primData)
      .set("prim_info", s.primInfo);
}

template <class Decl>
void bindSurface(KernelArgs<Decl>& k, const SceneBuffers& s) {
  k.set("vertex_uv", s.vertexUv)
      .set("vertex_color", s.vertexColor)
      .set("vertex_tangent", s.vertexTangent)
      .set("material_textures", s.materialTextures)
      .set("textures", s.textures)
      .set("texture_levels", s.textureLevels)
      .set("texels", s.texels);
}

/// Only for kernels built with WT_HAS_ALPHA; `key` is set again per launch where it changes.
template <class Decl>
void bindAlpha(KernelArgs<Decl>& k, const SceneBuffers& s, std::uint32_t key = 0) {
  k.set("alpha_key", cl_uint(key))
      .set("alpha_bits", s.alphaBits)
      .set("alpha_tri_info", s.triangleInfo)
      .set("alpha_materials", s.alphaMaterials);
  bindSurface(k, s);
}

}  // namespace wt
