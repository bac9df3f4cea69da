// The scene as flat arrays, ready to be uploaded: world-space vertices,
// triangles, materials and one camera. Loaders produce it; nothing here
// knows about glTF or OpenCL.
#pragma once

#include "core/math.h"
#include "shared/lights.h"
#include "shared/types.h"
#include "texture/texture.h"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {

/// A malformed or unreadable scene. what() names the file and the element,
/// e.g. "box.gltf: mesh 3, primitive 0: index 1234 out of range (1000 vertices)".
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A camera as the scene describes it; turned into WtCamera per image size.
struct CameraDesc {
  glm::mat4 cameraToWorld{1.0f};  ///< camera looks down -Z, +Y up (glTF convention)
  bool orthographic = false;
  float yfov = 0.6911f;           ///< radians, perspective only
  float aspectRatio = 0.0f;       ///< 0: use the image's
  float xmag = 1.0f, ymag = 1.0f; ///< half extents, orthographic only
  float znear = 0.0f;             ///< ray tmin along the view direction
  std::string name;
};

/// A KHR_lights_punctual light placed in the world. Units as glTF: candela
/// for point and spot, lux for directional (see kernels/shared/lights.h).
struct PunctualLight {
  int type = WT_LIGHT_POINT;        ///< WT_LIGHT_POINT, _SPOT or _DIRECTIONAL
  glm::vec3 position{0.0f};         ///< world
  glm::vec3 direction{0, 0, -1};    ///< world, unit: where the light travels (the node's -Z)
  glm::vec3 intensity{1.0f};        ///< colour x intensity
  float innerConeAngle = 0.0f;      ///< spot, radians
  float outerConeAngle = 0.7853982f;///< spot, radians
  std::string name;
};

/// A placed copy of a mesh primitive: triangles[firstTriangle ..
/// firstTriangle + triangleCount) are the primitive's triangles, in its own
/// order, moved by the copy's transform. Copies of one primitive's geometry
/// (the same positions and indices) share `geometry`, so that a BVH can be
/// built once per geometry (BvhInstance, host/bvh/lbvh.h) and the geometry
/// stored once (SceneBuffers with InstancingMode::On).
struct GeometryInstance {
  std::uint32_t firstTriangle = 0;
  std::uint32_t triangleCount = 0;
  std::uint32_t geometry = 0;
  /// mesh space -> scene space (world less Scene::origin), composed in double
  /// as the loader placed the copy; a mirroring one (negative determinant)
  /// had two corners of each triangle swapped so the front face stays in front
  glm::dmat4 transform{1.0};
};

/// A placed copy of a set of spheres, curves, SDF grids or displaced
/// meshes: Scene::spheres (type WT_PRIM_SPHERE), Scene::curves
/// (WT_PRIM_CURVE), Scene::sdfGrids (WT_PRIM_SDF_GRID) or
/// Scene::displacedMeshes (WT_PRIM_DISPLACED) [first, first + count) are the
/// geometry's items moved by `transform`, which is a similarity (rotation,
/// uniform scale, translation; radii and displacements scale with it), or
/// for SDF grids any affine map. Copies that share `geometry` (per type) can
/// be stored once (SceneBuffers with Instancing::On); a copy that is not its
/// source moved by the transforms (checked on the host) stays flattened.
struct PrimitiveInstance {
  std::uint32_t type = WT_PRIM_SPHERE;  ///< WT_PRIM_SPHERE, _CURVE, _SDF_GRID or _DISPLACED
  std::uint32_t first = 0, count = 0;
  std::uint32_t geometry = 0;
  glm::dmat4 transform{1.0};  ///< geometry space -> scene space (world less Scene::origin), double
};

/// An analytic sphere (kernels/geometry/sphere.cl), relative to Scene::origin
/// like every position. A sphere emits when its material does, from its
/// outside (and its inside for a double-sided material).
struct Sphere {
  glm::vec3 center{0.0f};     ///< world, relative to Scene::origin
  float radius = 1.0f;        ///< world units, > 0
  std::uint32_t material = 0; ///< index into Scene::materials
};

/// How a curve's points make its shape (kernels/geometry/curve.cl).
enum class CurveBasis : std::uint32_t {
  kLinear,   ///< a polyline of round cones: each point a joint sphere, each pair the hull of two
  kBSpline,  ///< a uniform cubic B-spline of (position, radius), which passes near but not through its points (not its end points either: repeat them to reach them); subdivided into linear segments on the host
};

/// A curve of round cross-section (hair, fur, grass, wires): points
/// [firstPoint, firstPoint + pointCount) of Scene::curvePoints.
struct Curve {
  std::uint32_t firstPoint = 0;
  std::uint32_t pointCount = 0;  ///< >= 2 (linear) or >= 4 (B-spline) for any segment
  std::uint32_t material = 0;    ///< index into Scene::materials
  CurveBasis basis = CurveBasis::kLinear;
};

/// How an SDF grid's values are stored on the device.
enum class SdfStorage : std::uint32_t {
  kAuto,    ///< sparse above kSdfSparseAboveCells cells, dense up to it
  kDense,   ///< every corner value of the grid, once (Falcor's normalized dense grid)
  kSparse,  ///< only the bricks the surface crosses, each with its own corners (Falcor's sparse brick set)
};

/// Grids of more cells than this are stored sparse unless the scene says otherwise.
constexpr std::uint64_t kSdfSparseAboveCells = 64ull * 64ull * 64ull;
/// Cells per axis at most: a brick's coordinates take 9 bits (WT_SDF_BRICK each).
constexpr std::uint32_t kSdfMaxCells = 4096;

/// A grid of signed distances (kernels/geometry/sdf_grid.cl): values at the
/// corners of cells.x * cells.y * cells.z cells, x fastest, interpolated
/// trilinearly; negative inside, the surface where the sign changes. Values
/// are in voxel units (a distance of one cell's shortest edge is 1), as
/// Falcor normalises its grids; only their sign and ratios matter to the
/// surface and its normal. Corner (i, j, k) sits at lattice point (i, j, k);
/// latticeToScene places the lattice.
struct SdfGrid {
  glm::uvec3 cells{0};             ///< per axis, 1 .. kSdfMaxCells
  std::vector<float> values;       ///< (cells.x + 1) (cells.y + 1) (cells.z + 1) corner values, x fastest
  glm::dmat4 latticeToScene{1.0};  ///< lattice -> scene (world less Scene::origin), affine, invertible
  std::uint32_t material = 0;      ///< index into Scene::materials
  SdfStorage storage = SdfStorage::kAuto;
};

/// A triangle mesh displaced along its interpolated normal by a scalar map
/// (kernels/geometry/displaced.cl): a point of a base triangle moves by
/// scale h(uv) + offset times the corners' normals interpolated linearly,
/// h the map sampled bilinearly between texel centres, repeating. Drawn as
/// the level-L micro-mesh (2^L micro-edges per base edge) without storing it.
struct DisplacedMesh {
  std::vector<glm::vec3> positions;   ///< world, relative to Scene::origin
  std::vector<glm::vec3> normals;     ///< unit, one per position
  std::vector<glm::vec2> texcoords;   ///< one per position, glTF's convention (v = 0 the map's top row)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise
  std::uint32_t mapWidth = 0, mapHeight = 0;
  std::vector<float> map;             ///< mapWidth * mapHeight values, row-major from the top; NaN is drawn as 0
  float scale = 1.0f;                 ///< world units per map unit
  float offset = 0.0f;                ///< world units, added after the scale
  int level = -1;                     ///< L in [0, WT_DISP_MAX_LEVEL]; -1: from the map's texel density (displacedLevel)
  std::uint32_t material = 0;         ///< index into Scene::materials
};

struct Scene {
  std::vector<WtVec4> positions;   ///< world space, w = 0
  std::vector<WtVec4> normals;     ///< world space, unit; (0,0,0) = none, use the geometric normal. Same size as positions.
  std::vector<glm::vec2> texcoords;///< TEXCOORD_0, same size as positions ((0,0) where absent)
  std::vector<glm::vec2> texcoords1;///< TEXCOORD_1: empty, or the size of positions ((0,0) where absent)
  std::vector<glm::vec4> colors;   ///< COLOR_0, linear RGBA: empty, or the size of positions ((1,1,1,1) where absent)
  std::vector<glm::vec4> tangents; ///< world, unit xyz and w = +-1 the bitangent's side (cross(n, t) w): empty, or the size of positions (zero where absent)
  std::vector<WtTriangle> triangles;
  std::vector<GeometryInstance> instances; ///< placed copies, in triangle order; may be empty (no copies known)
  std::vector<Sphere> spheres;            ///< analytic spheres (scene files only: glTF has none)
  std::vector<Curve> curves;              ///< round curves (scene files, .hair and .ply strands)
  std::vector<PrimitiveInstance> primitiveInstances;  ///< placed copies of spheres, curves, SDF grids and displaced meshes; may be empty
  std::vector<WtVec4> curvePoints;        ///< the curves' points: xyz world relative to origin, w = radius (world units, >= 0)
  std::vector<SdfGrid> sdfGrids;          ///< grids of signed distances (scene files, or made in code)
  std::vector<DisplacedMesh> displacedMeshes;  ///< displaced triangle meshes (scene files, or made in code)
  std::vector<WtMaterial> materials;      ///< never empty after loading (a default grey is added when needed)
  /// WT_TEXTURE_SLOTS per material (empty: no material is textured); slot s
  /// of material m, at m * WT_TEXTURE_SLOTS + s, counts where bit s of its
  /// texture_mask is set
  std::vector<WtTextureRef> materialTextures;
  TextureSet textures;                    ///< the images and samplers materialTextures name
  double textureSeconds = 0.0;            ///< decoding the images and building their mips
  std::vector<std::string> materialNames; ///< same size as materials
  std::optional<CameraDesc> camera;       ///< absent: frame the bounds (defaultCamera)
  std::vector<PunctualLight> lights;      ///< KHR_lights_punctual
  std::vector<std::string> warnings;      ///< unsupported features, once each, by name
  std::string sourceName;                 ///< file the scene came from, for messages
  glm::dvec3 origin{0.0};                 ///< world position of the scene's (0,0,0): every position, light and camera here is relative to it (GltfLoadOptions::recenter)

  /// Bounds of every triangle, sphere, curve point (with its radius), SDF
  /// grid's box and displaced mesh (its vertices moved by the largest |d|).
  Aabb bounds() const;
  /// Bounds of one triangle.
  Aabb triangleBounds(std::uint32_t tri) const;
  void addWarning(const std::string& text);  ///< keeps each text once
};

/// A camera looking at the bounds from +Z (and a little above), far enough
/// that the whole box fits the vertical field of view (radians).
CameraDesc defaultCamera(const Aabb& bounds, float yfov = 0.7853982f);

/// A camera transform with rigid axes: -Z keeps its direction, +Y is made
/// perpendicular to it, X last (on its side, so a mirroring transform still
/// mirrors); the translation as it was. Non-finite axes where the
/// transform's are parallel or zero.
glm::dmat4 rigidCameraTransform(const glm::dmat4& world);

/// The device camera for an image of width x height pixels.
WtCamera makeCamera(const CameraDesc& desc, int width, int height);

}  // namespace wt
