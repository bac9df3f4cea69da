#include "scene/camera_override.h"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace wt {
namespace {

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

void requireFinite(const std::optional<glm::dvec3>& v, const char* option) {
  if (v && !finite(*v)) throw std::invalid_argument(std::string(option) + ": the coordinates must be finite");
}

// Up and view directions closer than this to parallel leave the camera's roll undefined.
constexpr double kParallelSine = 1e-6;

bool parallel(const glm::dvec3& a, const glm::dvec3& b) {
  return glm::length(glm::cross(glm::normalize(a), glm::normalize(b))) < kParallelSine;
}

}  // namespace

void applyCameraOverride(Scene& scene, const CameraOverride& o) {
  if (!o.any()) return;
  requireFinite(o.from, "--look-from");
  requireFinite(o.at, "--look-at");
  requireFinite(o.up, "--up");
  if (o.up && glm::length(*o.up) == 0.0) throw std::invalid_argument("--up: the up direction must not be zero");
  if (o.fovDegrees && !(*o.fovDegrees > 0.0 && *o.fovDegrees < 180.0))
    throw std::invalid_argument("--fov: must be in (0, 180) degrees, got " + std::to_string(*o.fovDegrees));
  if (o.frame && (o.from || o.at))
    throw std::invalid_argument("--frame places the camera itself: it cannot be combined with --look-from or --look-at");

  const float yfov = o.fovDegrees ? float(glm::radians(*o.fovDegrees)) : glm::radians(45.0f);
  CameraDesc desc = (o.frame || !scene.camera) ? defaultCamera(scene.bounds(), yfov) : *scene.camera;
  if (o.fovDegrees) {
    if (desc.orthographic) throw std::invalid_argument("--fov: the scene's camera is orthographic (it has no field of view)");
    desc.yfov = yfov;
  }

  // The scene is stored relative to scene.origin: the options are in the file's world coordinates.
  const glm::dmat4 current(desc.cameraToWorld);
  const glm::dvec3 eye(current[3]);
  const glm::dvec3 forward = -glm::normalize(glm::dvec3(current[2]));
  const glm::dvec3 cameraUp = glm::normalize(glm::dvec3(current[1]));
  const glm::dvec3 newEye = o.from ? *o.from - scene.origin : eye;
  const glm::dvec3 target = o.at ? *o.at - scene.origin : newEye + forward;
  const glm::dvec3 view = target - newEye;
  if (!(glm::length(view) > 0.0))
    throw std::invalid_argument(o.from ? "--look-at: the point looked at must differ from --look-from"
                                       : "--look-at: the point looked at must differ from the camera's position");
  glm::dvec3 up = o.up ? *o.up : cameraUp;
  if (parallel(up, view)) {
    if (o.up) throw std::invalid_argument("--up: the up direction must not be parallel to the view direction");
    // turned to look straight along its old up axis: roll taken from world +Y, else +Z
    up = parallel(glm::dvec3(0, 1, 0), view) ? glm::dvec3(0, 0, 1) : glm::dvec3(0, 1, 0);
  }
  if (o.from || o.at || o.up) {
    desc.cameraToWorld = glm::mat4(glm::inverse(glm::lookAt(newEye, target, up)));
    desc.name = "command line";
  } else if (!o.frame) {
    desc.name += " (field of view from the command line)";
  }
  scene.camera = desc;
}

}  // namespace wt
