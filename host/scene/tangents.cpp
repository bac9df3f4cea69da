#include "scene/tangents.h"

#include <cmath>

namespace wt {
namespace {

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// A unit vector perpendicular to unit n (Duff et al. 2017).
glm::vec3 perpendicular(glm::vec3 n) {
  float sign = std::copysign(1.0f, n.z);
  float a = -1.0f / (sign + n.z);
  float b = n.x * n.y * a;
  return glm::vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

}  // namespace

std::vector<std::uint32_t> generateTangents(std::span<const glm::vec3> positions, std::span<const glm::vec3> normals,
                                            std::span<const glm::vec2> texcoords, std::vector<std::uint32_t>& corners,
                                            std::vector<glm::vec4>& tangents) {
  const std::size_t n = positions.size();
  // sums per (vertex, handedness): index 2 v for right-handed, 2 v + 1 for left-handed
  std::vector<glm::vec3> sum(2 * n, glm::vec3(0.0f));
  std::vector<std::uint8_t> used(2 * n, 0);
  std::vector<std::uint8_t> cornerLeft(corners.size(), 0);
  std::vector<glm::vec3> faceNormal(n, glm::vec3(0.0f));  // summed, for vertices without a normal

  for (std::size_t t = 0; t + 2 < corners.size(); t += 3) {
    const std::uint32_t v[3] = {corners[t], corners[t + 1], corners[t + 2]};
    const glm::vec3 e1 = positions[v[1]] - positions[v[0]], e2 = positions[v[2]] - positions[v[0]];
    const glm::vec2 d1 = texcoords[v[1]] - texcoords[v[0]], d2 = texcoords[v[2]] - texcoords[v[0]];
    const glm::vec3 ng = glm::cross(e1, e2);
    for (std::uint32_t k : v) faceNormal[k] += ng;
    const float det = d1.x * d2.y - d2.x * d1.y;
    glm::vec3 tu(0.0f), tv(0.0f);
    if (det != 0.0f && std::isfinite(det)) {
      tu = (e1 * d2.y - e2 * d1.y) / det;
      tv = (e2 * d1.x - e1 * d2.x) / det;
      if (!finite(tu) || !finite(tv)) tu = tv = glm::vec3(0.0f);
    }
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 a = positions[v[(k + 1) % 3]] - positions[v[k]];
      const glm::vec3 b = positions[v[(k + 2) % 3]] - positions[v[k]];
      const float la = glm::length(a), lb = glm::length(b);
      float angle = (la > 0.0f && lb > 0.0f) ? std::acos(glm::clamp(glm::dot(a, b) / (la * lb), -1.0f, 1.0f)) : 0.0f;
      if (!std::isfinite(angle)) angle = 0.0f;
      glm::vec3 nv = normals.empty() ? ng : normals[v[k]];
      // glTF's v runs down the image, and its bitangent up it (towards -dp/dv)
      const bool left = glm::dot(glm::cross(nv, tu), tv) > 0.0f;
      cornerLeft[t + k] = left;
      sum[2 * v[k] + left] += angle * tu;
      used[2 * v[k] + left] = 1;
    }
  }

  std::vector<std::uint32_t> sources(n);
  for (std::uint32_t i = 0; i < n; ++i) sources[i] = i;
  // a vertex used with both handednesses gets a copy for its left-handed corners
  std::vector<std::uint32_t> leftVertex(n);
  for (std::uint32_t i = 0; i < n; ++i) {
    leftVertex[i] = i;
    if (used[2 * i] && used[2 * i + 1]) {
      leftVertex[i] = std::uint32_t(sources.size());
      sources.push_back(i);
    }
  }
  tangents.assign(sources.size(), glm::vec4(1.0f, 0.0f, 0.0f, 1.0f));
  for (std::size_t c = 0; c < corners.size(); ++c)
    if (cornerLeft[c]) corners[c] = leftVertex[corners[c]];
  for (std::uint32_t out = 0; out < sources.size(); ++out) {
    const std::uint32_t i = sources[out];
    const bool left = out >= n || (used[2 * i + 1] && !used[2 * i]);
    glm::vec3 nv = normals.empty() ? faceNormal[i] : normals[i];
    const float nl = glm::length(nv);
    nv = (nl > 0.0f && std::isfinite(nl)) ? nv / nl : glm::vec3(0.0f, 0.0f, 1.0f);
    glm::vec3 t = sum[2 * i + left];
    t -= nv * glm::dot(nv, t);
    const float tl = glm::length(t);
    t = (tl > 0.0f && std::isfinite(tl)) ? t / tl : perpendicular(nv);
    tangents[out] = glm::vec4(t, left ? -1.0f : 1.0f);
  }
  return sources;
}

}  // namespace wt
