// The volumes the camera is inside, for nested dielectrics
// (kernels/shared/media.h): every path's medium stack starts from them.
#pragma once

#include "scene/scene.h"
#include "shared/media.h"

#include <glm/glm.hpp>

namespace wt {

/// The closed transmitting volumes (media_is_boundary) that hold `point`, as
/// the stack a path would carry had it entered them from outside: the
/// outermost first (by the nearest boundary along the test rays, farthest
/// first), entered with media_cross, so a stack too small for them keeps the
/// ones of highest priority. A triangle mesh holds the point when the
/// crossings of its material's triangles along a ray from it leave more often
/// than they enter, on two of three rays in general position (a ray along an
/// edge may count a crossing twice or not at all); an analytic sphere when
/// the point is nearer its centre than its radius. Curves, grids of
/// distances and displaced meshes bound no media here.
WtMediaStack cameraMediaStack(const Scene& scene, glm::vec3 point);

}  // namespace wt
