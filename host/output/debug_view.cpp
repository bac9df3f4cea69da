#include "output/debug_view.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace wt {
namespace {

std::uint8_t encodeSrgb(float linear) {
  float c = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
  float s = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
  return std::uint8_t(std::lround(s * 255.0f));
}

/// A heat map from blue (0) through green to red (1), as display values.
void heat(float t, float out[3]) {
  t = std::clamp(std::isfinite(t) ? t : 0.0f, 0.0f, 1.0f);
  out[0] = std::clamp(2.0f * t - 0.5f, 0.0f, 1.0f);
  out[1] = 1.0f - std::abs(2.0f * t - 1.0f);
  out[2] = std::clamp(1.0f - 2.0f * t + 0.5f, 0.0f, 1.0f);
}

}  // namespace

DebugView parseDebugView(std::string_view name) {
  if (name == "normals") return DebugView::Normals;
  if (name == "albedo") return DebugView::Albedo;
  if (name == "uv") return DebugView::Uv;
  if (name == "depth") return DebugView::Depth;
  if (name == "bounces") return DebugView::Bounces;
  if (name == "bvh-cost") return DebugView::BvhCost;
  throw std::invalid_argument("--debug: unknown view '" + std::string(name) +
                              "' (known: normals, albedo, uv, depth, bounces, bvh-cost)");
}

void applyDebugView(Image& image, DebugView view) {
  if (view == DebugView::None) return;
  const Aovs& a = image.aovs;
  if (a.empty()) throw std::invalid_argument("--debug: the render recorded no AOVs");
  const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
  float depthMin = INFINITY, depthMax = 0.0f, bouncesMax = 0.0f, costMax = 0.0f;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (std::isfinite(a.depth[i])) depthMin = std::min(depthMin, a.depth[i]), depthMax = std::max(depthMax, a.depth[i]);
    bouncesMax = std::max(bouncesMax, a.bounces[i]);
    costMax = std::max(costMax, a.bvhCost[i]);
  }
  image.rgb.assign(3 * pixels, 0.0f);
  image.srgba.assign(4 * pixels, 255);
  image.rgbVariance.clear();
  for (std::size_t i = 0; i < pixels; ++i) {
    float* rgb = &image.rgb[3 * i];
    float display[3] = {0.0f, 0.0f, 0.0f};  // linear values for the 8-bit pixels
    switch (view) {
      case DebugView::Normals:
        for (int c = 0; c < 3; ++c) rgb[c] = a.normal[3 * i + c], display[c] = 0.5f * rgb[c] + 0.5f;
        if (a.normal[3 * i] == 0.0f && a.normal[3 * i + 1] == 0.0f && a.normal[3 * i + 2] == 0.0f)
          display[0] = display[1] = display[2] = 0.0f;  // no surface: black, not grey
        break;
      case DebugView::Albedo:
        for (int c = 0; c < 3; ++c) rgb[c] = display[c] = a.albedo[3 * i + c];
        break;
      case DebugView::Uv:
        rgb[0] = display[0] = a.uv[2 * i];
        rgb[1] = display[1] = a.uv[2 * i + 1];
        break;
      case DebugView::Depth: {
        const float d = a.depth[i];
        rgb[0] = rgb[1] = rgb[2] = std::isfinite(d) ? d : 0.0f;
        if (std::isfinite(d)) {
          const float range = depthMax - depthMin;
          display[0] = display[1] = display[2] = range > 0.0f ? 1.0f - 0.9f * (d - depthMin) / range : 1.0f;
        }
        break;
      }
      case DebugView::Bounces:
        rgb[0] = rgb[1] = rgb[2] = a.bounces[i];
        heat(bouncesMax > 0.0f ? a.bounces[i] / bouncesMax : 0.0f, display);
        break;
      case DebugView::BvhCost:
        rgb[0] = rgb[1] = rgb[2] = a.bvhCost[i];
        heat(costMax > 0.0f ? a.bvhCost[i] / costMax : 0.0f, display);
        break;
      case DebugView::None: break;
    }
    for (int c = 0; c < 3; ++c) image.srgba[4 * i + c] = encodeSrgb(display[c]);
  }
}

}  // namespace wt
