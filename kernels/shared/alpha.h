// What the alpha test (kernels/materials/alpha.cl) reads of a material,
// shared by the host (SceneBuffers::alphaMaterials fills it) and the kernels.
#ifndef WT_SHARED_ALPHA_H
#define WT_SHARED_ALPHA_H

#include "shared/types.h"

/// A material's alpha mode as traversal needs it, 16 bytes, one per
/// material: read instead of the 80-byte WtMaterial, and without the base
/// colour texture where the host found that texture's alpha 1 everywhere (a
/// JPEG, an opaque PNG), whose sampling at every candidate hit would cost
/// the most of the test and change nothing.
typedef struct WtAlphaMaterial {
  wt_uint mode;     ///< WT_ALPHA_*
  float cutoff;     ///< WT_ALPHA_MASK: coverage below it is a hole
  float factor;     ///< the base colour alpha factor, in [0,1]
  wt_uint texture;  ///< 1: times the base colour texture's alpha (material_textures, WT_TEXTURE_SLOT_BASE_COLOR); 0: no texture, or an opaque one
} WtAlphaMaterial;

#endif  // WT_SHARED_ALPHA_H
