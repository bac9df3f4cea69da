// Host builds of the kernels' robust spawning (kernels/shared/spawn.h): the
// bench makes its secondary rays with them, and the tests compare them with
// the device bit for bit.
#pragma once

#include "shared/spawn.h"

#include <glm/glm.hpp>

namespace wt {

/// triangle_point (kernels/geometry/triangle.cl): the point with barycentrics
/// (1 - b1 - b2, b1, b2) and the rounding error bound of each coordinate.
inline glm::vec3 trianglePoint(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, float b1, float b2, glm::vec3* error) {
  float b0 = 1.0f - b1 - b2;
  for (int a = 0; a < 3; ++a) (*error)[a] = spawn_barycentric_error(b0, b1, b2, p0[a], p1[a], p2[a]);
  return b0 * p0 + b1 * p1 + b2 * p2;
}

/// ray_offset_origin (kernels/common.h): p pushed along unit n past its error bound.
inline glm::vec3 offsetRayOrigin(glm::vec3 p, glm::vec3 error, glm::vec3 n) {
  float d = spawn_offset_distance(n.x, n.y, n.z, error.x, error.y, error.z);
  glm::vec3 offset = d * n;
  return {spawn_offset_coordinate(p.x, offset.x), spawn_offset_coordinate(p.y, offset.y),
          spawn_offset_coordinate(p.z, offset.z)};
}

}  // namespace wt
