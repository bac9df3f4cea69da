// Textures as host and kernels share them (host/texture/texture.h packs
// them, kernels/materials/texture.cl samples them). Three arrays travel:
//   textures  WtTexture[]       one per glTF texture: an image and its sampler
//   levels    WtTextureLevel[]  every mip level of every image, each image's levels adjacent, finest first
//   texels    uint[]            every level's texels, row-major from the image's top row (the file's first)
// An 8-bit texel is one uint, R in the low byte: R | G << 8 | B << 16 | A << 24.
// A 16-bit texel (16-bit PNG) is two uints: R | G << 16, then B | A << 16.
#ifndef WT_SHARED_TEXTURES_H
#define WT_SHARED_TEXTURES_H

#include "shared/types.h"

// WtTexture.flags, bit by bit:
//   bit 0     WT_TEXTURE_SRGB        RGB are sRGB-encoded: decoded to linear per texel before filtering; alpha never
//   bit 1     WT_TEXTURE_16BIT       two uints per texel instead of one
//   bits 2-3  wrap S (u), WT_WRAP_*  read with WT_TEXTURE_WRAP_S(flags)
//   bits 4-5  wrap T (v), WT_WRAP_*  read with WT_TEXTURE_WRAP_T(flags)
//   bit 6     WT_TEXTURE_MAG_LINEAR  magnification (lod <= 0): bilinear, else nearest
//   bit 7     WT_TEXTURE_MIN_LINEAR  minification (lod > 0): bilinear within a level, else nearest
//   bits 8-9  between levels, WT_MIP_*: none (level 0 only), nearest level, or a blend of two (trilinear)
// glTF's sampler codes map as: wrap 10497 REPEAT, 33071 CLAMP_TO_EDGE,
// 33648 MIRRORED_REPEAT; magFilter 9728 NEAREST, 9729 LINEAR; minFilter
// 9728 NEAREST and 9729 LINEAR (no mips), 9984 NEAREST_MIPMAP_NEAREST,
// 9985 LINEAR_MIPMAP_NEAREST, 9986 NEAREST_MIPMAP_LINEAR, 9987
// LINEAR_MIPMAP_LINEAR. An undefined wrap is REPEAT, an undefined filter
// LINEAR (magnification) or LINEAR_MIPMAP_LINEAR (minification).
#define WT_TEXTURE_SRGB (1u << 0)
#define WT_TEXTURE_16BIT (1u << 1)
#define WT_TEXTURE_WRAP_S_SHIFT 2
#define WT_TEXTURE_WRAP_T_SHIFT 4
#define WT_TEXTURE_MAG_LINEAR (1u << 6)
#define WT_TEXTURE_MIN_LINEAR (1u << 7)
#define WT_TEXTURE_MIP_SHIFT 8

#define WT_WRAP_REPEAT 0u  ///< glTF 10497
#define WT_WRAP_CLAMP 1u   ///< glTF 33071, CLAMP_TO_EDGE
#define WT_WRAP_MIRROR 2u  ///< glTF 33648, MIRRORED_REPEAT
#define WT_TEXTURE_WRAP_S(flags) (((flags) >> WT_TEXTURE_WRAP_S_SHIFT) & 3u)
#define WT_TEXTURE_WRAP_T(flags) (((flags) >> WT_TEXTURE_WRAP_T_SHIFT) & 3u)

#define WT_MIP_NONE 0u     ///< minFilter NEAREST or LINEAR: level 0 at every lod
#define WT_MIP_NEAREST 1u  ///< *_MIPMAP_NEAREST: the level nearest to lod
#define WT_MIP_LINEAR 2u   ///< *_MIPMAP_LINEAR: levels floor(lod) and floor(lod) + 1 blended
#define WT_TEXTURE_MIP(flags) (((flags) >> WT_TEXTURE_MIP_SHIFT) & 3u)

/// One glTF texture: an image (its levels) and a sampler, 16 bytes.
typedef struct WtTexture {
  wt_uint first_level;  ///< index of the image's level 0 in the levels array
  wt_uint level_count;  ///< >= 1; the last level is 1 x 1
  wt_uint flags;        ///< WT_TEXTURE_* above
  wt_uint pad;
} WtTexture;

/// One mip level of one image, 16 bytes.
typedef struct WtTextureLevel {
  wt_uint offset;         ///< first texel, in uints (not texels), into the texel array
  wt_uint width, height;  ///< texels, >= 1
  wt_uint pad;
} WtTextureLevel;

#endif  // WT_SHARED_TEXTURES_H
