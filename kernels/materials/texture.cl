// Texture sampling (kernels/shared/textures.h for the layout). glTF's UV
// convention: (0, 0) is the top-left corner of the image (the first texel of
// the first row), u runs right, v down, and texel (i, j) of a w x h level has
// its centre at ((i + 0.5) / w, (j + 0.5) / h). Filtering is in linear light:
// sRGB texels are decoded before they are weighted.
#ifndef WT_MATERIALS_TEXTURE_CL
#define WT_MATERIALS_TEXTURE_CL

#include "common.h"
#include "shared/textures.h"

/// Linear value of each 8-bit sRGB code: the exact transfer function of
/// i / 255 in double precision, rounded to float (TextureSample.SrgbDecode*
/// checks every entry against host/texture/texture.cpp's srgbToLinear).
__constant float texture_srgb_table[256] = {
    0.0f, 0.000303527f, 0.000607054f, 0.000910581f, 0.001214108f, 0.001517635f, 0.001821162f, 0.0021246888f,
    0.002428216f, 0.0027317428f, 0.00303527f, 0.0033465358f, 0.0036765074f, 0.004024717f, 0.004391442f, 0.0047769533f,
    0.0051815165f, 0.0056053917f, 0.006048833f, 0.0065120906f, 0.00699541f, 0.007499032f, 0.008023193f, 0.008568126f,
    0.009134059f, 0.009721218f, 0.010329823f, 0.010960094f, 0.011612245f, 0.012286488f, 0.0129830325f, 0.013702083f,
    0.014443844f, 0.015208514f, 0.015996294f, 0.016807375f, 0.017641954f, 0.01850022f, 0.019382361f, 0.020288562f,
    0.02121901f, 0.022173885f, 0.023153367f, 0.024157632f, 0.02518686f, 0.026241222f, 0.027320892f, 0.02842604f,
    0.029556835f, 0.030713445f, 0.031896032f, 0.033104766f, 0.034339808f, 0.035601314f, 0.03688945f, 0.038204372f,
    0.039546236f, 0.0409152f, 0.04231141f, 0.04373503f, 0.045186203f, 0.046665087f, 0.048171826f, 0.049706567f,
    0.051269457f, 0.052860647f, 0.054480277f, 0.05612849f, 0.05780543f, 0.059511237f, 0.061246052f, 0.063010015f,
    0.064803265f, 0.06662594f, 0.06847817f, 0.070360094f, 0.07227185f, 0.07421357f, 0.07618538f, 0.07818742f,
    0.08021982f, 0.08228271f, 0.08437621f, 0.08650046f, 0.08865558f, 0.09084171f, 0.093058966f, 0.09530747f,
    0.09758735f, 0.099898726f, 0.10224173f, 0.104616486f, 0.107023105f, 0.10946171f, 0.11193243f, 0.114435375f,
    0.116970666f, 0.11953843f, 0.122138776f, 0.12477182f, 0.12743768f, 0.13013647f, 0.13286832f, 0.13563333f,
    0.13843161f, 0.14126329f, 0.14412847f, 0.14702727f, 0.14995979f, 0.15292615f, 0.15592647f, 0.15896083f,
    0.16202937f, 0.1651322f, 0.1682694f, 0.17144111f, 0.1746474f, 0.17788842f, 0.18116425f, 0.18447499f,
    0.18782078f, 0.19120169f, 0.19461784f, 0.19806932f, 0.20155625f, 0.20507874f, 0.20863687f, 0.21223076f,
    0.2158605f, 0.2195262f, 0.22322796f, 0.22696587f, 0.23074006f, 0.23455058f, 0.23839757f, 0.24228112f,
    0.24620132f, 0.25015828f, 0.2541521f, 0.25818285f, 0.26225066f, 0.2663556f, 0.2704978f, 0.2746773f,
    0.27889428f, 0.28314874f, 0.28744084f, 0.29177064f, 0.29613826f, 0.30054379f, 0.3049873f, 0.30946892f,
    0.31398872f, 0.31854677f, 0.3231432f, 0.3277781f, 0.33245152f, 0.33716363f, 0.34191442f, 0.34670407f,
    0.3515326f, 0.35640013f, 0.3613068f, 0.3662526f, 0.3712377f, 0.37626213f, 0.38132602f, 0.38642943f,
    0.39157248f, 0.39675522f, 0.40197778f, 0.4072402f, 0.4125426f, 0.41788507f, 0.42326766f, 0.4286905f,
    0.43415365f, 0.43965718f, 0.4452012f, 0.4507858f, 0.45641103f, 0.462077f, 0.4677838f, 0.47353148f,
    0.47932017f, 0.48514995f, 0.49102086f, 0.49693298f, 0.5028865f, 0.50888133f, 0.5149177f, 0.52099556f,
    0.5271151f, 0.5332764f, 0.5394795f, 0.54572445f, 0.55201143f, 0.5583404f, 0.5647115f, 0.57112485f,
    0.57758045f, 0.58407843f, 0.59061885f, 0.59720176f, 0.60382736f, 0.61049557f, 0.6172066f, 0.6239604f,
    0.63075715f, 0.63759685f, 0.6444797f, 0.65140563f, 0.65837485f, 0.6653873f, 0.67244315f, 0.6795425f,
    0.6866853f, 0.69387174f, 0.7011019f, 0.70837575f, 0.7156935f, 0.7230551f, 0.73046076f, 0.7379104f,
    0.7454042f, 0.7529422f, 0.7605245f, 0.76815116f, 0.7758222f, 0.7835378f, 0.7912979f, 0.7991027f,
    0.80695224f, 0.8148466f, 0.82278574f, 0.8307699f, 0.838799f, 0.8468732f, 0.8549926f, 0.8631572f,
    0.8713671f, 0.8796224f, 0.8879231f, 0.8962694f, 0.9046612f, 0.91309863f, 0.92158186f, 0.9301109f,
    0.9386857f, 0.9473065f, 0.9559733f, 0.9646863f, 0.9734453f, 0.9822506f, 0.9911021f, 1.0f
};

/// The exact sRGB decoding of one 16-bit channel in [0, 1].
inline float texture_srgb_to_linear(float c) {
  return c <= 0.04045f ? c * (1.0f / 12.92f) : pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

/// Texel `index` of the level whose texels start at `offset`: linear RGBA.
inline float4 texture_texel(__global const uint* texels, uint offset, uint index, uint flags) {
  if (flags & WT_TEXTURE_16BIT) {
    uint rg = texels[offset + 2u * index], ba = texels[offset + 2u * index + 1u];
    float4 c = (float4)((float)(rg & 0xffffu), (float)(rg >> 16), (float)(ba & 0xffffu), (float)(ba >> 16)) *
               (1.0f / 65535.0f);
    if (flags & WT_TEXTURE_SRGB)
      c = (float4)(texture_srgb_to_linear(c.x), texture_srgb_to_linear(c.y), texture_srgb_to_linear(c.z), c.w);
    return c;
  }
  uint p = texels[offset + index];
  if (flags & WT_TEXTURE_SRGB)
    return (float4)(texture_srgb_table[p & 255u], texture_srgb_table[(p >> 8) & 255u],
                    texture_srgb_table[(p >> 16) & 255u], (float)(p >> 24) * (1.0f / 255.0f));
  return (float4)((float)(p & 255u), (float)((p >> 8) & 255u), (float)((p >> 16) & 255u), (float)(p >> 24)) *
         (1.0f / 255.0f);
}

/// u brought into one period of its wrap mode, [0, 1] (repeat, clamp) or
/// [0, 2] (mirror), before it is scaled to texels: a huge u then cannot
/// overflow or lose the texel grid. NaN and infinities become 0.
inline float texture_reduce(float u, uint mode) {
  u = isfinite(u) ? u : 0.0f;
  if (mode == WT_WRAP_CLAMP) return clamp(u, 0.0f, 1.0f);
  float period = mode == WT_WRAP_MIRROR ? 2.0f : 1.0f;
  return u - period * floor(u * (1.0f / period));  // exact: period is a power of two
}

/// Texel column (or row) i of a reduced coordinate, in [-1, 2n] for n
/// texels, wrapped into [0, n). The final clamp is all clamp-to-edge needs;
/// after repeat and mirror it changes nothing, and keeps any other mode in
/// the image.
inline uint texture_wrap_index(int i, int n, uint mode) {
  if (mode == WT_WRAP_REPEAT) {
    i = i < 0 ? i + n : (i >= n ? i - n : i);
  } else if (mode == WT_WRAP_MIRROR) {
    int period = 2 * n;
    i = i < 0 ? i + period : (i >= period ? i - period : i);
    i = i >= n ? period - 1 - i : i;
  }
  return (uint)clamp(i, 0, n - 1);
}

/// One level, nearest texel or bilinear.
inline float4 texture_level_sample(__global const WtTextureLevel* levels, __global const uint* texels, uint level,
                                   uint flags, float2 uv, bool bilinear) {
  WtTextureLevel l = levels[level];
  int w = (int)l.width, h = (int)l.height;
  uint wrap_s = WT_TEXTURE_WRAP_S(flags), wrap_t = WT_TEXTURE_WRAP_T(flags);
  float s = texture_reduce(uv.x, wrap_s) * (float)w, t = texture_reduce(uv.y, wrap_t) * (float)h;
  if (!bilinear) {
    uint x = texture_wrap_index((int)floor(s), w, wrap_s), y = texture_wrap_index((int)floor(t), h, wrap_t);
    return texture_texel(texels, l.offset, y * l.width + x, flags);
  }
  // the four texels whose centres surround (s, t)
  s -= 0.5f;
  t -= 0.5f;
  float s0 = floor(s), t0 = floor(t);
  float fs = s - s0, ft = t - t0;
  uint x0 = texture_wrap_index((int)s0, w, wrap_s), x1 = texture_wrap_index((int)s0 + 1, w, wrap_s);
  uint y0 = texture_wrap_index((int)t0, h, wrap_t), y1 = texture_wrap_index((int)t0 + 1, h, wrap_t);
  float4 a = texture_texel(texels, l.offset, y0 * l.width + x0, flags);
  float4 b = texture_texel(texels, l.offset, y0 * l.width + x1, flags);
  float4 c = texture_texel(texels, l.offset, y1 * l.width + x0, flags);
  float4 d = texture_texel(texels, l.offset, y1 * l.width + x1, flags);
  return mix(mix(a, b, fs), mix(c, d, fs), ft);
}

/// Linear RGBA of `texture` at `uv`, `lod` levels above the finest (from
/// texture_lod). lod <= 0 (or NaN) magnifies level 0 with the magnification
/// filter; lod > 0 minifies with the minification filter: level 0 alone
/// without mips, else the nearest level or two levels blended, lod clamped
/// to the last level. Finite for any uv and lod.
inline float4 texture_sample(__global const WtTexture* textures, __global const WtTextureLevel* levels,
                             __global const uint* texels, uint texture, float2 uv, float lod) {
  WtTexture tex = textures[texture];
  uint flags = tex.flags;
  if (!(lod > 0.0f))
    return texture_level_sample(levels, texels, tex.first_level, flags, uv, (flags & WT_TEXTURE_MAG_LINEAR) != 0u);
  bool bilinear = (flags & WT_TEXTURE_MIN_LINEAR) != 0u;
  uint mip = WT_TEXTURE_MIP(flags), last = tex.level_count - 1u;
  if (mip == WT_MIP_NONE || last == 0u) return texture_level_sample(levels, texels, tex.first_level, flags, uv, bilinear);
  lod = fmin(lod, (float)last);  // +inf too
  if (mip == WT_MIP_NEAREST)
    return texture_level_sample(levels, texels, tex.first_level + min((uint)(lod + 0.5f), last), flags, uv, bilinear);
  float below = floor(lod), f = lod - below;
  uint level = tex.first_level + (uint)below;
  float4 fine = texture_level_sample(levels, texels, level, flags, uv, bilinear);
  if (f == 0.0f) return fine;  // also lod == last: no level past it is read
  return mix(fine, texture_level_sample(levels, texels, level + 1u, flags, uv, bilinear), f);
}

/// The continuous level for an isotropic footprint `footprint_uv` wide (in
/// UV units) on `texture`: log2 of the footprint in level-0 texels of the
/// longer side. Negative where a texel covers more than the footprint
/// (texture_sample magnifies there); 0 for a footprint of 0 or NaN.
inline float texture_lod(__global const WtTexture* textures, __global const WtTextureLevel* levels, uint texture,
                         float footprint_uv) {
  WtTextureLevel l = levels[textures[texture].first_level];
  float texels = footprint_uv * (float)max(l.width, l.height);
  return texels > 0.0f ? log2(texels) : 0.0f;
}

#endif  // WT_MATERIALS_TEXTURE_CL
