// Spheres on the host: their boxes and rows (kernels/geometry/sphere.cl).
#include "geometry/primitives.h"

#include <numbers>

#include <cmath>

namespace wt {

bool sphereUsable(const Sphere& s) {
  return std::isfinite(s.center.x) && std::isfinite(s.center.y) && std::isfinite(s.center.z) &&
         std::isfinite(s.radius) && s.radius > 0.0f;
}

void gatherSpheres(const Scene& scene, PrimitiveRows& rows) {
  rows.dataFirst[WT_PRIM_SPHERE] = std::uint32_t(rows.data.size());
  rows.infoFirst[WT_PRIM_SPHERE] = std::uint32_t(rows.info.size());
  rows.count[WT_PRIM_SPHERE] = scene.spheres.size();
  // one row each by scene index, so a typed id is the scene's sphere index
  for (std::size_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& s = scene.spheres[i];
    rows.data.push_back({s.center.x, s.center.y, s.center.z, s.radius});
    rows.info.push_back({s.material, 0u, 0u, 0u});
    if (!sphereUsable(s)) {
      ++rows.skipped;
      continue;
    }
    Aabb box;
    box.extend(s.center - glm::vec3(s.radius));
    box.extend(s.center + glm::vec3(s.radius));
    // the box's float corners may round inside the sphere: widen by an ulp or so
    const glm::vec3 slack = 2.4e-7f * (glm::abs(s.center) + glm::vec3(s.radius));
    box.lo -= slack;
    box.hi += slack;
    rows.bounds.push_back(box);
    rows.ids.push_back(primId(WT_PRIM_SPHERE, std::uint32_t(i)));
  }
}

double sphereArea(const Scene& scene, const PrimitiveRows&, std::uint32_t index) {
  const double r = scene.spheres[index].radius;
  return 4.0 * std::numbers::pi * r * r;
}

}  // namespace wt
