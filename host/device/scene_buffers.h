// The scene on the device: BVH nodes and triangles in leaf order, vertex
// attributes and materials, uploaded once and shared by every stage.
#pragma once

#include "bvh/bvh4.h"
#include "bvh/lbvh.h"
#include "device/context.h"
#include "scene/scene.h"

#include <cstdint>
#include <vector>

namespace wt {

class SceneBuffers {
 public:
  /// Build the BVH over the scene's triangles (but degenerate ones), collapse
  /// it to the 4-wide layout the kernels traverse, and upload.
  SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options = {});

  cl::Buffer nodes;       ///< WtBvh4Node[nodeCount] (one dummy node when empty); kernels declare it WtBvhNode*
  /// float4[3 * triangles], leaf order, world space; w of vertex k holds the
  /// bits of the triangle's vertex index v_k (for the per-vertex normals)
  cl::Buffer triVerts;
  cl::Buffer triangleMaterials;  ///< uint[triangles], leaf order: the triangle's material
  cl::Buffer normals;     ///< float4 per vertex
  cl::Buffer materials;   ///< WtMaterial[]
  std::uint32_t nodeCount = 0;
  std::size_t uploadedBytes = 0;  ///< nodes + triangle data

  /// The binary LBVH the 4-wide tree was collapsed from (its nodes are not uploaded).
  const Bvh& bvh() const { return m_bvh; }
  const Bvh4Stats& bvh4Stats() const { return m_bvh4Stats; }
  /// Leaf-order triangle index -> the scene's triangle index.
  std::uint32_t sceneTriangle(std::uint32_t leafIndex) const { return m_bvh.primIndices[leafIndex]; }
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
  Bvh m_bvh;  ///< primIndices hold scene triangle indices
  Bvh4Stats m_bvh4Stats;
  std::vector<std::uint32_t> m_bvhToScene;
  std::vector<std::uint32_t> m_sceneToLeaf;
  std::size_t m_skippedTriangles = 0;
};

}  // namespace wt
