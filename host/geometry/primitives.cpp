// The geometry types beside triangles: the host's one list of them.
#include "geometry/primitives.h"

#include <array>
#include <cmath>
#include <iterator>

namespace wt {

void gatherNoRows(const Scene&, PrimitiveRows&) {}
double noArea(const Scene&, const PrimitiveRows&, std::uint32_t) { return std::nan(""); }

std::span<const PrimitiveType> primitiveTypes() {
#define WT_GEOMETRY_ROW(TAG, ID, NAME, FEATURE, SWITCH, GATHER, AREA) \
  PrimitiveType{WT_PRIM_##TAG, NAME, "WT_HAS_" #SWITCH, FEATURE, GATHER, AREA},
  static constexpr PrimitiveType kTypes[] = {WT_GEOMETRY_TYPES(WT_GEOMETRY_ROW)};
#undef WT_GEOMETRY_ROW
  static_assert(std::size(kTypes) + 1 == WT_PRIM_TYPES);
  static_assert([] {  // ids 1 .. WT_PRIM_TYPES - 1, each once (0 is triangles)
    std::uint32_t seen = 0;
    for (const PrimitiveType& t : kTypes) seen |= 1u << t.id;
    return seen == (1u << WT_PRIM_TYPES) - 2u;
  }());
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
    if (t.id == WT_PRIM_INSTANCE)
      gatherInstances(instances, rows);
    else
      t.gather(scene, rows);
  }
  return rows;
}

double primitiveScale(const Scene& scene, const PrimitiveRows& rows) {
  double area = 0.0;
  std::size_t counted = 0;
  auto add = [&](double a) {
    if (std::isfinite(a)) area += a, ++counted;
  };
  for (const WtTriangle& t : scene.triangles) {
    const glm::dvec3 p0(scene.positions[t.v0].x, scene.positions[t.v0].y, scene.positions[t.v0].z);
    const glm::dvec3 p1(scene.positions[t.v1].x, scene.positions[t.v1].y, scene.positions[t.v1].z);
    const glm::dvec3 p2(scene.positions[t.v2].x, scene.positions[t.v2].y, scene.positions[t.v2].z);
    add(0.5 * glm::length(glm::cross(p1 - p0, p2 - p0)));
  }
  std::array<double (*)(const Scene&, const PrimitiveRows&, std::uint32_t), WT_PRIM_TYPES> areaOf{};
  for (const PrimitiveType& t : primitiveTypes()) areaOf[t.id] = t.area;
  for (std::uint32_t id : rows.ids)
    if (const auto f = areaOf[primType(id)]) add(f(scene, rows, primIndex(id)));
  if (counted > 0 && area > 0.0) return std::sqrt(area / double(counted));
  // no surface to measure: the bounds spread over the primitives as over a surface
  const Aabb b = scene.bounds();
  const glm::dvec3 diagonal(double(b.hi.x) - b.lo.x, double(b.hi.y) - b.lo.y, double(b.hi.z) - b.lo.z);
  const std::size_t prims = std::max<std::size_t>(1, scene.triangles.size() + rows.ids.size());
  const double d = glm::length(diagonal);
  return std::isfinite(d) && d > 0.0 ? d / std::sqrt(double(prims)) : 1.0;
}

}  // namespace wt
