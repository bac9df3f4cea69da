#include "scene/scene.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace wt {

Aabb Scene::bounds() const {
  Aabb box;
  for (const WtTriangle& t : triangles)
    for (std::uint32_t v : {t.v0, t.v1, t.v2})
      box.extend(glm::vec3(positions[v].x, positions[v].y, positions[v].z));
  for (const Sphere& s : spheres) {
    box.extend(s.center - glm::vec3(s.radius));
    box.extend(s.center + glm::vec3(s.radius));
  }
  // a B-spline stays inside its points' hull
  for (const WtVec4& p : curvePoints) {
    const glm::vec3 c(p.x, p.y, p.z);
    if (!std::isfinite(p.x + p.y + p.z + p.w)) continue;
    box.extend(c - glm::vec3(std::fabs(p.w)));
    box.extend(c + glm::vec3(std::fabs(p.w)));
  }
  for (const SdfGrid& g : sdfGrids)
    for (int corner = 0; corner < 8; ++corner) {
      const glm::dvec3 c((corner & 1) ? g.cells.x : 0u, (corner & 2) ? g.cells.y : 0u, (corner & 4) ? g.cells.z : 0u);
      const glm::vec3 w(glm::dvec3(g.latticeToScene * glm::dvec4(c, 1.0)));
      if (std::isfinite(w.x + w.y + w.z)) box.extend(w);
    }
  for (const DisplacedMesh& m : displacedMeshes) {
    // the largest displacement any texel makes
    float reach = std::fabs(m.offset);
    for (float h : m.map)
      if (std::isfinite(h)) reach = std::max(reach, std::fabs(m.scale * h + m.offset));
    for (const auto& t : m.triangles)
      for (std::uint32_t v : t) {
        if (v >= m.positions.size()) continue;
        const glm::vec3 p = m.positions[v];
        if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(reach)) continue;
        box.extend(p - glm::vec3(reach));
        box.extend(p + glm::vec3(reach));
      }
  }
  return box;
}

Aabb Scene::triangleBounds(std::uint32_t tri) const {
  Aabb box;
  const WtTriangle& t = triangles[tri];
  for (std::uint32_t v : {t.v0, t.v1, t.v2})
    box.extend(glm::vec3(positions[v].x, positions[v].y, positions[v].z));
  return box;
}

void Scene::addWarning(const std::string& text) {
  if (std::find(warnings.begin(), warnings.end(), text) == warnings.end())
    warnings.push_back(text);
}

CameraDesc defaultCamera(const Aabb& bounds, float yfov) {
  CameraDesc desc;
  desc.name = "default (framing the scene bounds)";
  desc.yfov = yfov;
  glm::vec3 center = bounds.empty() ? glm::vec3(0.0f) : bounds.center();
  float radius = bounds.empty() ? 1.0f : std::max(0.5f * glm::length(bounds.extent()), 1e-6f);
  // Distance at which a sphere of that radius fills the vertical field of view.
  float distance = radius / std::sin(0.5f * desc.yfov);
  glm::vec3 eye = center + distance * glm::normalize(glm::vec3(0.0f, 0.25f, 1.0f));
  desc.cameraToWorld = glm::inverse(glm::lookAt(eye, center, glm::vec3(0.0f, 1.0f, 0.0f)));
  desc.znear = 0.0f;
  return desc;
}

WtCamera makeCamera(const CameraDesc& desc, int width, int height) {
  const glm::mat4& m = desc.cameraToWorld;
  glm::vec3 origin(m[3]);
  glm::vec3 axisX = glm::normalize(glm::vec3(m[0]));
  glm::vec3 axisY = glm::normalize(glm::vec3(m[1]));
  glm::vec3 axisZ = glm::normalize(glm::vec3(m[2]));
  // The image decides the aspect ratio; the camera keeps its vertical extent.
  float aspect = float(width) / float(std::max(height, 1));
  glm::vec3 right, up;
  if (desc.orthographic) {
    up = axisY * desc.ymag;
    right = axisX * desc.ymag * aspect;
  } else {
    float tanHalf = std::tan(0.5f * desc.yfov);
    up = axisY * tanHalf;
    right = axisX * tanHalf * aspect;
  }
  glm::vec3 forward = -axisZ;
  WtCamera cam;
  cam.origin = {origin.x, origin.y, origin.z,
                float(desc.orthographic ? WT_CAMERA_ORTHOGRAPHIC : WT_CAMERA_PERSPECTIVE)};
  cam.right = {right.x, right.y, right.z, 0.0f};
  cam.up = {up.x, up.y, up.z, 0.0f};
  cam.forward = {forward.x, forward.y, forward.z, desc.znear};
  return cam;
}

glm::dmat4 rigidCameraTransform(const glm::dmat4& world) {
  const glm::dvec3 z = glm::normalize(glm::dvec3(world[2]));
  const glm::dvec3 y = glm::normalize(glm::dvec3(world[1]) - glm::dot(glm::dvec3(world[1]), z) * z);
  const glm::dvec3 x = glm::normalize(glm::dvec3(world[0]) - glm::dot(glm::dvec3(world[0]), z) * z -
                                      glm::dot(glm::dvec3(world[0]), y) * y);
  return glm::dmat4(glm::dvec4(x, 0.0), glm::dvec4(y, 0.0), glm::dvec4(z, 0.0), world[3]);
}

}  // namespace wt
