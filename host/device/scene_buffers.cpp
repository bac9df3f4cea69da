#include "device/scene_buffers.h"

#include "bvh/builders.h"
#include "shared/lights.h"

#include <algorithm>
#include <array>
#include <map>
#include <tuple>
#include <chrono>
#include <cmath>
#include <cstddef>

namespace wt {
namespace {

template <class Array>
cl::Buffer upload(Context& context, const Array& data, std::size_t& bytes) {
  using T = typename Array::value_type;
  // OpenCL rejects zero-sized buffers: keep one element where a scene has none.
  std::size_t size = std::max<std::size_t>(data.size(), 1) * sizeof(T);
  cl::Buffer buffer(context.context(), CL_MEM_READ_ONLY, size);
  if (!data.empty())
    context.queue().enqueueWriteBuffer(buffer, CL_TRUE, 0, data.size() * sizeof(T), data.data());
  bytes += data.size() * sizeof(T);
  return buffer;
}

}  // namespace

std::vector<BvhInstance> bvhInstances(const Scene& scene, std::span<const std::uint32_t> bvhToScene) {
  // A copy's triangles that enter the BVH are consecutive inputs (bvhToScene
  // is ascending). Copies that lost the same triangles (zero area in mesh
  // space, as at a sphere's poles) still share a geometry: the id is
  // renumbered by which of its triangles a copy kept. Should two patterns
  // ever share a hash, the tree stays correct (the builder refits every box
  // to the copy's own triangles), only less tight.
  std::vector<BvhInstance> out;
  out.reserve(scene.instances.size());
  std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint64_t>, std::uint32_t> ids;
  std::size_t at = 0;
  for (const GeometryInstance& copy : scene.instances) {
    const std::size_t end = std::size_t(copy.firstTriangle) + copy.triangleCount;
    if (end > scene.triangles.size()) continue;
    while (at < bvhToScene.size() && bvhToScene[at] < copy.firstTriangle) ++at;
    std::size_t last = at;
    std::uint64_t pattern = 0xcbf29ce484222325ull;  // FNV-1a over the kept triangles' local indices
    for (; last < bvhToScene.size() && bvhToScene[last] < end; ++last) {
      pattern ^= bvhToScene[last] - copy.firstTriangle;
      pattern *= 0x100000001b3ull;
    }
    const std::uint32_t kept = std::uint32_t(last - at);
    if (kept == 0) continue;
    const auto key = std::make_tuple(copy.geometry, kept, kept == copy.triangleCount ? 0 : pattern);
    const std::uint32_t id = ids.emplace(key, std::uint32_t(ids.size())).first->second;
    out.push_back({std::uint32_t(at), kept, id});
    at = last;
  }
  return out;
}

SceneBuffers::SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options) {
  // Zero-area and non-finite triangles never enter the BVH: they cannot be
  // hit meaningfully, and in float a ray through a collinear triangle can
  // still produce a spurious hit.
  std::vector<Aabb> bounds;
  std::vector<std::uint32_t> bvhToScene;
  bounds.reserve(scene.triangles.size());
  bvhToScene.reserve(scene.triangles.size());
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
    bvhToScene.push_back(std::uint32_t(i));
  }
  const Bvh bvh = buildBvh(bounds, binaryBuildOptions(options, bounds.size()), bvhInstances(scene, bvhToScene));
  m_bvhStats = bvh.stats;
  Bvh4 bvh4 = collapseToBvh4(bvh, bvh4Options(options));
  m_bvh4Stats = bvh4.stats;
  nodeCount = std::uint32_t(bvh4.nodes.size());
  // Leaves laid out in blocks of four (packLeavesIntoBlocks); from here on
  // the leaf order addresses the scene's triangles directly.
  const LeafPacking packing = packLeavesIntoBlocks(bvh4, bvh.primIndices.size());
  orderChildSlots(bvh4);  // after the packing, which lays the leaves out in slot order
  m_leafMisfits = packing.misfits;
  m_leafToScene.resize(packing.order.size());
  for (std::size_t i = 0; i < packing.order.size(); ++i) m_leafToScene[i] = bvhToScene[bvh.primIndices[packing.order[i]]];
  m_sceneToLeaf.assign(scene.triangles.size(), 0xffffffffu);
  for (std::size_t leaf = 0; leaf < m_leafToScene.size(); ++leaf) m_sceneToLeaf[m_leafToScene[leaf]] = std::uint32_t(leaf);

  // The triangles in leaf order, in blocks of four (WT_TRIANGLE_BLOCK): per
  // corner one row of x, of y and of z, 36 bytes a triangle; its vertex
  // indices (shading reads the normals by them) and material go to tri_info,
  // 16 bytes, which traversal never reads. Every lane is written below but
  // the last block's spare ones, which are zeroed (no leaf covers them): no
  // zero fill of the whole, 36 MB for 1 M triangles.
  constexpr std::size_t kBlockFloats = 4 * WT_TRIANGLE_BLOCK_ROWS;
  const std::size_t triangles = m_leafToScene.size();
  std::vector<float, UninitialisedAllocator<float>> blocks(kBlockFloats *
                                                           ((triangles + kTriangleBlock - 1) / kTriangleBlock));
  if (triangles % kTriangleBlock != 0) std::fill(blocks.end() - kBlockFloats, blocks.end(), 0.0f);
  std::vector<std::array<std::uint32_t, 4>, UninitialisedAllocator<std::array<std::uint32_t, 4>>> info(triangles);
  for (std::size_t i = 0; i < triangles; ++i) {
    const WtTriangle& t = scene.triangles[m_leafToScene[i]];
    const std::uint32_t corner[3] = {t.v0, t.v1, t.v2};
    float* lane = blocks.data() + kBlockFloats * (i / kTriangleBlock) + i % kTriangleBlock;
    for (int k = 0; k < 3; ++k) {
      const WtVec4& v = scene.positions[corner[k]];
      lane[12 * k + 0] = v.x;
      lane[12 * k + 4] = v.y;
      lane[12 * k + 8] = v.z;
    }
    info[i] = {t.v0, t.v1, t.v2, t.material};
  }
  std::size_t bytes = 0;
  nodes = upload(context, bvh4.nodes, bytes);
  triVerts = upload(context, blocks, bytes);
  triangleInfo = upload(context, info, bytes);
  uploadedBytes = bytes;
  std::size_t attributeBytes = 0;
  normals = upload(context, scene.normals, attributeBytes);
  materials = upload(context, scene.materials, attributeBytes);
  uploadPrimitives(context, scene, options);
}

PrimitiveTree buildPrimitiveTree(const PrimitiveRows& rows, const BvhBuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  // Each leaf entry is a typed id, tested one by one, so leaves stay small.
  BvhBuildOptions primOptions = options;
  primOptions.maxLeafSize = kPrimitiveLeafSize;
  const Bvh bvh = buildBvh(rows.bounds, binaryBuildOptions(primOptions, rows.bounds.size()));
  Bvh4Options collapse = bvh4Options(primOptions);
  collapse.nodeBytesPerPrimitive = 0.0;  // no triangle blocks to weigh the nodes against
  PrimitiveTree tree;
  tree.bvh4 = collapseToBvh4(bvh, collapse);
  orderChildSlots(tree.bvh4);
  tree.refs.resize(bvh.primIndices.size());
  for (std::size_t i = 0; i < tree.refs.size(); ++i) tree.refs[i] = rows.ids[bvh.primIndices[i]];
  tree.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tree;
}

void SceneBuffers::uploadPrimitives(Context& context, const Scene& scene, const BvhBuildOptions& options) {
  PrimitiveRows rows = gatherPrimitives(scene);
  m_primitiveCount = rows.count;
  m_skippedPrimitives = rows.skipped;
  PrimitiveTree tree = buildPrimitiveTree(rows, options);
  m_primStats = tree.bvh4.stats;
  m_primitiveBuildSeconds = tree.seconds;

  geometry = WtGeometry{};
  geometry.node_count = std::uint32_t(tree.bvh4.nodes.size());
  geometry.triangle_count = std::uint32_t(m_leafToScene.size());
  std::uint32_t emitters = geometry.triangle_count;
  for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type) {
    geometry.data_first[type] = rows.dataFirst[type];
    geometry.info_first[type] = rows.infoFirst[type];
    geometry.emitter_first[type] = type == WT_PRIM_TRIANGLE ? 0u : emitters;
    if (type != WT_PRIM_TRIANGLE) emitters += std::uint32_t(rows.count[type]);
  }
  primitiveBytes = 0;
  primNodes = upload(context, tree.bvh4.nodes, primitiveBytes);
  primRefs = upload(context, tree.refs, primitiveBytes);
  primData = upload(context, rows.data, primitiveBytes);
  primInfo = upload(context, rows.info, primitiveBytes);
}

void SceneBuffers::bindGeometry(cl::Kernel& kernel, int first) const {
  kernel.setArg(first, geometry);
  kernel.setArg(first + 1, primNodes);
  kernel.setArg(first + 2, primRefs);
  kernel.setArg(first + 3, primData);
  kernel.setArg(first + 4, primInfo);
}

int SceneBuffers::stackSize() const {
  int needed = std::max(bvh4StackEntries(m_bvh4Stats), bvh4StackEntries(m_primStats));
  return std::max(32, (needed + 31) / 32 * 32);
}

}  // namespace wt

// One definition, two compilers: the kernels see these exact sizes.
static_assert(sizeof(WtVec4) == 16);
static_assert(sizeof(WtTriangle) == 16);
static_assert(wt::kTriangleBlock == WT_TRIANGLE_BLOCK);
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
static_assert(sizeof(WtGeometry) == 64 && offsetof(WtGeometry, data_first) == 16 &&
              offsetof(WtGeometry, info_first) == 32 && offsetof(WtGeometry, emitter_first) == 48);
