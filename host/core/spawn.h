// Host builds of the kernels' robust spawning (kernels/shared/spawn.h): the
// bench and the stress suite make their secondary rays with them, and
// tests/kernels/test_shared_code.cpp compares them with the device bit for bit.
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

/// sphere_surface (kernels/geometry/sphere.cl): where ray (o, d) meets the
/// sphere at t, reprojected onto it, with its rounding error bound; *normal
/// is the outward unit normal.
inline glm::vec3 spherePoint(glm::vec3 center, float radius, glm::vec3 o, glm::vec3 d, float t, glm::vec3* error,
                             glm::vec3* normal) {
  glm::vec3 q = o + t * d - center;
  float len = glm::length(q);
  *normal = len > 0.0f ? q / len : glm::vec3(0.0f, 1.0f, 0.0f);
  glm::vec3 rel = radius * *normal;
  glm::vec3 p = center + rel;
  *error = spawn_gamma(6) * glm::abs(rel) + spawn_gamma(2) * glm::abs(p);
  return p;
}

/// ray_offset_origin (kernels/common.h): p pushed along unit n past its error bound.
inline glm::vec3 offsetRayOrigin(glm::vec3 p, glm::vec3 error, glm::vec3 n) {
  float d = spawn_offset_distance(n.x, n.y, n.z, error.x, error.y, error.z);
  glm::vec3 offset = d * n;
  return {spawn_offset_coordinate(p.x, offset.x), spawn_offset_coordinate(p.y, offset.y),
          spawn_offset_coordinate(p.z, offset.z)};
}

}  // namespace wt
