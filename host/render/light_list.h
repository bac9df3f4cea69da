// The scene's lights as the kernels sample them: point, spot and directional
// lights first, then emissive triangles, then the environment; an alias
// table picks one with probability proportional to its estimated power.
#pragma once

#include "device/scene_buffers.h"
#include "scene/scene.h"
#include "shared/lights.h"

#include <cstdint>
#include <span>
#include <vector>

namespace wt {

struct LightList {
  std::vector<WtLight> lights;
  std::vector<WtAliasSlot> alias;      ///< one slot per light
  std::vector<float> emitterPdfArea;   ///< per leaf-order triangle: selection probability / area (0: not a light)
  std::uint32_t analyticCount = 0;     ///< lights [0, analyticCount) are point/spot/directional
  float environmentPmf = 0.0f;         ///< selection probability of the environment
  std::size_t emissiveTriangles = 0;
  bool sampleable = false;             ///< some light has power: NEE may pick from the table
};

/// Walker/Vose alias table for weights >= 0 (not all zero). pmf = weight / sum.
std::vector<WtAliasSlot> buildAliasTable(std::span<const double> weights);

/// The light list of a scene whose triangles were uploaded as `buffers`.
/// `environmentPower` is the environment's estimated power (0: no environment
/// light, see environmentPowerEstimate).
LightList buildLightList(const Scene& scene, const SceneBuffers& buffers, double environmentPower);

/// Power of a uniform environment of luminance `meanLuminance` falling on the scene's bounding sphere.
double environmentPowerEstimate(const Scene& scene, double meanLuminance);

double luminance(glm::vec3 rgb);

}  // namespace wt
