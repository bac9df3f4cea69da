// The geometry types beside triangles: the host's one list of them.
#include "geometry/primitives.h"

#include <array>

namespace wt {

std::span<const PrimitiveType> primitiveTypes() {
  static constexpr std::array<PrimitiveType, 5> kTypes = {{
      {WT_PRIM_SPHERE, "spheres", "WT_HAS_SPHERES", gatherSpheres},
      {WT_PRIM_CURVE, "curve segments", "WT_HAS_CURVES", gatherCurves},
      {WT_PRIM_INSTANCE, "instances", "WT_HAS_INSTANCES", nullptr},
      {WT_PRIM_SDF_GRID, "SDF bricks", "WT_HAS_SDF_GRIDS", gatherSdfGrids},
      {WT_PRIM_DISPLACED, "displaced triangles", "WT_HAS_DISPLACED", gatherDisplaced},
  }};
  return kTypes;
}

const char* primTypeName(std::uint32_t type) {
  if (type == WT_PRIM_TRIANGLE) return "triangles";
  for (const PrimitiveType& t : primitiveTypes())
    if (t.id == type) return t.name;
  return "";
}

PrimitiveRows gatherPrimitives(const Scene& scene, std::span<const InstanceDesc> instances) {
  PrimitiveRows rows;
  for (const PrimitiveType& t : primitiveTypes()) {
    if (t.gather)
      t.gather(scene, rows);
    else
      gatherInstances(instances, rows);
  }
  return rows;
}

}  // namespace wt
