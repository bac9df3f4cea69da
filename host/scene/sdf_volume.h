// Grids of signed distances from files and from formulas: Mitsuba's .vol
// grids and procedural shapes (the scene file's "sdf" objects), as SdfGrid
// (scene/scene.h) values in voxel units.
#pragma once

#include "scene/scene.h"

#include <glm/glm.hpp>

#include <string>
#include <vector>

namespace wt {

/// A grid's corner values and the object-space box its lattice spans.
struct SdfVolume {
  glm::uvec3 cells{0};          ///< per axis (corners - 1)
  std::vector<float> values;    ///< corners, x fastest, voxel units (SdfGrid)
  glm::dvec3 lo{0.0}, hi{1.0};  ///< object-space box of the lattice
  /// lattice (corner (i, j, k) at (i, j, k)) -> object space
  glm::dmat4 latticeToObject() const;
};

/// The procedural shapes of a scene file's "sdf" object, in the object box [-1, 1]^3.
enum class SdfShape { kSphere, kTorus, kBox, kNoisySphere };

struct SdfShapeParams {
  double radius = 0.8;        ///< sphere, noisy sphere: radius; torus: radius of the ring
  double minorRadius = 0.25;  ///< torus: radius of the tube
  double halfSize = 0.6;      ///< box: half its edge
  double amplitude = 0.06;    ///< noisy sphere: how far the noise moves the surface (object units)
  double frequency = 5.0;     ///< noisy sphere: the noise's waves per object unit (radians)
};

/// The signed distance of a shape at object-space point p (a bound on it
/// for the noisy sphere, whose noise is not a distance).
double sdfShapeDistance(SdfShape shape, const SdfShapeParams& params, glm::dvec3 p);

/// A shape sampled at the corners of resolution^3 cells over [-1, 1]^3.
SdfVolume makeSdfShape(SdfShape shape, const SdfShapeParams& params, std::uint32_t resolution);

/// A Mitsuba .vol grid ("VOL", version 3, encoding 1 = float32, x/y/z
/// resolution, 1 channel, the bounding box as 6 floats, then the values x
/// fastest): the values are the corners (resolution - 1 cells per axis) in
/// the box's units, scaled to voxel units here. A malformed file, a NaN or
/// infinite value, a channel count other than 1 or a degenerate box throws
/// SceneError naming `name` and what is wrong.
SdfVolume loadVolFile(const std::string& path, const std::string& name);

/// A raw grid: (cells + 1) corner values per axis as little-endian float32,
/// x fastest, nothing else, in the units of the box [lo, hi] the corners
/// span; scaled to voxel units here. A file of another size, or a NaN or
/// infinite value, throws SceneError naming `name`.
SdfVolume loadRawSdf(const std::string& path, const std::string& name, glm::uvec3 cells, glm::dvec3 lo, glm::dvec3 hi);

/// Writes a float32 single-channel .vol file (values as given).
void writeVolFile(const std::string& path, glm::uvec3 corners, const std::vector<float>& values, glm::dvec3 lo,
                  glm::dvec3 hi);

/// What is wrong with a grid's values for drawing ("" when nothing): no
/// corner inside, or none outside, so no surface.
std::string sdfSurfaceProblem(const std::vector<float>& values);

}  // namespace wt
