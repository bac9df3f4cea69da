// Textures for scenes made in the tests: a checkerboard of alpha, and a
// material slot pointed at a texture (TEXCOORD_0, no transform).
#pragma once

#include "scene/scene.h"

#include <cstdint>

namespace wt::test {

constexpr int kNearest = 9728;  // glTF's NEAREST filter

/// An n x n white texture (sRGB) whose alpha is a checkerboard, opaque where
/// x + y is even, read nearest.
inline std::uint32_t addCheckerTexture(Scene& scene, std::uint32_t n) {
  DecodedImage image;
  image.width = image.height = n;
  image.name = "checker";
  for (std::uint32_t y = 0; y < n; ++y)
    for (std::uint32_t x = 0; x < n; ++x)
      for (std::uint8_t c : {255, 255, 255, (x + y) % 2 == 0 ? 255 : 0}) image.rgba8.push_back(c);
  return scene.textures.addTexture(scene.textures.addImage(image, true), -1, -1, kNearest, kNearest);
}

/// Slot `slot` (WT_TEXTURE_SLOT_*) of material `material` reads `texture`.
inline void setMaterialTexture(Scene& scene, std::uint32_t material, std::uint32_t slot, std::uint32_t texture) {
  scene.materialTextures.resize(scene.materials.size() * WT_TEXTURE_SLOTS);
  WtTextureRef ref{};
  ref.texture = texture;
  ref.scale = 1.0f;
  ref.transform_u = {1.0f, 0.0f, 0.0f, 0.0f};
  ref.transform_v = {0.0f, 1.0f, 0.0f, 0.0f};
  scene.materialTextures[material * WT_TEXTURE_SLOTS + slot] = ref;
  scene.materials[material].texture_mask |= 1u << slot;
}

inline void setBaseColorTexture(Scene& scene, std::uint32_t material, std::uint32_t texture) {
  setMaterialTexture(scene, material, WT_TEXTURE_SLOT_BASE_COLOR, texture);
}

}  // namespace wt::test
