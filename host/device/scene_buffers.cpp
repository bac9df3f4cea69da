#include "device/scene_buffers.h"

#include "bvh/builders.h"
#include "shared/lights.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <stdexcept>
#include <string>

namespace wt {
namespace {

template <typename T>
cl::Buffer upload(Context& context, const std::vector<T>& data, std::size_t& bytes) {
  // OpenCL rejects zero-sized buffers: keep one element where a scene has none.
  std::size_t size = std::max<std::size_t>(data.size(), 1) * sizeof(T);
  cl::Buffer buffer(context.context(), CL_MEM_READ_ONLY, size);
  if (!data.empty())
    context.queue().enqueueWriteBuffer(buffer, CL_TRUE, 0, data.size() * sizeof(T), data.data());
  bytes += data.size() * sizeof(T);
  return buffer;
}

}  // namespace

SceneBuffers::SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options) {
  // the tagged vertex index of tri_verts (shared/types.h) has room for these
  if (scene.positions.size() > WT_MAX_VERTICES)
    throw std::length_error("scene has " + std::to_string(scene.positions.size()) + " vertices; at most " +
                            std::to_string(WT_MAX_VERTICES) + " are supported");
  // Zero-area and non-finite triangles never enter the BVH: they cannot be
  // hit meaningfully, and in float a ray through a collinear triangle can
  // still produce a spurious hit.
  std::vector<Aabb> bounds;
  bounds.reserve(scene.triangles.size());
  m_bvhToScene.reserve(scene.triangles.size());
  for (std::size_t i = 0; i < scene.triangles.size(); ++i) {
    const WtTriangle& t = scene.triangles[i];
    auto pos = [&](std::uint32_t v) {
      return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z);
    };
    glm::vec3 p0 = pos(t.v0), p1 = pos(t.v1), p2 = pos(t.v2);
    glm::vec3 n = glm::cross(p1 - p0, p2 - p0);
    auto finite3 = [](glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    bool finite = finite3(p0) && finite3(p1) && finite3(p2);
    if (!finite || glm::dot(n, n) == 0.0f) {
      ++m_skippedTriangles;
      continue;
    }
    bounds.push_back(scene.triangleBounds(std::uint32_t(i)));
    m_bvhToScene.push_back(std::uint32_t(i));
  }
  m_bvh = buildBvh(bounds, binaryBuildOptions(options, bounds.size()));
  Bvh4 bvh4 = collapseToBvh4(m_bvh, bvh4Options(options));
  m_bvh4Stats = bvh4.stats;
  nodeCount = std::uint32_t(bvh4.nodes.size());
  // From here on primIndices address the scene's triangles directly.
  for (std::uint32_t& p : m_bvh.primIndices) p = m_bvhToScene[p];
  m_sceneToLeaf.assign(scene.triangles.size(), 0xffffffffu);
  for (std::size_t leaf = 0; leaf < m_bvh.primIndices.size(); ++leaf) m_sceneToLeaf[m_bvh.primIndices[leaf]] = std::uint32_t(leaf);

  // Reorder triangles to leaf order, so a leaf addresses a contiguous range.
  // Each corner's w carries its vertex index, tagged (WT_VERTEX_TAG; shading
  // reads the normals by it), so a triangle costs 3 x 16 bytes of positions
  // and 4 of material.
  std::vector<WtVec4> verts(3 * m_bvh.primIndices.size());
  std::vector<std::uint32_t> materialOf(m_bvh.primIndices.size());
  for (std::size_t i = 0; i < materialOf.size(); ++i) {
    const WtTriangle& t = scene.triangles[m_bvh.primIndices[i]];
    const std::uint32_t corner[3] = {t.v0, t.v1, t.v2};
    for (int k = 0; k < 3; ++k) {
      WtVec4 v = scene.positions[corner[k]];
      const std::uint32_t tagged = corner[k] | WT_VERTEX_TAG;
      std::memcpy(&v.w, &tagged, sizeof v.w);
      verts[3 * i + k] = v;
    }
    materialOf[i] = t.material;
  }
  std::size_t bytes = 0;
  nodes = upload(context, bvh4.nodes, bytes);
  triVerts = upload(context, verts, bytes);
  triangleMaterials = upload(context, materialOf, bytes);
  uploadedBytes = bytes;
  std::size_t attributeBytes = 0;
  normals = upload(context, scene.normals, attributeBytes);
  materials = upload(context, scene.materials, attributeBytes);
}

int SceneBuffers::stackSize() const {
  int needed = bvh4StackEntries(m_bvh4Stats);
  return std::max(32, (needed + 31) / 32 * 32);
}

}  // namespace wt

// One definition, two compilers: the kernels see these exact sizes.
static_assert(sizeof(WtVec4) == 16);
static_assert(sizeof(WtTriangle) == 16);
static_assert(sizeof(WtBvhNode) == 32);
static_assert(offsetof(WtBvhNode, hi_x) == 16);
static_assert(sizeof(WtBvh4Node) == 128);
static_assert(offsetof(WtBvh4Node, lo_y) == 32 && offsetof(WtBvh4Node, lo_z) == 64);
// bvh_ray_planes (kernels/bvh.cl) addresses the planes by these float offsets
static_assert(offsetof(WtBvh4Node, hi_x) == 16 && offsetof(WtBvh4Node, hi_y) == 48 && offsetof(WtBvh4Node, hi_z) == 80);
static_assert(offsetof(WtBvh4Node, child) == 96 && offsetof(WtBvh4Node, count) == 112);
static_assert(sizeof(WtMaterial) == 64);
static_assert(sizeof(WtCamera) == 64);
static_assert(sizeof(WtFrameParams) == 64);
static_assert(sizeof(WtLight) == 64);
static_assert(sizeof(WtAliasSlot) == 16);
static_assert(sizeof(WtLightNode) == 64);
