// Instances on the host: their rows and boxes (kernels/geometry/instance.cl).
#include "geometry/primitives.h"

#include <cmath>

namespace wt {
namespace {

/// Three float4 rows of the 3x4 affine matrix m (glm is column-major).
void appendRows(const glm::dmat4& m, std::vector<WtVec4>& data) {
  for (int r = 0; r < 3; ++r)
    data.push_back({float(m[0][r]), float(m[1][r]), float(m[2][r]), float(m[3][r])});
}

}  // namespace

void gatherInstances(std::span<const InstanceDesc> instances, PrimitiveRows& rows) {
  rows.dataFirst[WT_PRIM_INSTANCE] = std::uint32_t(rows.data.size());
  rows.infoFirst[WT_PRIM_INSTANCE] = std::uint32_t(rows.info.size());
  rows.count[WT_PRIM_INSTANCE] = instances.size();
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const InstanceDesc& instance = instances[i];
    const glm::dmat4& toScene = instance.objectToScene;
    appendRows(glm::inverse(toScene), rows.data);
    appendRows(toScene, rows.data);
    const bool mirrored = glm::determinant(glm::dmat3(toScene)) < 0.0;
    rows.info.push_back({instance.root,
                         (mirrored ? WT_INSTANCE_MIRRORED : 0u) | (instance.primitives ? WT_INSTANCE_PRIMITIVES : 0u),
                         0u, 0u});

    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const Aabb& box : instance.rootBoxes) {
      if (!(box.lo.x <= box.hi.x && box.lo.y <= box.hi.y && box.lo.z <= box.hi.z)) continue;
      for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 c((corner & 1) ? box.hi.x : box.lo.x, (corner & 2) ? box.hi.y : box.lo.y,
                           (corner & 4) ? box.hi.z : box.lo.z);
        const glm::dvec3 w(toScene * glm::dvec4(c, 1.0));
        lo = glm::min(lo, w);
        hi = glm::max(hi, w);
      }
    }
    // The ray meets the copy through the float matrices, a few ulps from the
    // double ones: widen by more than that, relative to the box's magnitude.
    const glm::dvec3 slack = 4e-6 * (glm::max(glm::abs(lo), glm::abs(hi)) + (hi - lo));
    Aabb box;
    box.lo = glm::vec3(lo - slack);
    box.hi = glm::vec3(hi + slack);
    const bool finite = std::isfinite(box.lo.x) && std::isfinite(box.lo.y) && std::isfinite(box.lo.z) &&
                        std::isfinite(box.hi.x) && std::isfinite(box.hi.y) && std::isfinite(box.hi.z);
    if (!finite || !(lo.x <= hi.x)) {
      ++rows.skipped;
      continue;
    }
    rows.bounds.push_back(box);
    rows.ids.push_back(primId(WT_PRIM_INSTANCE, std::uint32_t(i)));
  }
}

}  // namespace wt
