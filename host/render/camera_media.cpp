#include "render/camera_media.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace wt {
namespace {

// unit directions in general position: no two along one plane of an
// axis-aligned box, so that at most one of them meets an edge of common geometry
const std::array<glm::dvec3, 3> kDirections = {glm::normalize(glm::dvec3(0.5772, 0.5774, 0.5776)),
                                               glm::normalize(glm::dvec3(-0.3101, 0.8203, -0.4807)),
                                               glm::normalize(glm::dvec3(0.7071, -0.2929, -0.6432))};

/// Distance along the ray to triangle (a, b, c) (Moller-Trumbore, double, both
/// faces); NaN where it misses or lies behind.
double rayTriangle(const glm::dvec3& o, const glm::dvec3& d, const glm::dvec3& a, const glm::dvec3& b,
                   const glm::dvec3& c) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (det == 0.0) return nan;
  const glm::dvec3 s = o - a;
  const double u = glm::dot(s, p) / det;
  if (u < 0.0 || u > 1.0) return nan;
  const glm::dvec3 q = glm::cross(s, e1);
  const double v = glm::dot(d, q) / det;
  if (v < 0.0 || u + v > 1.0) return nan;
  const double t = glm::dot(e2, q) / det;
  return t > 0.0 ? t : nan;
}

}  // namespace

WtMediaStack cameraMediaStack(const Scene& scene, glm::vec3 point) {
  WtMediaStack stack;
  for (wt_uint& id : stack.id) id = WT_MEDIUM_NONE;
  const std::size_t count = scene.materials.size();
  std::vector<char> boundary(count, 0);
  bool any = false;
  for (std::size_t m = 0; m < count; ++m) {
    boundary[m] = char(media_is_boundary(scene.materials.data(), wt_uint(m)));
    any |= boundary[m] != 0;
  }
  if (!any) return stack;

  // per material: leaving minus entering crossings along each ray, and the nearest boundary
  std::vector<std::array<int, 3>> winding(count, {0, 0, 0});
  std::vector<double> nearest(count, std::numeric_limits<double>::infinity());
  const glm::dvec3 o(point);
  auto vertex = [&](wt_uint i) {
    const WtVec4& v = scene.positions[i];
    return glm::dvec3(v.x, v.y, v.z);
  };
  for (const WtTriangle& t : scene.triangles) {
    if (t.material >= count || !boundary[t.material]) continue;
    const glm::dvec3 a = vertex(t.v0), b = vertex(t.v1), c = vertex(t.v2);
    const glm::dvec3 ng = glm::cross(b - a, c - a);  // the winding's normal: out of the volume
    for (std::size_t k = 0; k < kDirections.size(); ++k) {
      const double dist = rayTriangle(o, kDirections[k], a, b, c);
      if (std::isnan(dist)) continue;
      winding[t.material][k] += glm::dot(ng, kDirections[k]) > 0.0 ? 1 : -1;
      nearest[t.material] = std::min(nearest[t.material], dist);
    }
  }
  for (const Sphere& s : scene.spheres) {
    if (s.material >= count || !boundary[s.material]) continue;
    const double r = s.radius, d = glm::length(o - glm::dvec3(s.center));
    if (!(d < r)) continue;
    for (int& w : winding[s.material]) ++w;
    nearest[s.material] = std::min(nearest[s.material], r - d);
  }

  std::vector<wt_uint> inside;
  for (std::size_t m = 0; m < count; ++m) {
    int votes = 0;
    for (int w : winding[m]) votes += w > 0;
    if (votes >= 2) inside.push_back(wt_uint(m));
  }
  // the outermost first: its boundary the farthest
  std::stable_sort(inside.begin(), inside.end(), [&](wt_uint a, wt_uint b) { return nearest[a] > nearest[b]; });
  for (wt_uint m : inside) media_cross(&stack, scene.materials.data(), m, 1);
  return stack;
}

}  // namespace wt
