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
#include <span>
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
  double seconds = 0.0;  ///< wall time of the build and collapse
};
PrimitiveTree buildPrimitiveTree(const PrimitiveRows& rows, const BvhBuildOptions& options);

class SceneBuffers {
 public:
  /// Build the BVH over the scene's triangles (but degenerate ones), collapse
  /// it to the 4-wide layout the kernels traverse, and upload.
  SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options = {});

  cl::Buffer nodes;       ///< WtBvh4Node[nodeCount] (one dummy node when empty); kernels declare it WtBvhNode*
  /// The triangles in leaf order, world space, in blocks of four
  /// (WT_TRIANGLE_BLOCK, shared/types.h): float4[9 * blocks], per block and
  /// corner k rows x, y, z of the four triangles
  cl::Buffer triVerts;
  /// uint4[triangles], leaf order: the triangle's three vertex indices (for
  /// the per-vertex normals) and its material
  cl::Buffer triangleInfo;
  cl::Buffer normals;     ///< float4 per vertex
  cl::Buffer materials;   ///< WtMaterial[]
  std::uint32_t nodeCount = 0;
  std::size_t uploadedBytes = 0;  ///< nodes + triangle data

  /// The primitives other than triangles (kernels/geometry/geometry.cl): their
  /// BVH (WtBvh4Node, leaves of up to 4 typed ids), the typed ids in leaf
  /// order, and each type's rows; `geometry` says where each type's rows start.
  cl::Buffer primNodes, primRefs, primData, primInfo;
  WtGeometry geometry{};
  std::size_t primitiveBytes = 0;  ///< primNodes + primRefs + primData + primInfo
  /// Set the kernel's WT_GEOMETRY_PARAMS, arguments first .. first + 4.
  void bindGeometry(cl::Kernel& kernel, int first) const;
  /// Primitives of `type` (WT_PRIM_*) the scene has, left out or not.
  std::size_t primitiveCount(std::uint32_t type) const { return m_primitiveCount[type]; }
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
  /// Leaf order (the kernels' triangle index) -> the scene's triangle index.
  const std::vector<std::uint32_t>& leafOrder() const { return m_leafToScene; }
  std::uint32_t sceneTriangle(std::uint32_t leafIndex) const { return m_leafToScene[leafIndex]; }
  /// The scene's triangle index -> its leaf-order index; 0xffffffff for one
  /// left out of the BVH or out of range.
  std::uint32_t leafTriangle(std::uint32_t sceneIndex) const {
    return sceneIndex < m_sceneToLeaf.size() ? m_sceneToLeaf[sceneIndex] : 0xffffffffu;
  }
  /// Triangles left out of the BVH (zero area or non-finite vertices).
  std::size_t skippedTriangles() const { return m_skippedTriangles; }
  /// Traversal stack entries the BVH needs, for KernelFeatures::bvhStackSize.
  int stackSize() const;

 private:
  void uploadPrimitives(Context& context, const Scene& scene, const BvhBuildOptions& options);

  BvhBuildStats m_bvhStats;
  Bvh4Stats m_bvh4Stats;
  std::size_t m_leafMisfits = 0;
  std::vector<std::uint32_t> m_leafToScene;
  std::vector<std::uint32_t> m_sceneToLeaf;
  std::size_t m_skippedTriangles = 0;
  Bvh4Stats m_primStats;
  std::array<std::size_t, WT_PRIM_TYPES> m_primitiveCount{};
  std::size_t m_skippedPrimitives = 0;
  double m_primitiveBuildSeconds = 0.0;
};

}  // namespace wt
