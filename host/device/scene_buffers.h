// The scene on the device: BVH nodes and triangles in leaf order, vertex
// attributes and materials, uploaded once and shared by every stage.
#pragma once

#include "bvh/bvh4.h"
#include "bvh/lbvh.h"
#include "device/context.h"
#include "geometry/primitives.h"
#include "scene/scene.h"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

namespace wt {

/// The scene's placed copies (Scene::instances) as BVH instances over the
/// BVH's input, where input primitive i is scene triangle bvhToScene[i]
/// (ascending). A copy that lost a triangle (zero area, non-finite corners)
/// is left out: its triangles are built as the others are.
std::vector<BvhInstance> bvhInstances(const Scene& scene, std::span<const std::uint32_t> bvhToScene);

/// Leaves of the primitive BVH hold at most this many typed ids.
constexpr int kPrimitiveLeafSize = 4;

/// The BVH over the primitives other than triangles, as uploaded: the 4-wide
/// tree and the typed ids in its leaf order.
struct PrimitiveTree {
  Bvh4 bvh4;
  std::vector<std::uint32_t> refs;
  std::vector<WtVec4> joints;  ///< WT_LEAF_JOINT_ROWS per ref (WtGeometry::leaf_joints)
  double seconds = 0.0;  ///< wall time of the build and collapse
};
/// Every primitive, curve segments included, is in exactly one leaf.
PrimitiveTree buildPrimitiveTree(const PrimitiveRows& rows, const BvhBuildOptions& options);

/// Whether scene triangle `tri` can have a hole under its material's alpha
/// mode (kernels/materials/alpha.cl): MASK where its coverage (the alpha
/// factor, COLOR_0's alpha at its corners, the base colour texture's alpha)
/// can fall below the cutoff, BLEND where it can fall below 1. A texture
/// whose alpha is 1 everywhere (a JPEG, an opaque PNG) counts as none:
/// `opaqueTexture` answers for texture indices (textureIsOpaque).
bool triangleMayHaveHoles(const Scene& scene, std::uint32_t tri, const std::vector<std::int8_t>& opaqueTexture);

/// Whether shadow rays may cross material `m` (WtMaterial::shadow_pass): a
/// metallic-roughness thin wall (no KHR_materials_volume) that transmits
/// and is smooth everywhere (roughness below WT_PBR_MIN_ROUGHNESS, no
/// anisotropy; textures only scale these factors down), so light crosses it
/// straight. Its tint (COLOR_0, textures) is read where a shadow ray meets
/// it. Such a wall has no vertex of its own that could sample a light
/// behind it: shadow rays through it are the only way NEE finds that light
/// (kernels/connect.cl).
bool thinShadowPass(const WtMaterial& m);

/// Whether texture `texture` of the scene's TextureSet is opaque: its
/// finest level's alpha is 1 at every texel.
bool textureIsOpaque(const TextureSet& textures, std::uint32_t texture);

/// "off", "on", "auto" (Instancing, host/bvh/lbvh.h).
std::optional<Instancing> parseInstancing(std::string_view name);

struct InstancedPrimitives;

/// A read-only buffer of `bytes` at `data` (one dummy word where empty). With
/// `inPlace` on a CPU device it is that memory itself (CL_MEM_USE_HOST_PTR):
/// no copy and no second set of pages to fault in, so the memory must then
/// outlive the buffer unchanged; elsewhere the bytes are copied.
cl::Buffer readOnlyBuffer(Context& context, const void* data, std::size_t bytes, bool inPlace);

class SceneBuffers {
 public:
  /// A leaf-order slot no triangle fills (the padding before a geometry
  /// stored once, which starts at a block boundary).
  static constexpr std::uint32_t kNoTriangle = 0xffffffffu;
  /// Geometries with fewer triangles a copy stay flattened with
  /// Instancing::On: the instance's transform and second traversal cost more
  /// than the few nodes and blocks it saves.
  static constexpr std::size_t kMinInstanceTriangles = 64;
  /// Instancing::Auto stores geometries once when their flattened copies
  /// (beyond the first: kFlatBytesPerTriangle of nodes and triangles a
  /// triangle, flatBytesPerPrimitive an item of the other types) would take
  /// more than the device's global memory cache, or than
  /// kInstancingAutoBytes where the device reports none (instancingPays).
  static constexpr std::size_t kInstancingAutoBytes = std::size_t(32) << 20;
  static constexpr std::size_t kFlatBytesPerTriangle = 64;
  static bool instancingPays(double copiedBytes, std::uint64_t cacheBytes) {
    return copiedBytes > double(cacheBytes > 0 ? cacheBytes : kInstancingAutoBytes);
  }
  /// Per type, the device bytes one flattened item of `rows` takes: the
  /// type's gathered data and info rows (an SDF brick's values, a displaced
  /// mesh's boxes and map) over its items, plus its share of the primitive
  /// tree (refs, leaf joints, a node per two leaves); 0 for a type with none.
  static std::array<double, WT_PRIM_TYPES> flatBytesPerPrimitive(const PrimitiveRows& rows);

  /// Build the BVH over the scene's triangles (but degenerate ones), collapse
  /// it to the 4-wide layout the kernels traverse, and upload.
  SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options = {});

  /// WtBvh4Node[nodeCount] (one dummy node when empty); kernels declare it
  /// WtBvhNode*. The scene's tree from node 0, then each instanced
  /// geometry's (InstanceDesc::root).
  cl::Buffer nodes;
  /// The triangles in leaf order, world space (an instanced geometry's in its
  /// object space, after the others from a block boundary), in blocks of four
  /// (WT_TRIANGLE_BLOCK, shared/types.h): float4[9 * blocks], per block and
  /// corner k rows x, y, z of the four triangles
  cl::Buffer triVerts;
  /// uint4[triangles], leaf order: the triangle's three vertex indices (for
  /// the per-vertex normals) and its material
  cl::Buffer triangleInfo;
  cl::Buffer normals;     ///< float4 per vertex
  cl::Buffer materials;   ///< WtMaterial[]: kernelMaterials()
  /// The materials as uploaded: the scene's, each exactly Lambertian one as
  /// the Lambertian model unless BvhBuildOptions::lambertianForms is off.
  const std::vector<WtMaterial>& kernelMaterials() const { return m_kernelMaterials; }

  /// What materials/textured.cl reads (WT_SURFACE_PARAMS), each one dummy
  /// entry where the scene has none: per vertex TEXCOORD_0 and _1 (float4),
  /// COLOR_0 (float4) and tangents (float4); the materials' texture slots
  /// (WtTextureRef, WT_TEXTURE_SLOTS per material) and the textures
  /// (shared/textures.h).
  cl::Buffer vertexUv, vertexColor, vertexTangent, materialTextures, textures, textureLevels, texels;
  std::size_t textureBytes = 0;  ///< textures, levels and texels on the device
  double textureUploadSeconds = 0.0;
  /// Whether a material reads a texture / the vertices have COLOR_0 (KernelFeatures).
  bool hasTextures() const { return m_hasTextures; }
  bool hasVertexColors() const { return m_hasVertexColors; }

  /// One bit per leaf-order triangle (bit t % 32 of word t / 32): set where
  /// the triangle may have a hole (triangleMayHaveHoles), so that traversal
  /// reads the material of those triangles' hits only. A bit per triangle
  /// rather than a flag in the material: the material is a second dependent
  /// load (tri_info, then 80 bytes) on every hit, the bits a 1 MiB-per-8 M
  /// triangles array whose word for a block of four sits with its
  /// neighbours' in one cache line. One dummy word when no triangle has one.
  cl::Buffer alphaBits;
  /// WtAlphaMaterial per material (shared/alpha.h): what the test reads of
  /// it; one dummy entry when no triangle has a hole.
  cl::Buffer alphaMaterials;
  /// Leaf-order triangles whose bit is set: an instanced geometry's once.
  std::size_t alphaTriangles() const { return m_alphaTriangles; }
  /// Whether the alpha test is needed at all (KernelFeatures::alpha).
  bool hasAlpha() const { return m_alphaTriangles > 0; }
  std::uint32_t nodeCount = 0;
  std::size_t uploadedBytes = 0;  ///< nodes + triangle data (tri_verts, tri_info)

  /// The primitives other than triangles (kernels/geometry/geometry.cl): their
  /// BVH (WtBvh4Node, leaves of up to 4 typed ids), the typed ids in leaf
  /// order, and each type's rows; `geometry` says where each type's rows start.
  cl::Buffer primNodes, primRefs, primData, primInfo;
  WtGeometry geometry{};
  std::size_t primitiveBytes = 0;  ///< primNodes + primRefs + primData + primInfo
  /// Primitives of `type` (WT_PRIM_*) the scene has, left out or not.
  std::size_t primitiveCount(std::uint32_t type) const { return m_primitiveCount[type]; }
  /// The scene's primitiveScale (every type, copies counted flat), for chooseTraversal.
  double primitiveScale() const { return m_primitiveScale; }
  /// Which types beside triangles the scene has (KernelFeatures::primitives).
  std::array<bool, WT_PRIM_TYPES> primitiveTypesPresent() const {
    std::array<bool, WT_PRIM_TYPES> present{};
    for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type)
      present[type] = type != WT_PRIM_TRIANGLE && m_primitiveCount[type] > 0;
    return present;
  }
  /// A displaced base triangle or SDF brick whose material emits, as
  /// gathered: what the light list weighs it by (render/light_list.cpp).
  struct SurfaceEmitter {
    std::uint32_t id;       ///< typed id (WT_PRIM_DISPLACED or WT_PRIM_SDF_GRID), as on the device
    std::uint32_t source;   ///< its Scene::displacedMeshes or Scene::sdfGrids entry
    std::uint32_t element;  ///< displaced: the base triangle's index in its mesh; SDF: the brick's cells the surface crosses
  };
  const std::vector<SurfaceEmitter>& surfaceEmitters() const { return m_surfaceEmitters; }
  /// Non-triangle primitives left out of their BVH (zero size, non-finite).
  std::size_t skippedPrimitives() const { return m_skippedPrimitives; }
  const Bvh4Stats& primitiveBvhStats() const { return m_primStats; }
  double primitiveBuildSeconds() const { return m_primitiveBuildSeconds; }

  /// The build of the binary tree the 4-wide tree was collapsed from.
  const BvhBuildStats& bvhStats() const { return m_bvhStats; }
  const Bvh4Stats& bvh4Stats() const { return m_bvh4Stats; }
  /// Leaves that take one more four-lane test than their size needs
  /// (LeafPacking::misfits).
  std::size_t leafMisfits() const { return m_leafMisfits; }
  /// Leaf order (the kernels' triangle index) -> the scene's triangle index;
  /// for an instanced geometry's triangle, its source copy's; kNoTriangle
  /// for padding.
  const std::vector<std::uint32_t>& leafOrder() const { return m_leafToScene; }
  /// The scene triangle of leaf-order triangle `leafIndex` on instance
  /// `instance` (a typed id, as the kernels' hit_instance), or of the flat
  /// triangle for 0xffffffff.
  std::uint32_t sceneTriangle(std::uint32_t leafIndex, std::uint32_t instance = 0xffffffffu) const;
  /// The scene's triangle index -> its leaf-order index (an instanced copy's:
  /// its geometry's triangle); 0xffffffff for one left out of the BVH or out
  /// of range.
  std::uint32_t leafTriangle(std::uint32_t sceneIndex) const {
    return sceneIndex < m_sceneToLeaf.size() ? m_sceneToLeaf[sceneIndex] : 0xffffffffu;
  }
  /// The instance (typed id) the scene's triangle is part of; 0xffffffff for
  /// a flat one.
  std::uint32_t triangleInstance(std::uint32_t sceneIndex) const {
    return sceneIndex < m_sceneToInstance.size() ? m_sceneToInstance[sceneIndex] : 0xffffffffu;
  }
  /// Instances (WT_PRIM_INSTANCE primitives); 0 unless Instancing put some in.
  std::size_t instanceCount() const { return m_instanceOffset.size(); }
  /// Whether instance `instance` (typed id) mirrors its geometry: the copy's
  /// corners 1 and 2 are swapped against its geometry's (barycentrics b1, b2
  /// trade places).
  bool instanceMirrored(std::uint32_t instance) const { return m_instanceMirrored[primIndex(instance)]; }
  /// A sphere's or curve segment's typed id in the flattened scene (spheres
  /// by scene index, segments as gatherCurves numbers them) as the device
  /// knows it: its typed id there and the instance it is on (0xffffffff
  /// for none). Other ids as they are.
  std::pair<std::uint32_t, std::uint32_t> devicePrimitive(std::uint32_t sceneId) const;
  /// The reverse: the flattened scene's typed id of device primitive `deviceId` hit on `instance`.
  std::uint32_t scenePrimitive(std::uint32_t deviceId, std::uint32_t instance) const;
  /// Whether spheres, curves, SDF grids or displaced meshes are stored once (their device ids differ from the flattened scene's).
  bool primitivesInstanced() const { return !m_primInstanceFirst.empty(); }
  /// Scene triangles in instanced copies (each stored once per geometry).
  std::size_t instancedTriangles() const { return m_instancedTriangles; }
  /// What the triangles take on the device: uploadedBytes, and with
  /// instances primitiveBytes (their rows and tree; a scene with spheres too
  /// counts theirs here as well).
  std::size_t triangleBytes() const { return uploadedBytes + (instanceCount() > 0 ? primitiveBytes : 0); }
  /// Everything the scene's geometry takes on the device: uploadedBytes,
  /// primitiveBytes (with the instances' rows), normals and materials.
  std::size_t geometryBytes() const { return uploadedBytes + primitiveBytes + m_attributeBytes; }
  /// Triangles left out of the BVH (zero area or non-finite vertices).
  std::size_t skippedTriangles() const { return m_skippedTriangles; }
  /// Triangles in triVerts and triangleInfo (leaf order; 0: both hold one dummy entry).
  std::size_t storedTriangles() const { return m_storedTriangles; }
  /// Traversal stack entries the BVH needs, for KernelFeatures::bvhStackSize.
  int stackSize() const;

 private:
  void uploadPrimitives(Context& context, const Scene& scene, const BvhBuildOptions& options,
                        std::vector<InstanceDesc> instances);
  /// The gathered rows with the copies in `geometries` stored once: the
  /// flat items renumbered, each geometry's items in object space after
  /// them, an instance per copy appended to `instances`; `trees` gets each
  /// geometry's own tree.
  PrimitiveRows layoutPrimitiveInstances(const Scene& scene, const PrimitiveRows& full,
                                         std::vector<InstancedPrimitives>& geometries, const BvhBuildOptions& options,
                                         std::vector<InstanceDesc>& instances, std::vector<PrimitiveTree>& trees);

  void uploadSurface(Context& context, const Scene& scene);

  void uploadAlpha(Context& context, const Scene& scene);

  bool m_hasTextures = false, m_hasVertexColors = false;
  std::vector<WtMaterial> m_kernelMaterials;
  bool m_allSurfaceAttributes = false;  ///< BvhBuildOptions::allSurfaceAttributes
  bool m_texelsInPlace = false;         ///< BvhBuildOptions::texelsInPlace
  std::size_t m_alphaTriangles = 0;
  BvhBuildStats m_bvhStats;
  Bvh4Stats m_bvh4Stats;
  std::size_t m_leafMisfits = 0;
  std::vector<std::uint32_t> m_leafToScene;
  std::vector<std::uint32_t> m_sceneToLeaf;
  std::size_t m_skippedTriangles = 0;
  std::size_t m_storedTriangles = 0;
  Bvh4Stats m_primStats;
  std::array<std::size_t, WT_PRIM_TYPES> m_primitiveCount{};
  double m_primitiveScale = 1.0;
  std::size_t m_skippedPrimitives = 0;
  double m_primitiveBuildSeconds = 0.0;
  std::vector<std::uint32_t> m_sceneToInstance;  ///< empty without instances
  std::vector<std::int64_t> m_instanceOffset;    ///< per instance: its first scene triangle less its source copy's
  std::vector<bool> m_instanceMirrored;
  std::size_t m_instancedTriangles = 0;
  std::vector<SurfaceEmitter> m_surfaceEmitters;
  int m_blasStackEntries = 0;
  /// Spheres and curves stored once, per type: the flattened scene's item
  /// -> (device index, instance typed id or 0xffffffff), and device index ->
  /// the flattened scene's item for the flat ones; empty without them.
  std::array<std::vector<std::pair<std::uint32_t, std::uint32_t>>, WT_PRIM_TYPES> m_primDevice;
  std::array<std::vector<std::uint32_t>, WT_PRIM_TYPES> m_primScene;
  std::vector<std::int64_t> m_primInstanceFirst;  ///< per instance: its copy's first item less its geometry's device index
  int m_primitiveInstanceStack = 0;               ///< stack entries the primitive geometries' trees need
  std::size_t m_attributeBytes = 0;
};

}  // namespace wt
