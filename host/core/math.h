// Small geometric helpers shared by every host module.
#pragma once

#include <glm/glm.hpp>

#include <algorithm>
#include <limits>

namespace wt {

/// Axis-aligned box; empty when lo > hi.
struct Aabb {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};

  void extend(const glm::vec3& p) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  void extend(const Aabb& b) {
    lo = glm::min(lo, b.lo);
    hi = glm::max(hi, b.hi);
  }
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  glm::vec3 center() const { return 0.5f * (lo + hi); }
  glm::vec3 extent() const { return hi - lo; }
  float surfaceArea() const {
    if (empty()) return 0.0f;
    glm::vec3 e = extent();
    return 2.0f * (e.x * e.y + e.y * e.z + e.z * e.x);
  }
  bool contains(const Aabb& b) const {
    return glm::all(glm::lessThanEqual(lo, b.lo)) && glm::all(glm::greaterThanEqual(hi, b.hi));
  }
};

}  // namespace wt
