// The camera a user asks for on the command line (--look-from, --look-at,
// --up, --fov, --frame), applied over the scene's own camera.
#pragma once

#include "scene/scene.h"

#include <glm/glm.hpp>

#include <optional>

namespace wt {

/// Camera settings given in the file's world coordinates. What is not given
/// stays as the scene's camera (or the framing camera when it has none).
struct CameraOverride {
  std::optional<glm::dvec3> from;   ///< eye; alone it moves the camera, keeping its view direction
  std::optional<glm::dvec3> at;     ///< point looked at; alone it turns the camera in place
  std::optional<glm::dvec3> up;     ///< default: the camera's current up axis
  std::optional<double> fovDegrees; ///< vertical, perspective; with frame the distance follows it
  bool frame = false;               ///< start from a camera framing the scene's bounds

  bool any() const { return from || at || up || fovDegrees || frame; }
};

/// Replaces scene.camera by the override applied to it. Throws
/// std::invalid_argument naming the option for a camera that cannot be
/// built (eye at the point looked at, up along the view, a fov outside
/// (0, 180), --frame with --look-from or --look-at, non-finite values).
void applyCameraOverride(Scene& scene, const CameraOverride& override);

}  // namespace wt
