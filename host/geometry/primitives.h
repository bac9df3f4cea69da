// The primitives other than triangles, gathered type by type into the rows
// the kernels read (kernels/geometry/geometry.cl): a box and a typed id per
// primitive for their BVH, and each type's prim_data and prim_info rows.
// A type's gatherer lives in host/geometry/<type>.cpp; the list in
// kernels/geometry/types.def names every type, and primitiveTypes() and the
// gatherers' declarations below are expanded from it.
#pragma once

#include "core/math.h"
#include "scene/scene.h"
#include "shared/types.h"

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace wt {

/// A typed primitive id (WT_PRIM_TYPE_SHIFT): type and index.
constexpr std::uint32_t primId(std::uint32_t type, std::uint32_t index) {
  return (type << WT_PRIM_TYPE_SHIFT) | (index & WT_PRIM_INDEX_MASK);
}
constexpr std::uint32_t primType(std::uint32_t id) { return id >> WT_PRIM_TYPE_SHIFT; }
constexpr std::uint32_t primIndex(std::uint32_t id) { return id & WT_PRIM_INDEX_MASK; }

struct PrimitiveRows;

/// A geometry type beside triangles, as the host knows it.
struct PrimitiveType {
  std::uint32_t id;    ///< WT_PRIM_*
  const char* name;    ///< plural, for tables ("spheres")
  const char* define;  ///< the kernels' switch that compiles it in ("WT_HAS_SPHERES", kernelDefines)
  const char* feature;  ///< its name in the feature set ("spheres", featureNames)
  /// Its boxes, typed ids and rows from the scene; nothing for instances,
  /// which gatherPrimitives lays out from the geometries SceneBuffers stores once.
  void (*gather)(const Scene&, PrimitiveRows&);
  /// The surface area of gathered primitive `index` (a typed id's index),
  /// for primitiveScale; NaN (not counted) for instances, whose copies count as their primitives.
  double (*area)(const Scene&, const PrimitiveRows&, std::uint32_t index);
};

/// Every type beside triangles, in the order gatherPrimitives lays them out.
std::span<const PrimitiveType> primitiveTypes();

/// The type's name in plural, for tables ("triangles", "spheres"); "" for none.
const char* primTypeName(std::uint32_t type);

struct PrimitiveRows {
  std::vector<Aabb> bounds;                         ///< per primitive, world
  std::vector<std::uint32_t> ids;                   ///< per primitive (as bounds): its typed id
  std::vector<WtVec4> data;                         ///< prim_data
  std::vector<std::array<std::uint32_t, 4>> info;   ///< prim_info; x = material
  std::array<std::uint32_t, WT_PRIM_TYPES> dataFirst{};  ///< per type: its first prim_data row
  std::array<std::uint32_t, WT_PRIM_TYPES> infoFirst{};  ///< per type: its first prim_info row
  std::array<std::size_t, WT_PRIM_TYPES> count{};        ///< per type: primitives in the scene (kept or not)
  std::size_t skipped = 0;  ///< primitives left out (degenerate: zero size, non-finite)
  /// gatherCurves: per Scene::curves entry its first kept segment's index, then the end (curves + 1 entries)
  std::vector<std::uint32_t> curveSegments;
  /// gatherSdfGrids: per grid its first brick's index, then the end (grids + 1 entries)
  std::vector<std::uint32_t> sdfBricks;
  /// gatherDisplaced: per mesh its first kept base triangle's index, then the end (meshes + 1 entries)
  std::vector<std::uint32_t> displacedTriangles;
};

/// Every listed type's gatherer and area (kernels/geometry/types.def), each
/// defined in its host/geometry/<type>.cpp; documented below where a type says more.
#define WT_GEOMETRY_DECLARE(TAG, ID, NAME, FEATURE, SWITCH, GATHER, AREA) \
  void GATHER(const Scene& scene, PrimitiveRows& rows);                   \
  double AREA(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index);
WT_GEOMETRY_TYPES(WT_GEOMETRY_DECLARE)
#undef WT_GEOMETRY_DECLARE

/// Whether a sphere can be drawn: a finite centre and a finite radius > 0.
/// The others are left out of the BVH and of the light list alike.
bool sphereUsable(const Sphere& sphere);

/// Spheres (WT_PRIM_SPHERE): one data row (center, radius) and one info row
/// (material) per sphere, by scene index; radius <= 0 or a non-finite value
/// leaves the sphere out.
void gatherSpheres(const Scene& scene, PrimitiveRows& rows);
/// A gathered sphere's area, 4 pi r^2.
double sphereArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index);

/// B-spline pieces are subdivided until each one's control points lie within
/// this fraction of its smallest radius of the straight segment that
/// replaces it (a bound on how far the traced surface strays from the spline's).
constexpr double kCurveFlatness = 0.05;
/// A B-spline segment is cut into at most 2^kCurveMaxDepth linear pieces.
constexpr int kCurveMaxDepth = 10;

/// Curves (WT_PRIM_CURVE) as linear segments, B-splines subdivided first
/// (kCurveFlatness): two data rows (the joints, with the neighbours' signs,
/// kernels/geometry/curve.cl) and one info row (material, curve, u at each
/// end) per segment, curve by curve; a typed id is the segment's index in
/// that order. A point with a non-finite coordinate or a radius that is
/// negative or not finite breaks its curve there (the segments that use it
/// are left out); consecutive points at one position are merged (the larger
/// radius kept); a segment of radius 0 at both ends is left out. count: the
/// segments, kept or not.
void gatherCurves(const Scene& scene, PrimitiveRows& rows);

/// A curve segment as gatherCurves wrote it.
struct CurveSegment {
  glm::vec4 p0{0.0f}, p1{0.0f};      ///< the joints: xyz world, w radius (>= 0)
  bool left = false, right = false;  ///< the curve goes on past p0, past p1 (segments index - 1, index + 1)
  std::uint32_t material = 0;
  std::uint32_t curve = 0;           ///< index into Scene::curves
  float u0 = 0.0f, u1 = 0.0f;        ///< the curve's parameter at p0 and p1 (0 at its root, 1 at its tip)
};
/// Segment `index` (a WT_PRIM_CURVE typed id's index) of gathered rows.
CurveSegment curveSegment(const PrimitiveRows& rows, std::uint32_t index);
/// A gathered segment's area: its round cone's side, pi (r0 + r1) times the slant length.
double curveSegmentArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index);

/// curve_surface (kernels/geometry/curve.cl) on the host: where ray (o, d)
/// meets the segment at t, reprojected onto its hull, with its rounding
/// error bound; *normal is the outward unit normal.
glm::vec3 curvePoint(const CurveSegment& segment, glm::vec3 o, glm::vec3 d, float t, glm::vec3* error,
                     glm::vec3* normal);

/// Whether an SDF grid is stored sparse: as it says, else by size (kSdfSparseAboveCells).
bool sdfGridSparse(const SdfGrid& grid);
/// Whether an SDF grid can be drawn: 1 .. kSdfMaxCells cells per axis, one
/// value per corner, a finite invertible placement. The others are left out.
bool sdfGridUsable(const SdfGrid& grid);

/// SDF grids (WT_PRIM_SDF_GRID): WT_SDF_GRID_ROWS data rows per grid, then
/// the values (a dense grid's corners once; a sparse grid's bricks'
/// (WT_SDF_BRICK + 1)^3 corners each); WT_SDF_INFO_ROWS info rows per
/// brick (its row and its cells' crossing mask); one primitive per brick of
/// WT_SDF_BRICK^3 cells that the surface crosses (a cell whose corners all
/// lie on one side holds no surface: the interpolant is their convex
/// combination), boxed around those cells, grid by grid, bricks x fastest.
/// count: the bricks kept.
void gatherSdfGrids(const Scene& scene, PrimitiveRows& rows);
/// A grid for gatherSdfGridList: placed by `latticeToScene` in place of its
/// own; `drawn` false writes its rows but none of its bricks or values (a
/// copy stored once as an instance keeps its index).
struct SdfGridRef {
  const SdfGrid* grid = nullptr;
  glm::dmat4 latticeToScene{1.0};
  bool drawn = true;
};
/// gatherSdfGrids over a list of grids: a brick's grid index is its list index.
void gatherSdfGridList(std::span<const SdfGridRef> grids, PrimitiveRows& rows);
/// A gathered brick's surface area, estimated as its crossed cells times a
/// cell's mean face area (the light list's weight for an emitting brick).
double sdfBrickArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index);
/// A grid cell's mean face area: its volume to the power 2/3.
double sdfCellArea(const SdfGrid& grid);

/// sdf_surface (kernels/geometry/sdf_grid.cl) on the host: where ray (o, d)
/// crossed brick `index` (a WT_PRIM_SDF_GRID typed id's index) at t in
/// brick-local cell `cell` (the hit's first parameter, RayHit::b1), o + t d,
/// with its error bound; *normal is the interpolant's unit gradient (zero
/// where it vanishes).
glm::vec3 sdfGridPoint(const PrimitiveRows& rows, std::uint32_t index, glm::vec3 o, glm::vec3 d, float t, float cell,
                       glm::vec3* error, glm::vec3* normal);

/// A displaced mesh's level L (2^L micro-edges per base edge): its own
/// when it gives one, else the least with micro-edges of at most one texel
/// along either axis of the map on the longest base edge, capped at
/// WT_DISP_MAX_LEVEL.
std::uint32_t displacedLevel(const DisplacedMesh& mesh);
/// Whether a displaced mesh can be drawn: one normal and uv per position, a
/// map of mapWidth x mapHeight (1 .. 65536 each) values, finite scale and
/// offset, a level of at most WT_DISP_MAX_LEVEL. The others are left out.
bool displacedMeshUsable(const DisplacedMesh& mesh);

/// Displaced meshes (WT_PRIM_DISPLACED): WT_DISP_MESH_ROWS data rows per
/// mesh, WT_DISP_VERTEX_ROWS per vertex, then each base triangle's boxes
/// (its own and its sub-triangles' to level D, eight bits a coordinate
/// relative to the parent's box; shared/types.h), then each map's texels
/// (NaN written as 0); WT_DISP_INFO_ROWS info rows per base triangle
/// ((material, mesh row, boxes' row), corners' rows, index), one primitive
/// per base triangle boxed around its micro-triangles. A triangle with a
/// corner out of range or not finite is left out. count: the base
/// triangles kept.
void gatherDisplaced(const Scene& scene, PrimitiveRows& rows);
/// gatherDisplaced with boxes stored to level min(L - 1, maxDepth,
/// WT_DISP_MAX_DEPTH) only: tests reach the levels walked untested below
/// the stored ones at small L. The base triangles' boxes are built on
/// `threads` threads (0: every hardware thread), the same rows on any number.
void gatherDisplacedTo(const Scene& scene, PrimitiveRows& rows, std::uint32_t maxDepth, int threads = 0);
/// A mesh for gatherDisplacedList; `drawn` false writes its header rows but
/// none of its vertices, triangles or map (a copy stored once as an instance
/// keeps its index).
struct DisplacedRef {
  const DisplacedMesh* mesh = nullptr;
  bool drawn = true;
};
/// gatherDisplacedTo over a list of meshes: a base triangle's mesh index is its list index.
void gatherDisplacedList(std::span<const DisplacedRef> meshes, PrimitiveRows& rows, std::uint32_t maxDepth,
                         int threads = 0);

/// Which mesh and base triangle a WT_PRIM_DISPLACED typed id's index is.
struct DisplacedTriangleRef {
  std::uint32_t mesh = 0, triangle = 0;
};
DisplacedTriangleRef displacedTriangle(const PrimitiveRows& rows, std::uint32_t index);
/// A gathered base triangle's flat area (the displaced surface's is
/// displacedArea, 4^L triangles' worth of work).
double displacedBaseArea(const Scene& scene, const PrimitiveRows& rows, std::uint32_t index);

/// displaced_surface (kernels/geometry/displaced.cl) on the host: the
/// point of base triangle `triangle` at lattice point (li, lj) (the hit's
/// parameters, RayHit::b1 and b2) from its micro-triangle, with its error
/// bound; *normal the micro-triangle's unit normal on the winding's side;
/// *shading (if given) the displaced surface's unit normal.
glm::vec3 displacedPoint(const DisplacedMesh& mesh, std::uint32_t triangle, float li, float lj, glm::vec3* error,
                         glm::vec3* normal, glm::vec3* shading = nullptr);

/// Micro-vertex (i, j) of base triangle `triangle` cut `perEdge` times per
/// edge (weights (perEdge - i - j, i, j) / perEdge on its corners), as the
/// kernel computes it for perEdge = 2^L.
glm::vec3 displacedVertex(const DisplacedMesh& mesh, std::uint32_t triangle, int perEdge, int i, int j);

/// The displaced surface's area over base triangle `triangle`: its 4^L
/// micro-triangles' areas summed (what light sampling spreads its samples over).
double displacedArea(const DisplacedMesh& mesh, std::uint32_t triangle);

/// Pre-tessellation, for comparison only: every displaced mesh turned into
/// triangles, perEdge^2 per base triangle (the kernel's surface exactly
/// when perEdge = 2^L), with the displaced surface's normals at the
/// vertices; Scene::displacedMeshes is emptied. Returns the triangles made.
std::size_t tessellateDisplaced(Scene& scene, int perEdge);

/// A placed copy of a geometry stored once (WT_PRIM_INSTANCE,
/// kernels/geometry/instance.cl), as SceneBuffers laid it out.
struct InstanceDesc {
  glm::dmat4 objectToScene{1.0};  ///< the geometry's object space -> scene space, double
  std::uint32_t root = 0;         ///< the geometry's root node in SceneBuffers::nodes (primNodes for primitives)
  bool primitives = false;        ///< a geometry of spheres, curves, SDF grids or displaced meshes (WT_INSTANCE_PRIMITIVES)
  std::array<Aabb, 4> rootBoxes;  ///< the root's child boxes, object space (empty ones unused)
};

/// Instances (WT_PRIM_INSTANCE): WT_INSTANCE_ROWS data rows each
/// (object-from-scene and scene-from-object, float 3x4 both, rounded from
/// the double matrix and its double inverse) and one info row (root,
/// WT_INSTANCE_MIRRORED); the box is the root's child boxes moved to scene
/// space, corner by corner, in double, widened past float rounding.
void gatherInstances(std::span<const InstanceDesc> instances, PrimitiveRows& rows);

/// Every type's rows; instances as given (SceneBuffers builds their geometries first).
PrimitiveRows gatherPrimitives(const Scene& scene, std::span<const InstanceDesc> instances = {});

/// A scene's length scale for the traversal choice (chooseTraversal): the
/// square root of its surfaces' mean area per primitive, over the triangles
/// and every gathered primitive (`rows`: gatherPrimitives' flat rows, a copy
/// of an instance counted as its own primitives, as rays meet it); with no
/// area, the bounds' diagonal over the square root of the primitive count.
double primitiveScale(const Scene& scene, const PrimitiveRows& rows);

}  // namespace wt
