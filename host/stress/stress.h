// The numerical-stability stress suite (issue 5): each row puts one part of
// the renderer where float arithmetic is weakest and measures whether it
// holds, with a pass criterion stated next to the figure. `wavetrace stress`
// prints every row; the tests run the quick variant of each group.
#pragma once

#include "device/context.h"
#include "device/tracer.h"
#include "scene/scene.h"

#include <glm/glm.hpp>

#include <functional>
#include <string>
#include <vector>

namespace wt {

struct StressRow {
  std::string group;      ///< "transform", "cracks", "self-intersection", "degenerate", "materials", "textures", "accumulation", "non-finite"
  std::string name;       ///< the case
  std::string figure;     ///< what was measured
  std::string criterion;  ///< what passing means
  bool pass = false;
  double seconds = 0.0;
};

struct StressOptions {
  bool quick = false;  ///< small images and ray counts (the CTest subset)
  std::vector<std::string> groups;  ///< empty: every group
};

using StressGroup = std::vector<StressRow> (*)(Context&, const StressOptions&);

/// The groups by name, in the order `wavetrace stress` runs them.
const std::vector<std::pair<std::string, StressGroup>>& stressGroups();

/// Run the selected groups; `onRow` sees each row as it is finished.
std::vector<StressRow> runStress(Context& context, const StressOptions& options,
                                 const std::function<void(const StressRow&)>& onRow = {});

/// A figure formatted with printf's `fmt` (one double), for the rows.
std::string stressFormat(const char* fmt, double v);

/// Every vertex, every edge midpoint and `perEdge` random points along every
/// edge of the scene's triangles; with `visibleFrom`, only the edges whose
/// two ends face that point (vertex normals), so no target is a silhouette.
/// The targets of the crack rows and of the watertightness tests.
std::vector<glm::vec3> edgeTargets(const Scene& scene, int perEdge, std::uint32_t seed,
                                   const glm::vec3* visibleFrom = nullptr);

/// Rays from each origin through each target that find nothing: closest-hit
/// misses plus any-hit misses (a closed mesh around or in front of the
/// origins must stop every one), traced one ray per work-item, again in
/// packets, and the any-hit queries once more as streams. Adds the rays
/// traced to *rayCount.
std::uint64_t countLeaks(Tracer& tracer, const std::vector<glm::vec3>& origins, const std::vector<glm::vec3>& targets,
                         std::uint64_t* rayCount);

/// `wavetrace stress`: every row printed with its figure and criterion (or
/// JSON); returns 1 when any row fails.
int runStressCommand(const StressOptions& options, const std::string& device, bool json);

// The groups (host/stress/*.cpp).
std::vector<StressRow> stressTransforms(Context&, const StressOptions&);       ///< translated and scaled scenes render the same image
std::vector<StressRow> stressCracks(Context&, const StressOptions&);           ///< rays at shared edges and vertices of closed meshes never leak
std::vector<StressRow> stressSelfIntersection(Context&, const StressOptions&); ///< re-spawned grazing rays never find the surface they left
std::vector<StressRow> stressDegenerate(Context&, const StressOptions&);       ///< degenerate files: a warning or a clear error, never a NaN
std::vector<StressRow> stressMaterials(Context&, const StressOptions&);        ///< material extremes in a furnace: no NaN, no energy gain
std::vector<StressRow> stressAccumulation(Context&, const StressOptions&);     ///< 2^20 samples per precision mode against double
std::vector<StressRow> stressNonFinite(Context&, const StressOptions&);        ///< NaN samples are counted, reported and never accumulated
std::vector<StressRow> stressPrimitives(Context&, const StressOptions&);       ///< the other geometry types: transforms, self-intersection, degenerate input
std::vector<StressRow> stressFarFurnace(Context&, const StressOptions&);      ///< white objects of every geometry type far from the origin vanish in a uniform sky
std::vector<StressRow> stressTextures(Context&, const StressOptions&);         ///< texture coordinates far out or NaN, one texel, odd sizes, 16 bits
std::vector<StressRow> stressDisplaced(Context&, const StressOptions&);        ///< displaced meshes (in the primitives group): transforms, zero and extreme scale, NaN maps

}  // namespace wt
