// The scene's lights as the kernels sample them: point, spot and directional
// lights first, then emissive triangles, then the environment; an alias
// table picks one with probability proportional to its estimated power. With
// the light tree, the emissive triangles are one entry of the alias table
// (WT_LIGHT_TREE, their total power) and are stored after the others, where
// the tree's leaves point.
#pragma once

#include "device/program.h"
#include "device/scene_buffers.h"
#include "scene/scene.h"
#include "shared/lights.h"

#include <cstdint>
#include <span>
#include <vector>

namespace wt {

/// How next-event estimation picks among emissive triangles.
enum class LightSampler {
  Auto,   ///< the tree from kLightTreeMinEmitters emitters on, else by power
  Power,  ///< an alias table by power (the shading point plays no part)
  Tree,   ///< the light tree (importance at the shading point)
};

/// Emitter count from which LightSampler::Auto uses the light tree
/// (docs/integrators.md: where it starts to win).
constexpr std::size_t kLightTreeMinEmitters = 8;

struct LightList {
  std::vector<WtLight> lights;         ///< the alias table's entries first, then (with the tree) the emissive triangles
  std::vector<WtAliasSlot> alias;      ///< one slot per entry the table picks from (lights [0, alias.size()))
  /// per emitter slot (WtGeometry::emitter_first): for a leaf-order triangle, its (or, with the
  /// tree, the tree's) selection probability / area; for another type's primitive, its selection
  /// probability (0: not a light)
  std::vector<float> emitterPdfArea;
  std::vector<WtLightNode> tree;       ///< the light tree (empty without it)
  std::vector<std::uint32_t> emitterLeaf;  ///< per leaf-order triangle: its tree leaf, WT_LIGHT_NODE_NONE when not in the tree
  /// per leaf-order triangle: the index in `lights` of the WT_LIGHT_QUAD it is half of, WT_NO_QUAD when none
  std::vector<std::uint32_t> emitterQuad;
  std::uint32_t analyticCount = 0;     ///< lights [0, analyticCount) are point/spot/directional
  float environmentPmf = 0.0f;         ///< selection probability of the environment
  std::size_t emissiveTriangles = 0;   ///< the triangles among the lights (a quad light's two included)
  std::size_t quadLights = 0;          ///< WT_LIGHT_QUAD lights (findQuadLights)
  std::size_t emissivePrimitives = 0;  ///< emissive primitives of other types (spheres, displaced base triangles, SDF bricks)
  bool sampleable = false;             ///< some light has power: NEE may pick from the table
};

/// Two emissive triangles that make one rectangle: one light, sampled by
/// solid angle as a spherical rectangle (kernels/lights/light_sampling.cl).
struct QuadLight {
  std::uint32_t first = 0;   ///< leaf-order index of the half with the lower index
  std::uint32_t corner = 0;  ///< its corner (0, 1, 2) at the rectangle's right angle; the other two end the diagonal
  std::uint32_t second = 0;  ///< leaf-order index of the other half
};

/// How far from a rectangle a pair may be, relative to its diagonal: the
/// cosine of the angle at each half's right angle, and the distance of the
/// second half's far corner from where the first half's edges put it. At
/// 1e-5 the rectangle sampled and the two triangles hit differ by a sliver
/// of about that share of the area (a bias far below any render's noise),
/// while rectangles whose corners were rounded to float (1e-7 relative),
/// also after a node's transform, are all found.
constexpr double kQuadTolerance = 1e-5;

/// The pairs of emissive triangles (leaf order, not instanced) that make a
/// rectangle light: a shared diagonal (the same two positions), the same
/// material with untextured emission and no holes (alphaMode OPAQUE), a
/// right angle opposite the diagonal in each and the two windings facing the
/// same way, within kQuadTolerance; a general parallelogram stays two
/// triangles (spherical-rectangle sampling needs a rectangle). Sorted by
/// `first`; a triangle is in at most one pair.
std::vector<QuadLight> findQuadLights(const Scene& scene, const SceneBuffers& buffers);

/// Walker/Vose alias table for weights >= 0 (not all zero). pmf = weight / sum.
std::vector<WtAliasSlot> buildAliasTable(std::span<const double> weights);

/// The light list of a scene whose triangles were uploaded as `buffers`.
/// `environmentPower` is the environment's estimated power (0: no environment
/// light, see environmentPowerEstimate). `coverageWeights`: an emitter with
/// holes weighs by its meanCoverage (at least kMinCoverageWeight), else by
/// its emission alone (for comparison; unbiased either way).
/// `quadLights`: pairs findQuadLights finds are one WT_LIGHT_QUAD each (the
/// program must then be built with KernelFeatures::quadLights), else two
/// triangle lights.
LightList buildLightList(const Scene& scene, const SceneBuffers& buffers, double environmentPower,
                         LightSampler sampler = LightSampler::Auto, bool coverageWeights = true,
                         bool quadLights = true);

/// Set KernelFeatures::lightTree and otherLights from the light kinds `lights`
/// holds: a program built so samples every light the list can pick.
void setLightFeatures(KernelFeatures& features, const LightList& lights);

/// The least share of its power an emitter with holes is weighed by.
constexpr double kMinCoverageWeight = 1e-3;

/// Power of a uniform environment of luminance `meanLuminance` falling on the scene's bounding sphere.
double environmentPowerEstimate(const Scene& scene, double meanLuminance);

double luminance(glm::vec3 rgb);
/// The mean of the emissive texture (linear RGB) over triangle `t`, from 16
/// stratified texels of the mip level where each stands for about a 16th of
/// the triangle; 1 where its material has no emissive texture.
glm::dvec3 averageEmissiveTexture(const Scene& scene, const WtTriangle& t);
/// The share of triangle `t` that is there (a ray meets it) where its material
/// has holes (alphaMode MASK or BLEND): its coverage as traversal's alpha test
/// reads it (alpha factor x COLOR_0 alpha x base colour texture alpha; MASK 0
/// or 1 by the cutoff) averaged over 64 stratified points; 1 for OPAQUE.
double meanCoverage(const Scene& scene, const WtTriangle& t);

}  // namespace wt
