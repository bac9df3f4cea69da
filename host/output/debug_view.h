// Debug views (`render --debug VIEW`): one AOV, or a heat map of a per-pixel
// count, as the image itself, for finding scene problems (flipped normals,
// missing textures, wrong materials, runaway paths).
#pragma once

#include "render/renderer.h"

#include <string_view>

namespace wt {

enum class DebugView : std::uint8_t { None, Normals, Albedo, Uv, Depth, Bounces, BvhCost };

/// "normals", "albedo", "uv", "depth", "bounces", "bvh-cost". Throws std::invalid_argument naming an unknown view.
DebugView parseDebugView(std::string_view name);

/// Replace the image's radiance and 8-bit pixels by the view of its AOVs
/// (image.aovs, which must be recorded; else std::invalid_argument).
/// Radiance (EXR): normals and albedo as they are, uv as (u, v, 0), depth
/// and bounces as grey values of the distance and the mean surfaces hit;
/// pixels (PNG): normals mapped from [-1, 1] to [0, 1], depth near-bright
/// over the image's depth range, bounces a heat map from 0 to the image's
/// maximum; bvh-cost likewise for the nodes the camera ray visited (which
/// needs RenderSettings::bvhCost). The variance is dropped (it belongs to the radiance).
void applyDebugView(Image& image, DebugView view);

}  // namespace wt
