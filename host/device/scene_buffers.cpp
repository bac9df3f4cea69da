#include "device/scene_buffers.h"

#include "bvh/builders.h"
#include "bvh/parallel.h"
#include "scene/generators.h"
#include "shared/alpha.h"
#include "shared/lights.h"
#include "shared/materials.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <limits>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <cstddef>
#include <cstring>
#include <map>
#include <stdexcept>
#include <tuple>

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

cl::Buffer readOnlyBuffer(Context& context, const void* data, std::size_t bytes, bool inPlace) {
  // OpenCL rejects zero-sized buffers and a null host pointer: one dummy word
  if (bytes == 0 || data == nullptr) return cl::Buffer(context.context(), CL_MEM_READ_ONLY, sizeof(wt_uint));
  // a CPU device's kernels address host memory: the buffer can be the array
  // itself; not under Oclgrind, whose uninitialised-value checker takes a
  // CL_MEM_USE_HOST_PTR buffer's contents as never written (the environment
  // renders reported every read of its texels and distributions)
  if (inPlace && context.info().isCpu && !context.underOclgrind())
    return cl::Buffer(context.context(), CL_MEM_READ_ONLY | CL_MEM_USE_HOST_PTR, bytes, const_cast<void*>(data));
  cl::Buffer buffer(context.context(), CL_MEM_READ_ONLY, bytes);
  context.queue().enqueueWriteBuffer(buffer, CL_TRUE, 0, bytes, data);
  return buffer;
}

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

namespace {

/// A 4-wide tree over triangles with its leaves packed into blocks of four:
/// position i of `order` (leaf order) is input triangle order[i].
struct TriangleTree {
  Bvh4 bvh4;
  BvhBuildStats stats;
  std::vector<std::uint32_t> order;
  std::size_t misfits = 0;
};

TriangleTree buildTriangleTree(std::span<const Aabb> bounds, const BvhBuildOptions& options,
                               std::span<const BvhInstance> instances) {
  TriangleTree tree;
  const Bvh bvh = buildBvh(bounds, binaryBuildOptions(options, bounds.size()), instances);
  tree.stats = bvh.stats;
  tree.bvh4 = collapseToBvh4(bvh, bvh4Options(options));
  // Leaves laid out in blocks of four (packLeavesIntoBlocks); from here on
  // the leaf order addresses the triangles directly.
  const LeafPacking packing = packLeavesIntoBlocks(tree.bvh4, bvh.primIndices.size());
  orderChildSlots(tree.bvh4);  // after the packing, which lays the leaves out in slot order
  tree.misfits = packing.misfits;
  tree.order.resize(packing.order.size());
  for (std::size_t i = 0; i < packing.order.size(); ++i) tree.order[i] = bvh.primIndices[packing.order[i]];
  return tree;
}

WtBvh4Node emptyBvh4Node() {
  WtBvh4Node n{};
  for (int k = 0; k < 4; ++k) {
    n.lo_x[k] = n.lo_y[k] = n.lo_z[k] = INFINITY;
    n.hi_x[k] = n.hi_y[k] = n.hi_z[k] = -INFINITY;
    n.child[k] = WT_BVH4_EMPTY;
    n.count[k] = 0;
  }
  return n;
}

bool emits(const WtMaterial& m) { return m.emission.x > 0.0f || m.emission.y > 0.0f || m.emission.z > 0.0f; }

/// A geometry stored once: the copy its triangles come from and the copies
/// (Scene::instances indices) that place it; `kept` its triangles (local
/// indices) that enter the tree, the same for every copy.
struct InstancedGeometry {
  std::uint32_t source = 0;
  std::vector<std::uint32_t> copies;
  std::vector<std::uint32_t> kept;
};

/// The geometries to store once: per geometry id, the copies that keep the
/// same triangles (zero-area ones drop out per copy), at least two of them,
/// with at least kMinInstanceTriangles each, no emissive material (the
/// light list addresses emitters as scene-space triangles) and an invertible
/// finite transform.
std::vector<InstancedGeometry> chooseInstancedGeometries(const Scene& scene, const std::vector<std::uint8_t>& valid,
                                                         std::size_t minTriangles) {
  std::map<std::pair<std::uint32_t, std::vector<std::uint32_t>>, std::vector<std::uint32_t>> groups;
  for (std::uint32_t c = 0; c < scene.instances.size(); ++c) {
    const GeometryInstance& copy = scene.instances[c];
    if (std::size_t(copy.firstTriangle) + copy.triangleCount > scene.triangles.size()) continue;
    const double det = glm::determinant(glm::dmat3(copy.transform));
    if (!(std::isfinite(det) && det != 0.0)) continue;
    std::vector<std::uint32_t> kept;
    bool emissive = false;
    for (std::uint32_t t = 0; t < copy.triangleCount; ++t) {
      if (!valid[copy.firstTriangle + t]) continue;
      kept.push_back(t);
      emissive = emissive || emits(scene.materials[scene.triangles[copy.firstTriangle + t].material]);
    }
    if (emissive || kept.size() < minTriangles) continue;
    groups[{copy.geometry, std::move(kept)}].push_back(c);
  }
  std::vector<InstancedGeometry> out;
  for (auto& [key, copies] : groups) {
    if (copies.size() < 2) continue;
    InstancedGeometry g;
    g.kept = key.second;
    g.copies = std::move(copies);
    out.push_back(std::move(g));
  }
  // in scene order, so the layout does not depend on the map's
  std::sort(out.begin(), out.end(), [&](const InstancedGeometry& a, const InstancedGeometry& b) {
    return scene.instances[a.copies[0]].firstTriangle < scene.instances[b.copies[0]].firstTriangle;
  });
  return out;
}

/// How coarse a copy's floats are for its size: the largest coordinate of
/// its box over the box's largest extent (float spacing grows with the
/// first). The copy nearest the origin is not always the finest: a small
/// copy near it can be coarser for its size than a large one farther out.
double relativeSpacing(const Aabb& box) {
  const glm::dvec3 lo(box.lo), hi(box.hi);
  const glm::dvec3 far = glm::max(glm::abs(lo), glm::abs(hi)), extent = hi - lo;
  const double size = std::max({extent.x, extent.y, extent.z});
  const double reach = std::max({far.x, far.y, far.z});
  return size > 0.0 ? reach / size : INFINITY;
}

glm::dvec3 dpos(const Scene& scene, std::uint32_t v) {
  const WtVec4& p = scene.positions[v];
  return glm::dvec3(p.x, p.y, p.z);
}

}  // namespace

std::optional<Instancing> parseInstancing(std::string_view name) {
  if (name == "off") return Instancing::Off;
  if (name == "on") return Instancing::On;
  if (name == "auto") return Instancing::Auto;
  return std::nullopt;
}

SceneBuffers::SceneBuffers(Context& context, const Scene& scene, const BvhBuildOptions& options)
    : m_allSurfaceAttributes(options.allSurfaceAttributes), m_texelsInPlace(options.texelsInPlace) {
  // Zero-area and non-finite triangles never enter the BVH: they cannot be
  // hit meaningfully, and in float a ray through a collinear triangle can
  // still produce a spurious hit.
  std::vector<std::uint8_t> valid(scene.triangles.size(), 0);
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
    valid[i] = 1;
  }

  // Geometries stored once leave the flat tree; their copies become instances.
  std::vector<InstancedGeometry> instanced;
  if (options.instancing != Instancing::Off) {
    instanced = chooseInstancedGeometries(scene, valid, kMinInstanceTriangles);
    if (options.instancing == Instancing::Auto) {
      // Instances cost a second traversal per ray and lose the packets
      // inside them; they pay where the flattened copies would not fit the
      // cache and the stored-once ones do (docs/lab/2026-12-05-performance-log.md, "Instancing")
      std::size_t copiedTriangles = 0;
      for (const InstancedGeometry& g : instanced) copiedTriangles += g.kept.size() * (g.copies.size() - 1);
      if (!instancingPays(double(copiedTriangles) * kFlatBytesPerTriangle, context.info().globalCacheBytes))
        instanced.clear();
    }
  }
  std::vector<std::uint8_t> flat = valid;
  for (const InstancedGeometry& g : instanced)
    for (std::uint32_t c : g.copies)
      for (std::uint32_t t : g.kept) flat[scene.instances[c].firstTriangle + t] = 0;

  std::vector<Aabb> bounds;
  std::vector<std::uint32_t> bvhToScene;
  for (std::size_t i = 0; i < scene.triangles.size(); ++i) {
    if (!flat[i]) continue;
    bounds.push_back(scene.triangleBounds(std::uint32_t(i)));
    bvhToScene.push_back(std::uint32_t(i));
  }
  TriangleTree tree = buildTriangleTree(bounds, options, bvhInstances(scene, bvhToScene));
  m_bvhStats = tree.stats;
  m_bvh4Stats = tree.bvh4.stats;
  m_leafMisfits = tree.misfits;
  std::vector<WtBvh4Node> allNodes(tree.bvh4.nodes.begin(), tree.bvh4.nodes.end());
  m_leafToScene.resize(tree.order.size());
  for (std::size_t i = 0; i < tree.order.size(); ++i) m_leafToScene[i] = bvhToScene[tree.order[i]];
  m_sceneToLeaf.assign(scene.triangles.size(), 0xffffffffu);
  for (std::size_t leaf = 0; leaf < m_leafToScene.size(); ++leaf) m_sceneToLeaf[m_leafToScene[leaf]] = std::uint32_t(leaf);

  // The triangles in leaf order, in blocks of four (WT_TRIANGLE_BLOCK): per
  // corner one row of x, of y and of z, 36 bytes a triangle; its vertex
  // indices (shading reads the normals by them) and material go to tri_info,
  // 16 bytes, which traversal never reads. Positions per leaf triangle:
  // the scene's, or for a geometry stored once its object space.
  std::vector<glm::vec3> corners(3 * m_leafToScene.size());
  for (std::size_t i = 0; i < m_leafToScene.size(); ++i) {
    const WtTriangle& t = scene.triangles[m_leafToScene[i]];
    const std::uint32_t v[3] = {t.v0, t.v1, t.v2};
    for (int k = 0; k < 3; ++k) {
      const WtVec4& p = scene.positions[v[k]];
      corners[3 * i + k] = glm::vec3(p.x, p.y, p.z);
    }
  }

  // Each geometry stored once: its tree's nodes after the others (child and
  // leaf indices moved along), its triangles after the others from a block
  // boundary (the leaves' block layout holds), in object space: the copy
  // whose floats are finest for its size (relativeSpacing), moved to its
  // box's centre. Copy k's transform is W_k W_s^-1 T(centre), composed in double.
  std::vector<InstanceDesc> descs;
  if (!instanced.empty()) {
    if (allNodes.empty()) allNodes.push_back(emptyBvh4Node());  // node 0: the flat tree's root, hit by nothing
    m_sceneToInstance.assign(scene.triangles.size(), 0xffffffffu);
  }
  int blasStack = 0;
  for (const InstancedGeometry& g : instanced) {
    // the source: the copy whose floats are finest for its size (every copy
    // is drawn as the source moved, so its rounding reaches them all)
    double best = INFINITY;
    std::uint32_t source = g.copies[0];
    Aabb sourceBox;
    for (std::uint32_t c : g.copies) {
      Aabb box;
      for (std::uint32_t t : g.kept) box.extend(scene.triangleBounds(scene.instances[c].firstTriangle + t));
      const double coarseness = relativeSpacing(box);
      if (c == g.copies[0] || coarseness < best) best = coarseness, source = c, sourceBox = box;
    }
    const GeometryInstance& src = scene.instances[source];
    const glm::dvec3 centre = 0.5 * (glm::dvec3(sourceBox.lo) + glm::dvec3(sourceBox.hi));
    std::vector<glm::vec3> object(3 * g.kept.size());
    std::vector<Aabb> objectBounds(g.kept.size());
    for (std::size_t i = 0; i < g.kept.size(); ++i) {
      const WtTriangle& t = scene.triangles[src.firstTriangle + g.kept[i]];
      const std::uint32_t v[3] = {t.v0, t.v1, t.v2};
      for (int k = 0; k < 3; ++k) {
        object[3 * i + k] = glm::vec3(dpos(scene, v[k]) - centre);
        objectBounds[i].extend(object[3 * i + k]);
      }
    }
    TriangleTree blas = buildTriangleTree(objectBounds, options, {});
    blasStack = std::max(blasStack, bvh4StackEntries(blas.bvh4.stats));
    // pad the leaf order to a block boundary: no leaf covers the spare lanes
    while (m_leafToScene.size() % kTriangleBlock != 0) {
      m_leafToScene.push_back(kNoTriangle);
      corners.insert(corners.end(), 3, glm::vec3(0.0f));
    }
    const auto nodeBase = std::uint32_t(allNodes.size());
    const auto triangleBase = std::uint32_t(m_leafToScene.size());
    for (WtBvh4Node n : blas.bvh4.nodes) {
      for (int k = 0; k < 4; ++k)
        if (n.child[k] != WT_BVH4_EMPTY) n.child[k] += n.count[k] > 0 ? triangleBase : nodeBase;
      allNodes.push_back(n);
    }
    for (std::size_t i = 0; i < blas.order.size(); ++i) {
      const std::uint32_t local = g.kept[blas.order[i]];
      m_leafToScene.push_back(src.firstTriangle + local);
      for (int k = 0; k < 3; ++k) corners.push_back(object[3 * blas.order[i] + k]);
    }
    // the root's child boxes bound each copy
    InstanceDesc desc;
    desc.root = nodeBase;
    const WtBvh4Node& root = blas.bvh4.nodes.front();
    for (int k = 0; k < 4; ++k) {
      desc.rootBoxes[k].lo = glm::vec3(root.lo_x[k], root.lo_y[k], root.lo_z[k]);
      desc.rootBoxes[k].hi = glm::vec3(root.hi_x[k], root.hi_y[k], root.hi_z[k]);
    }
    const glm::dmat4 fromSource = glm::inverse(src.transform) * glm::translate(glm::dmat4(1.0), centre);
    for (std::uint32_t c : g.copies) {
      const GeometryInstance& copy = scene.instances[c];
      const auto instance = std::uint32_t(descs.size());
      desc.objectToScene = copy.transform * fromSource;
      descs.push_back(desc);
      m_instanceOffset.push_back(std::int64_t(copy.firstTriangle) - std::int64_t(src.firstTriangle));
      m_instanceMirrored.push_back(glm::determinant(glm::dmat3(desc.objectToScene)) < 0.0);
      for (std::size_t i = 0; i < blas.order.size(); ++i) {
        const std::uint32_t sceneTri = copy.firstTriangle + g.kept[blas.order[i]];
        m_sceneToLeaf[sceneTri] = triangleBase + std::uint32_t(i);
        m_sceneToInstance[sceneTri] = primId(WT_PRIM_INSTANCE, instance);
      }
    }
    m_instancedTriangles += g.kept.size() * g.copies.size();
  }
  m_blasStackEntries = blasStack;
  nodeCount = std::uint32_t(allNodes.size());

  // Every lane is written below but the last block's spare ones and the
  // padding, which are zeroed (no leaf covers them): no zero fill of the
  // whole, 36 MB for 1 M triangles.
  constexpr std::size_t kBlockFloats = 4 * WT_TRIANGLE_BLOCK_ROWS;
  const std::size_t triangles = m_leafToScene.size();
  std::vector<float, UninitialisedAllocator<float>> blocks(kBlockFloats *
                                                           ((triangles + kTriangleBlock - 1) / kTriangleBlock));
  if (triangles % kTriangleBlock != 0) std::fill(blocks.end() - kBlockFloats, blocks.end(), 0.0f);
  std::vector<std::array<std::uint32_t, 4>, UninitialisedAllocator<std::array<std::uint32_t, 4>>> info(triangles);
  for (std::size_t i = 0; i < triangles; ++i) {
    float* lane = blocks.data() + kBlockFloats * (i / kTriangleBlock) + i % kTriangleBlock;
    for (int k = 0; k < 3; ++k) {
      lane[12 * k + 0] = corners[3 * i + k].x;
      lane[12 * k + 4] = corners[3 * i + k].y;
      lane[12 * k + 8] = corners[3 * i + k].z;
    }
    if (m_leafToScene[i] == kNoTriangle) {
      info[i] = {0u, 0u, 0u, 0u};
      continue;
    }
    const WtTriangle& t = scene.triangles[m_leafToScene[i]];
    info[i] = {t.v0, t.v1, t.v2, t.material};
  }
  m_storedTriangles = triangles;
  std::size_t bytes = 0;
  nodes = upload(context, allNodes, bytes);
  triVerts = upload(context, blocks, bytes);
  triangleInfo = upload(context, info, bytes);
  uploadedBytes = bytes;
  normals = upload(context, scene.normals, m_attributeBytes);
  // each material in the cheapest model that renders it exactly (kernelMaterial)
  m_kernelMaterials = scene.materials;
  if (options.lambertianForms)
    std::transform(m_kernelMaterials.begin(), m_kernelMaterials.end(), m_kernelMaterials.begin(), kernelMaterial);
  // shadow rays cross smooth thin walls (tinted where they meet them: COLOR_0 and textures too)
  for (WtMaterial& m : m_kernelMaterials) m.shadow_pass = thinShadowPass(m) ? 1u : 0u;
  materials = upload(context, m_kernelMaterials, m_attributeBytes);
  uploadPrimitives(context, scene, options, descs);
  uploadSurface(context, scene);
  uploadAlpha(context, scene);
}

bool thinShadowPass(const WtMaterial& m) {
  // textures only multiply the factors: the roughness and the anisotropy stay below theirs, metallic below 1
  // where its factor is or a metallic-roughness texture scales it (setMaterialFeatures' dielectric share)
  const bool dielectric = m.base_color.w < 1.0f || (m.texture_mask & (1u << WT_TEXTURE_SLOT_METALLIC_ROUGHNESS)) != 0u;
  return m.model == WT_MATERIAL_PBR && m.transmission > 0.0f && dielectric && m.volume.w == 0.0f &&
         m.roughness < WT_PBR_MIN_ROUGHNESS && m.anisotropy == 0.0f;
}

bool textureIsOpaque(const TextureSet& textures, std::uint32_t texture) {
  if (texture >= textures.textures.size()) return false;
  const WtTexture& tex = textures.textures[texture];
  if (tex.first_level >= textures.levels.size()) return false;
  const WtTextureLevel& level = textures.levels[tex.first_level];
  const bool wide = (tex.flags & WT_TEXTURE_16BIT) != 0u;
  const std::size_t count = std::size_t(level.width) * level.height * (wide ? 2 : 1);
  if (std::size_t(level.offset) + count > textures.texels.size()) return false;
  const wt_uint* texel = textures.texels.data() + level.offset;
  // 8-bit: A in the top byte; 16-bit: A in the top half of the second uint (shared/textures.h)
  for (std::size_t i = wide ? 1 : 0; i < count; i += wide ? 2 : 1)
    if ((texel[i] >> (wide ? 16 : 24)) != (wide ? 0xffffu : 0xffu)) return false;
  return true;
}

bool triangleMayHaveHoles(const Scene& scene, std::uint32_t tri, const std::vector<std::int8_t>& opaqueTexture) {
  if (tri >= scene.triangles.size()) return false;
  const WtTriangle& t = scene.triangles[tri];
  if (t.material >= scene.materials.size()) return false;
  const WtMaterial& m = scene.materials[t.material];
  if (m.alpha_mode != WT_ALPHA_MASK && m.alpha_mode != WT_ALPHA_BLEND) return false;
  // the base colour texture as the kernels read it (SceneBuffers::uploadSurface)
  const std::size_t slot = std::size_t(t.material) * WT_TEXTURE_SLOTS + WT_TEXTURE_SLOT_BASE_COLOR;
  if ((m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR)) && slot < scene.materialTextures.size()) {
    const std::uint32_t texture = scene.materialTextures[slot].texture;
    if (texture >= opaqueTexture.size() || !opaqueTexture[texture]) return true;
  }
  // the least coverage over the triangle: the factor times its corners' least COLOR_0 alpha
  float least = m.alpha;
  if (!scene.colors.empty()) {
    for (std::uint32_t v : {t.v0, t.v1, t.v2})
      least = std::min(least, m.alpha * (v < scene.colors.size() ? scene.colors[v].w : 1.0f));
  }
  const float needed = m.alpha_mode == WT_ALPHA_MASK ? m.alpha_cutoff : 1.0f;
  return !(least >= needed);
}

void SceneBuffers::uploadAlpha(Context& context, const Scene& scene) {
  m_alphaTriangles = 0;
  std::vector<std::uint32_t> bits;
  std::vector<std::int8_t> opaque;  // per texture: its alpha is 1 everywhere
  const bool any = std::any_of(scene.materials.begin(), scene.materials.end(), [](const WtMaterial& m) {
    return m.alpha_mode == WT_ALPHA_MASK || m.alpha_mode == WT_ALPHA_BLEND;
  });
  if (any) {
    opaque.resize(scene.textures.textures.size());
    for (std::size_t t = 0; t < opaque.size(); ++t) opaque[t] = textureIsOpaque(scene.textures, std::uint32_t(t));
    bits.assign((m_leafToScene.size() + 31) / 32, 0u);
    for (std::size_t leaf = 0; leaf < m_leafToScene.size(); ++leaf) {
      // an instanced geometry's triangle stands for its source copy's, whose material every copy shares
      if (m_leafToScene[leaf] == kNoTriangle || !triangleMayHaveHoles(scene, m_leafToScene[leaf], opaque)) continue;
      bits[leaf / 32] |= 1u << (leaf % 32);
      ++m_alphaTriangles;
    }
    if (m_alphaTriangles == 0) bits.clear();
  }
  // the general program tests every triangle's bit
  if (bits.empty() && m_allSurfaceAttributes) bits.assign((m_leafToScene.size() + 31) / 32, 0u);
  alphaBits = upload(context, bits, m_attributeBytes);
  // each material's row; a texture whose alpha is 1 everywhere is left out
  std::vector<WtAlphaMaterial> rows;
  if (m_alphaTriangles > 0) {
    for (std::size_t i = 0; i < scene.materials.size(); ++i) {
      const WtMaterial& m = scene.materials[i];
      const std::size_t slot = i * WT_TEXTURE_SLOTS + WT_TEXTURE_SLOT_BASE_COLOR;
      const bool textured = m_hasTextures && (m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR)) &&
                            slot < scene.materialTextures.size() &&
                            !(scene.materialTextures[slot].texture < opaque.size() &&
                              opaque[scene.materialTextures[slot].texture]);
      rows.push_back({m.alpha_mode, m.alpha_cutoff, m.alpha, textured ? 1u : 0u});
    }
  }
  alphaMaterials = upload(context, rows, m_attributeBytes);
}

void SceneBuffers::uploadSurface(Context& context, const Scene& scene) {
  m_hasTextures = !scene.materialTextures.empty() &&
                  std::any_of(scene.materials.begin(), scene.materials.end(),
                              [](const WtMaterial& m) { return m.texture_mask != 0u; });
  m_hasVertexColors = !scene.colors.empty();
  // the anisotropy direction follows the tangents, textured or not
  const bool anisotropic = std::any_of(scene.materials.begin(), scene.materials.end(),
                                       [](const WtMaterial& m) { return m.anisotropy > 0.0f; });
  std::vector<WtVec4> uv, color, tangent;
  if (m_hasTextures || anisotropic || m_allSurfaceAttributes) {
    uv.resize(scene.positions.size());
    for (std::size_t v = 0; v < uv.size(); ++v) {
      glm::vec2 a = v < scene.texcoords.size() ? scene.texcoords[v] : glm::vec2(0.0f);
      glm::vec2 b = v < scene.texcoords1.size() ? scene.texcoords1[v] : glm::vec2(0.0f);
      uv[v] = {a.x, a.y, b.x, b.y};
    }
    tangent.resize(scene.positions.size(), WtVec4{0.0f, 0.0f, 0.0f, 1.0f});
    for (std::size_t v = 0; v < std::min(tangent.size(), scene.tangents.size()); ++v)
      tangent[v] = {scene.tangents[v].x, scene.tangents[v].y, scene.tangents[v].z, scene.tangents[v].w};
  }
  if (m_hasVertexColors || m_allSurfaceAttributes) {
    color.resize(scene.positions.size(), WtVec4{1.0f, 1.0f, 1.0f, 1.0f});
    for (std::size_t v = 0; v < std::min(color.size(), scene.colors.size()); ++v)
      color[v] = {scene.colors[v].x, scene.colors[v].y, scene.colors[v].z, scene.colors[v].w};
  }
  vertexUv = upload(context, uv, m_attributeBytes);
  vertexColor = upload(context, color, m_attributeBytes);
  vertexTangent = upload(context, tangent, m_attributeBytes);
  std::vector<WtTextureRef> refs;
  if (m_hasTextures) refs = scene.materialTextures;
  materialTextures = upload(context, refs, m_attributeBytes);
  std::size_t bytes = 0;
  const auto start = std::chrono::steady_clock::now();
  // spans, not `cond ? vector : vector{}`: that expression is a copy of the texels
  const TextureSet& set = scene.textures;
  textures = upload(context, m_hasTextures ? std::span(set.textures) : std::span<const WtTexture>(), bytes);
  textureLevels = upload(context, m_hasTextures ? std::span(set.levels) : std::span<const WtTextureLevel>(), bytes);
  const std::span<const wt_uint> texelWords = m_hasTextures ? std::span(set.texels) : std::span<const wt_uint>();
  texels = readOnlyBuffer(context, texelWords.data(), texelWords.size_bytes(), m_texelsInPlace);
  bytes += texelWords.size_bytes();
  textureBytes = m_hasTextures ? bytes : 0;
  textureUploadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

namespace {

double boxArea(const Aabb& b) {
  const glm::dvec3 e = glm::max(glm::dvec3(b.hi) - glm::dvec3(b.lo), glm::dvec3(0.0));
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

/// Nodes whose subtree holds more leaf entries stay axis-aligned: high in
/// the tree the strands below run every way, and each node's choice reads
/// its whole subtree.
constexpr std::uint32_t kOrientMaxEntries = 4096;
/// A node is oriented where its children's boxes in its frame have at most
/// this fraction of their axis-aligned area (the chance a ray enters them),
/// which pays for rotating the ray into the frame.
constexpr double kOrientArea = 0.8;

float floatDown(double x) {
  float f = float(x);
  return double(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float floatUp(double x) {
  float f = float(x);
  return double(f) < x ? std::nextafter(f, INFINITY) : f;
}

/// Give nodes low in the tree whose entries are all curve segments a frame
/// along the segments' common direction (WT_BVH4_ORIENTED), where their
/// children's boxes in it are much smaller (kOrientArea): such a node's
/// slot then holds a WtBvh4Oriented, its boxes on a grid. The root stays
/// aligned. `entry` maps leaf order to the gathered entry (bounds, ids).
void orientCurveNodes(Bvh4& tree, const PrimitiveRows& rows, const std::vector<std::uint32_t>& ids,
                      std::span<const std::uint32_t> entry, int threads) {
  const std::size_t nodes = tree.nodes.size();
  if (nodes < 2) return;
  // the joints of each leaf entry's segment; radius < 0: not a curve
  std::vector<glm::dvec4> ja(entry.size()), jb(entry.size());
  for (std::size_t i = 0; i < entry.size(); ++i) {
    const std::uint32_t id = ids[entry[i]];
    ja[i] = jb[i] = glm::dvec4(0.0, 0.0, 0.0, -1.0);
    if (primType(id) != WT_PRIM_CURVE) continue;
    const std::size_t row = rows.dataFirst[WT_PRIM_CURVE] + 2 * std::size_t(primIndex(id));
    if (row + 1 >= rows.data.size()) continue;
    const WtVec4 &ra = rows.data[row], &rb = rows.data[row + 1];
    ja[i] = glm::dvec4(ra.x, ra.y, ra.z, std::fabs(ra.w));
    jb[i] = glm::dvec4(rb.x, rb.y, rb.z, std::fabs(rb.w));
  }
  // each node's leaf-entry range (a subtree's entries are contiguous), children after parents in index
  std::vector<std::uint32_t> lo(nodes, 0xffffffffu), hi(nodes, 0), order{0};
  for (std::size_t i = 0; i < order.size(); ++i)
    for (int k = 0; k < 4; ++k)
      if (tree.nodes[order[i]].child[k] != WT_BVH4_EMPTY && tree.nodes[order[i]].count[k] == 0)
        order.push_back(tree.nodes[order[i]].child[k]);
  for (std::size_t i = order.size(); i-- > 0;) {
    const std::uint32_t n = order[i];
    const WtBvh4Node& node = tree.nodes[n];
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) continue;
      const std::uint32_t c = node.child[k];
      const std::uint32_t a = node.count[k] > 0 ? c : lo[c], b = node.count[k] > 0 ? c + node.count[k] : hi[c];
      lo[n] = std::min(lo[n], a), hi[n] = std::max(hi[n], b);
    }
  }
  std::vector<std::uint8_t> oriented(nodes, 0);
  std::vector<WtBvh4Oriented> framed(nodes);
  auto slotRange = [&](const WtBvh4Node& node, int k) {
    const std::uint32_t c = node.child[k];
    return node.count[k] > 0 ? std::pair{c, c + node.count[k]} : std::pair{lo[c], hi[c]};
  };
  // each node's choice reads only the tree as collapsed; nodes dealt out in turn, whose sizes vary by level
  auto orient = [&](std::size_t n) {
    if (hi[n] <= lo[n] || hi[n] - lo[n] > kOrientMaxEntries) return;
    bool curves = true;
    for (std::uint32_t i = lo[n]; i < hi[n] && curves; ++i) curves = ja[i].w >= 0.0;
    if (!curves) return;
    // the segments' main direction: power iteration on the sum of e e^T
    glm::dmat3 m(0.0);
    glm::dvec3 axis(0.0), centre(0.0);
    double longest = -1.0;
    for (std::uint32_t i = lo[n]; i < hi[n]; ++i) {
      const glm::dvec3 e = glm::dvec3(jb[i]) - glm::dvec3(ja[i]);
      m += glm::outerProduct(e, e);
      if (glm::dot(e, e) > longest) longest = glm::dot(e, e), axis = e;
      centre += 0.5 * (glm::dvec3(ja[i]) + glm::dvec3(jb[i]));
    }
    if (!(longest > 0.0)) return;
    for (int it = 0; it < 8; ++it) axis = glm::normalize(m * axis);
    if (!std::isfinite(axis.x + axis.y + axis.z)) return;
    centre /= double(hi[n] - lo[n]);
    // an orthonormal frame with z along the axis (Duff et al. 2017)
    const double sign = std::copysign(1.0, axis.z);
    const double a = -1.0 / (sign + axis.z), b = axis.x * axis.y * a;
    const glm::dvec3 x(1.0 + sign * axis.x * axis.x * a, sign * b, -sign * axis.x);
    const glm::dvec3 y(b, sign + axis.y * axis.y * a, -axis.y);
    WtBvh4Oriented f{};
    const glm::dvec3 r[3] = {x, y, axis};
    glm::dmat3 rf;  // the float rows, as the kernel reads them (row i in rf[i])
    for (int i = 0; i < 3; ++i) {
      f.rows[i][0] = float(r[i].x), f.rows[i][1] = float(r[i].y), f.rows[i][2] = float(r[i].z);
      f.rows[i][3] = float(centre[i]);
      rf[i] = glm::dvec3(f.rows[i][0], f.rows[i][1], f.rows[i][2]);
    }
    const glm::dvec3 cf(f.rows[0][3], f.rows[1][3], f.rows[2][3]);
    const WtBvh4Node& was = tree.nodes[n];
    double alignedArea = 0.0, orientedArea = 0.0;
    glm::dvec3 blo[4], bhi[4], all_lo(INFINITY), all_hi(-INFINITY);
    for (int k = 0; k < 4; ++k) {
      if (was.child[k] == WT_BVH4_EMPTY) continue;
      Aabb box;
      box.lo = glm::vec3(was.lo_x[k], was.lo_y[k], was.lo_z[k]);
      box.hi = glm::vec3(was.hi_x[k], was.hi_y[k], was.hi_z[k]);
      alignedArea += boxArea(box);
      blo[k] = glm::dvec3(INFINITY), bhi[k] = glm::dvec3(-INFINITY);
      const auto [first, last] = slotRange(was, k);
      for (std::uint32_t i = first; i < last; ++i)
        for (const glm::dvec4& j : {ja[i], jb[i]}) {
          const glm::dvec3 p(j), w = p - cf;
          const glm::dvec3 q(glm::dot(rf[0], w), glm::dot(rf[1], w), glm::dot(rf[2], w));
          // the rows' rounding scales the sphere by 1 + ~1e-7; the joint's own rounding
          const double ext = j.w * (1.0 + 1e-6) + 1e-6 * (std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)}) + j.w);
          blo[k] = glm::min(blo[k], q - ext), bhi[k] = glm::max(bhi[k], q + ext);
        }
      all_lo = glm::min(all_lo, blo[k]), all_hi = glm::max(all_hi, bhi[k]);
    }
    // the grid: 255 steps from a float corner below the boxes to past them
    std::uint8_t grid[24];
    for (int a = 0; a < 3; ++a) {
      const float q0 = floatDown(all_lo[a]);
      float qs = std::max(floatUp((all_hi[a] - double(q0)) / 255.0), std::numeric_limits<float>::min());
      while (double(q0) + 255.0 * double(qs) < all_hi[a]) qs = std::nextafter(qs, INFINITY);
      f.origin[a] = q0, f.step[a] = qs;
      for (int k = 0; k < 4; ++k) {
        std::uint8_t& qlo = grid[8 * a + k];
        std::uint8_t& qhi = grid[8 * a + 4 + k];
        if (was.child[k] == WT_BVH4_EMPTY) {
          qlo = 255, qhi = 0;
          continue;
        }
        double l = std::clamp(std::floor((blo[k][a] - double(q0)) / double(qs)), 0.0, 255.0);
        while (l > 0.0 && double(q0) + l * double(qs) > blo[k][a]) l -= 1.0;
        double h = std::clamp(std::ceil((bhi[k][a] - double(q0)) / double(qs)), 0.0, 255.0);
        while (h < 255.0 && double(q0) + h * double(qs) < bhi[k][a]) h += 1.0;
        qlo = std::uint8_t(l), qhi = std::uint8_t(h);
      }
    }
    for (int k = 0; k < 4; ++k) {
      if (was.child[k] == WT_BVH4_EMPTY) continue;
      glm::dvec3 e;
      for (int a = 0; a < 3; ++a) e[a] = double(grid[8 * a + 4 + k] - grid[8 * a + k]) * double(f.step[a]);
      orientedArea += 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    }
    if (!(orientedArea < kOrientArea * alignedArea)) return;
    std::memcpy(f.grid, grid, sizeof grid);
    std::memcpy(f.child, was.child, sizeof f.child);
    std::memcpy(f.count, was.count, sizeof f.count);
    framed[n] = f;
    oriented[n] = 1;
  };
  bvh_detail::runTeam(bvh_detail::teamThreads(threads, entry.size()), [&](int rank, int size, auto&) {
    for (std::size_t n = 1 + std::size_t(rank); n < nodes; n += std::size_t(size)) orient(n);
  });
  // each oriented node in its own slot (child and count where a WtBvh4Node has them); its parent's child index names it so
  for (std::size_t n = 0; n < nodes; ++n)
    if (oriented[n]) std::memcpy(&tree.nodes[n], &framed[n], sizeof(WtBvh4Oriented));
  for (std::size_t n = 0; n < nodes; ++n) {
    WtBvh4Node& node = tree.nodes[n];
    for (int k = 0; k < 4; ++k)
      if (node.child[k] != WT_BVH4_EMPTY && node.count[k] == 0 && oriented[node.child[k]]) node.child[k] |= WT_BVH4_ORIENTED;
  }
}

/// A leaf joint row that is no curve's: its infinite radius passes every ray through the leaf's reject.
constexpr WtVec4 kNoJoint{0.0f, 0.0f, 0.0f, -std::numeric_limits<float>::infinity()};

/// Each entry's segment joints, in leaf order beside the refs: a curve's
/// rows in `rows` (the sign bits too: the segment test reads these), kNoJoint
/// for the other types, and for a curve whose rows `rows` does not hold.
std::vector<WtVec4> leafJoints(const std::vector<std::uint32_t>& refs, const PrimitiveRows& rows) {
  std::vector<WtVec4> joints(WT_LEAF_JOINT_ROWS * refs.size(), kNoJoint);
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const std::uint32_t id = refs[i];
    if (primType(id) != WT_PRIM_CURVE) continue;
    const std::size_t row = rows.dataFirst[WT_PRIM_CURVE] + 2 * std::size_t(primIndex(id));
    if (row + 1 >= rows.data.size()) continue;
    for (int end = 0; end < 2; ++end) joints[WT_LEAF_JOINT_ROWS * i + end] = rows.data[row + end];
  }
  return joints;
}

}  // namespace

PrimitiveTree buildPrimitiveTree(const PrimitiveRows& rows, const BvhBuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  // Each leaf entry is a typed id, tested one by one, so leaves stay small.
  BvhBuildOptions primOptions = options;
  primOptions.maxLeafSize = kPrimitiveLeafSize;
  const std::vector<Aabb>& bounds = rows.bounds;
  const std::vector<std::uint32_t>& ids = rows.ids;
  const Bvh bvh = buildBvh(bounds, binaryBuildOptions(primOptions, bounds.size()));
  Bvh4Options collapse = bvh4Options(primOptions);
  collapse.nodeBytesPerPrimitive = 0.0;  // no triangle blocks to weigh the nodes against
  PrimitiveTree tree;
  tree.bvh4 = collapseToBvh4(bvh, collapse);
  orderChildSlots(tree.bvh4);
  orientCurveNodes(tree.bvh4, rows, ids, bvh.primIndices, options.threads);
  tree.refs.resize(bvh.primIndices.size());
  for (std::size_t i = 0; i < tree.refs.size(); ++i) tree.refs[i] = ids[bvh.primIndices[i]];
  tree.joints = leafJoints(tree.refs, rows);
  tree.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tree;
}

/// Spheres or curves stored once: the Scene::primitiveInstances entries
/// that place one geometry, the first of them its source (the copy whose
/// floats are finest for its size: relativeSpacing), and where its items' rows
/// start in the device's block of their type.
struct InstancedPrimitives {
  std::uint32_t type = WT_PRIM_SPHERE;
  std::vector<std::uint32_t> copies;
  glm::dvec3 centre{0.0};      ///< the source's box centre: the geometry's object space is the source's less it
  std::uint32_t base = 0;      ///< the geometry's first item's device index
  std::vector<Aabb> local;     ///< SDF grids, displaced meshes: the items' boxes in object space, as regathered there
};

namespace {

/// Until the trees are laid out, a primitive instance's root names its geometry: this plus its index.
constexpr std::uint32_t kPrimitiveGeometryTag = 0x80000000u;

std::uint32_t rowsPerItem(std::uint32_t type) { return type == WT_PRIM_CURVE ? 2u : 1u; }

/// The gathered index range [lo, hi) of a copy's items (spheres by scene
/// index, curves their kept segments); empty when the copy is out of range.
std::pair<std::uint32_t, std::uint32_t> copyItems(const Scene& scene, const PrimitiveRows& rows,
                                                  const PrimitiveInstance& copy) {
  const std::size_t end = std::size_t(copy.first) + copy.count;
  if (copy.type == WT_PRIM_SPHERE && end <= scene.spheres.size()) return {copy.first, std::uint32_t(end)};
  if (copy.type == WT_PRIM_CURVE && end <= scene.curves.size() && end < rows.curveSegments.size())
    return {rows.curveSegments[copy.first], rows.curveSegments[end]};
  if (copy.type == WT_PRIM_SDF_GRID && end <= scene.sdfGrids.size() && end < rows.sdfBricks.size())
    return {rows.sdfBricks[copy.first], rows.sdfBricks[end]};
  if (copy.type == WT_PRIM_DISPLACED && end <= scene.displacedMeshes.size() && end < rows.displacedTriangles.size())
    return {rows.displacedTriangles[copy.first], rows.displacedTriangles[end]};
  return {0u, 0u};
}

/// Whether `material` emits (such copies stay flat: the light list addresses emitters as flat items).
bool materialEmits(const Scene& scene, std::uint32_t material) {
  if (material >= scene.materials.size()) return false;
  const WtVec4& e = scene.materials[material].emission;
  return e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
}

/// Whether two float arrays hold the same bits.
bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

/// A similarity's scale: the linear part's columns of one length and
/// perpendicular to float-made rotations' digits; 0 when it is not one.
double similarityScale(const glm::dmat4& r) {
  const glm::dmat3 l(r);
  const double s2 = (glm::dot(l[0], l[0]) + glm::dot(l[1], l[1]) + glm::dot(l[2], l[2])) / 3.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (!(std::abs(glm::dot(l[i], l[j]) - (i == j ? s2 : 0.0)) <= 1e-5 * s2)) return 0.0;
  return std::sqrt(s2);
}

/// copyMatchesSource for SDF grids and displaced meshes. An SDF grid is its
/// source's values (the same bits, cells, storage and material) under
/// another lattice placement, any affine one, the same for every grid of
/// the copy. A displaced mesh is its source moved by a similarity (as
/// spheres: an uneven scale would bend the displacement off the normals):
/// the same triangles, texture coordinates, map bits, level and material,
/// positions and normals within float rounding of the moved source's, scale
/// and offset times the similarity's scale. Emitting copies stay flat.
bool surfaceCopyMatchesSource(const Scene& scene, const PrimitiveRows& rows, const PrimitiveInstance& c,
                              const PrimitiveInstance& s, glm::dmat4* relative) {
  const auto [lo, hi] = copyItems(scene, rows, c);
  const auto [slo, shi] = copyItems(scene, rows, s);
  if (hi == lo || hi - lo != shi - slo || c.count != s.count) return false;
  if (c.type == WT_PRIM_SDF_GRID) {
    glm::dmat4 r(1.0);
    for (std::uint32_t k = 0; k < c.count; ++k) {
      const SdfGrid& a = scene.sdfGrids[c.first + k];
      const SdfGrid& b = scene.sdfGrids[s.first + k];
      if (!sdfGridUsable(a) || !sdfGridUsable(b) || a.cells != b.cells || a.storage != b.storage ||
          a.material != b.material || materialEmits(scene, a.material) || !sameBits(a.values, b.values))
        return false;
      const glm::dmat4 rk = a.latticeToScene * glm::inverse(b.latticeToScene);
      if (k == 0) {
        r = rk;
        continue;
      }
      for (int i = 0; i < 4; ++i)
        if (!(glm::length(rk[i] - r[i]) <= 1e-9 * (glm::length(r[i]) + glm::length(r[3]) + 1.0))) return false;
    }
    *relative = r;
    return true;
  }
  const double det = glm::determinant(glm::dmat3(c.transform)) * glm::determinant(glm::dmat3(s.transform));
  if (!(std::isfinite(det) && det != 0.0)) return false;
  const glm::dmat4 r = c.transform * glm::inverse(s.transform);
  const double scale = similarityScale(r);
  if (!(scale > 0.0)) return false;
  const glm::dmat3 linear(r);
  const double reach = std::max({std::abs(r[3].x), std::abs(r[3].y), std::abs(r[3].z)});
  for (std::uint32_t k = 0; k < c.count; ++k) {
    const DisplacedMesh& a = scene.displacedMeshes[c.first + k];
    const DisplacedMesh& b = scene.displacedMeshes[s.first + k];
    if (!displacedMeshUsable(a) || !displacedMeshUsable(b) || a.triangles != b.triangles ||
        a.texcoords != b.texcoords || a.mapWidth != b.mapWidth || a.mapHeight != b.mapHeight ||
        displacedLevel(a) != displacedLevel(b) || a.material != b.material || materialEmits(scene, a.material) ||
        !sameBits(a.map, b.map))
      return false;
    // a few float roundings of the terms each copy's floats were made from
    auto near = [&](double x, double y) { return std::abs(x - scale * y) <= 4e-6 * (std::abs(x) + scale * std::abs(y)); };
    if (!near(a.scale, b.scale) || !near(a.offset, b.offset)) return false;
    for (std::size_t v = 0; v < a.positions.size(); ++v) {
      const glm::dvec3 bp(b.positions[v]), at(a.positions[v]);
      const glm::dvec3 moved(r * glm::dvec4(bp, 1.0));
      const double tol = 4e-6 * (glm::length(at) + scale * glm::length(bp) + reach);
      if (!(glm::length(moved - at) <= tol)) return false;
      const glm::dvec3 n = linear * glm::dvec3(b.normals[v]);
      const double len = glm::length(n);
      if (len > 0.0 ? !(glm::length(n / len - glm::dvec3(a.normals[v])) <= 1e-5) : a.normals[v] != glm::vec3(0.0f))
        return false;
    }
  }
  *relative = r;
  return true;
}

/// The box around a copy's items (scene space, double): spheres' and
/// joints' centres, SDF grids' lattice corners, displaced meshes' vertices.
void copyBox(const Scene& scene, const PrimitiveRows& rows, const PrimitiveInstance& copy, glm::dvec3* lo,
             glm::dvec3* hi, bool withRadii) {
  *lo = glm::dvec3(INFINITY);
  *hi = glm::dvec3(-INFINITY);
  auto add = [&](const glm::dvec3& p, double r) {
    *lo = glm::min(*lo, p - r);
    *hi = glm::max(*hi, p + r);
  };
  if (copy.type == WT_PRIM_SDF_GRID) {
    for (std::uint32_t k = 0; k < copy.count; ++k) {
      const SdfGrid& g = scene.sdfGrids[copy.first + k];
      for (int corner = 0; corner < 8; ++corner)
        add(glm::dvec3(g.latticeToScene * glm::dvec4((corner & 1) ? g.cells.x : 0u, (corner & 2) ? g.cells.y : 0u,
                                                     (corner & 4) ? g.cells.z : 0u, 1.0)),
            0.0);
    }
    return;
  }
  if (copy.type == WT_PRIM_DISPLACED) {
    for (std::uint32_t k = 0; k < copy.count; ++k)
      for (const glm::vec3& p : scene.displacedMeshes[copy.first + k].positions) add(glm::dvec3(p), 0.0);
    return;
  }
  const auto [first, end] = copyItems(scene, rows, copy);
  const std::uint32_t per = rowsPerItem(copy.type);
  for (std::uint32_t i = per * first; i < per * end; ++i) {
    const WtVec4& p = rows.data[rows.dataFirst[copy.type] + i];
    add(glm::dvec3(p.x, p.y, p.z), withRadii ? std::abs(double(p.w)) : 0.0);  // a sphere's or joint's radius
  }
}

/// Whether copy `c` is the source `s` moved by c's transform times the
/// inverse of s's, a similarity with scale *scale: every item's joint
/// (xyz, radius) within float rounding of the moved source's; spheres
/// usable and not emitting (the light list addresses emitters as flat
/// spheres), curves ending at the same joints.
bool copyMatchesSource(const Scene& scene, const PrimitiveRows& rows, const PrimitiveInstance& c,
                       const PrimitiveInstance& s, glm::dmat4* relative) {
  if (c.type == WT_PRIM_SDF_GRID || c.type == WT_PRIM_DISPLACED) return surfaceCopyMatchesSource(scene, rows, c, s, relative);
  const auto [lo, hi] = copyItems(scene, rows, c);
  const auto [slo, shi] = copyItems(scene, rows, s);
  if (hi == lo || hi - lo != shi - slo) return false;
  const double det = glm::determinant(glm::dmat3(c.transform)) * glm::determinant(glm::dmat3(s.transform));
  if (!(std::isfinite(det) && det != 0.0)) return false;
  const glm::dmat4 r = c.transform * glm::inverse(s.transform);
  const glm::dmat3 l(r);
  const double s2 = (glm::dot(l[0], l[0]) + glm::dot(l[1], l[1]) + glm::dot(l[2], l[2])) / 3.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(glm::dot(l[i], l[j]) - (i == j ? s2 : 0.0)) > 1e-5 * s2) return false;  // (float-made rotations)
  const double scale = std::sqrt(s2);
  const double reach = std::max({std::abs(r[3].x), std::abs(r[3].y), std::abs(r[3].z)});
  const std::uint32_t per = rowsPerItem(c.type);
  const std::uint32_t data = rows.dataFirst[c.type];
  for (std::uint32_t k = 0; k < hi - lo; ++k) {
    if (c.type == WT_PRIM_SPHERE) {
      const Sphere& sphere = scene.spheres[lo + k];
      if (!sphereUsable(sphere) || !sphereUsable(scene.spheres[slo + k])) return false;
      const WtVec4& e = scene.materials[sphere.material].emission;
      if (e.x > 0.0f || e.y > 0.0f || e.z > 0.0f) return false;
    }
    for (std::uint32_t j = 0; j < per; ++j) {
      const WtVec4& a = rows.data[data + per * (lo + k) + j];
      const WtVec4& b = rows.data[data + per * (slo + k) + j];
      if (std::signbit(a.w) != std::signbit(b.w)) return false;
      const glm::dvec3 moved(r * glm::dvec4(b.x, b.y, b.z, 1.0));
      const glm::dvec3 at(a.x, a.y, a.z);
      // a few float roundings of the terms each copy's floats were made from
      const double tol = 4e-6 * (glm::length(at) + scale * glm::length(glm::dvec3(b.x, b.y, b.z)) + reach +
                                 std::abs(double(a.w)));
      if (!(glm::length(moved - at) <= tol) || !(std::abs(scale * std::abs(b.w) - std::abs(a.w)) <= tol)) return false;
    }
  }
  *relative = r;
  return true;
}

/// Copies of spheres and curves to store once: per (type, geometry), the
/// copies that match their source (copyMatchesSource), two or more.
std::vector<InstancedPrimitives> choosePrimitiveGeometries(const Scene& scene, const PrimitiveRows& rows) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::uint32_t>> groups;
  for (std::uint32_t c = 0; c < scene.primitiveInstances.size(); ++c) {
    const PrimitiveInstance& copy = scene.primitiveInstances[c];
    if (copy.type != WT_PRIM_SPHERE && copy.type != WT_PRIM_CURVE && copy.type != WT_PRIM_SDF_GRID &&
        copy.type != WT_PRIM_DISPLACED)
      continue;
    const auto [lo, hi] = copyItems(scene, rows, copy);
    if (hi > lo) groups[{copy.type, copy.geometry}].push_back(c);
  }
  std::vector<InstancedPrimitives> out;
  std::vector<std::uint8_t> taken(scene.primitiveInstances.size(), 0);
  for (auto& [key, copies] : groups) {
    // the source: the copy whose floats are finest for its size (as for triangles)
    std::uint32_t source = copies[0];
    double best = INFINITY;
    for (std::uint32_t c : copies) {
      glm::dvec3 lo, hi;
      copyBox(scene, rows, scene.primitiveInstances[c], &lo, &hi, true);
      Aabb box;
      box.extend(glm::vec3(lo));
      box.extend(glm::vec3(hi));
      const double coarseness = relativeSpacing(box);
      if (c == copies[0] || coarseness < best) best = coarseness, source = c;
    }
    InstancedPrimitives g;
    g.type = key.first;
    glm::dmat4 relative;
    if (!copyMatchesSource(scene, rows, scene.primitiveInstances[source], scene.primitiveInstances[source], &relative))
      continue;
    g.copies.push_back(source);
    for (std::uint32_t c : copies)
      if (c != source && !taken[c] &&
          copyMatchesSource(scene, rows, scene.primitiveInstances[c], scene.primitiveInstances[source], &relative))
        g.copies.push_back(c);
    if (g.copies.size() < 2) continue;
    for (std::uint32_t c : g.copies) taken[c] = 1;
    // the centre of the source's items
    glm::dvec3 a, b;
    copyBox(scene, rows, scene.primitiveInstances[source], &a, &b, false);
    g.centre = 0.5 * (a + b);
    out.push_back(std::move(g));
  }
  // in scene order, so the layout does not depend on the map's
  std::sort(out.begin(), out.end(), [](const InstancedPrimitives& a, const InstancedPrimitives& b) {
    return a.copies[0] < b.copies[0];
  });
  return out;
}

/// Rows [first, end) of a gathered block: its data or info rows of `type`
/// up to the next type's in gatherPrimitives' order.
template <class Rows>
std::pair<std::size_t, std::size_t> blockOf(const Rows& all, const std::array<std::uint32_t, WT_PRIM_TYPES>& first,
                                            std::uint32_t type) {
  std::size_t end = all.size();
  bool after = false;
  for (const PrimitiveType& t : primitiveTypes()) {
    if (after && first[t.id] >= first[type]) {
      end = std::min<std::size_t>(end, first[t.id]);
      break;
    }
    after = after || t.id == type;
  }
  return {first[type], end};
}

}  // namespace

std::array<double, WT_PRIM_TYPES> SceneBuffers::flatBytesPerPrimitive(const PrimitiveRows& rows) {
  // the tree's share: a ref and its joints per item, and a 4-wide node per
  // two leaves' worth of items (a node's children are mostly leaves)
  constexpr double tree = sizeof(std::uint32_t) + WT_LEAF_JOINT_ROWS * sizeof(WtVec4) +
                          double(sizeof(WtBvh4Node)) / (2 * kPrimitiveLeafSize);
  std::array<double, WT_PRIM_TYPES> out{};
  for (const PrimitiveType& t : primitiveTypes()) {
    if (rows.count[t.id] == 0 || t.id == WT_PRIM_INSTANCE) continue;
    const auto [d0, d1] = blockOf(rows.data, rows.dataFirst, t.id);
    const auto [i0, i1] = blockOf(rows.info, rows.infoFirst, t.id);
    const double rowBytes = double(d1 - d0) * sizeof(WtVec4) + double(i1 - i0) * sizeof(std::array<std::uint32_t, 4>);
    out[t.id] = rowBytes / double(rows.count[t.id]) + tree;
  }
  return out;
}

void SceneBuffers::uploadPrimitives(Context& context, const Scene& scene, const BvhBuildOptions& options,
                                    std::vector<InstanceDesc> instances) {
  PrimitiveRows rows = gatherPrimitives(scene, instances);
  m_primitiveScale = wt::primitiveScale(scene, rows);  // the flat rows: every copy as rays meet it
  std::vector<InstancedPrimitives> geometries;
  if (options.instancing != Instancing::Off && !scene.primitiveInstances.empty()) {
    geometries = choosePrimitiveGeometries(scene, rows);
    if (options.instancing == Instancing::Auto) {
      // as triangles: only where the flattened copies would outgrow the cache,
      // each item weighed by its own type's bytes
      const std::array<double, WT_PRIM_TYPES> bytes = flatBytesPerPrimitive(rows);
      double copied = 0.0;
      for (const InstancedPrimitives& g : geometries) {
        const auto [lo, hi] = copyItems(scene, rows, scene.primitiveInstances[g.copies[0]]);
        copied += double(hi - lo) * double(g.copies.size() - 1) * bytes[g.type];
      }
      if (!instancingPays(copied, context.info().globalCacheBytes)) geometries.clear();
    }
  }
  std::vector<PrimitiveTree> geometryTrees;
  const std::size_t triangleInstances = instances.size();
  m_primitiveInstanceStack = 0;
  for (auto& map : m_primDevice) map.clear();
  for (auto& map : m_primScene) map.clear();
  if (!geometries.empty()) rows = layoutPrimitiveInstances(scene, rows, geometries, options, instances, geometryTrees);
  m_primitiveCount = rows.count;
  m_skippedPrimitives = rows.skipped;
  // the emitting displaced base triangles and SDF bricks (their rows' x is the material)
  m_surfaceEmitters.clear();
  auto emits = [&](std::uint32_t material) {
    if (material >= scene.materials.size()) return false;
    const WtVec4& e = scene.materials[material].emission;
    return e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
  };
  for (std::uint32_t k = 0; k < rows.count[WT_PRIM_DISPLACED]; ++k) {
    const std::size_t row = rows.infoFirst[WT_PRIM_DISPLACED] + WT_DISP_INFO_ROWS * std::size_t(k);
    if (emits(rows.info[row][0]))
      m_surfaceEmitters.push_back({primId(WT_PRIM_DISPLACED, k), rows.info[row][1] / WT_DISP_MESH_ROWS, rows.info[row + 1][3]});
  }
  for (std::uint32_t k = 0; k < rows.count[WT_PRIM_SDF_GRID]; ++k) {
    const std::size_t row = rows.infoFirst[WT_PRIM_SDF_GRID] + WT_SDF_INFO_ROWS * std::size_t(k);
    if (!emits(rows.info[row][0])) continue;
    std::uint32_t crossed = 0;
    for (std::size_t r = 1; r < WT_SDF_INFO_ROWS; ++r)
      for (std::uint32_t word : rows.info[row + r]) crossed += std::uint32_t(std::popcount(word));
    m_surfaceEmitters.push_back({primId(WT_PRIM_SDF_GRID, k), rows.info[row][1], crossed});
  }
  PrimitiveTree tree = buildPrimitiveTree(rows, options);
  m_primStats = tree.bvh4.stats;
  m_primitiveBuildSeconds = tree.seconds;
  // each geometry's tree after the scene's: its nodes and refs moved past the ones before
  for (const PrimitiveTree& g : geometryTrees) {
    const auto nodeBase = std::uint32_t(tree.bvh4.nodes.size());
    const auto refBase = std::uint32_t(tree.refs.size());
    for (WtBvh4Node n : g.bvh4.nodes) {
      for (int k = 0; k < 4; ++k)
        if (n.child[k] != WT_BVH4_EMPTY) n.child[k] += n.count[k] > 0 ? refBase : nodeBase;
      tree.bvh4.nodes.push_back(n);
    }
    tree.refs.insert(tree.refs.end(), g.refs.begin(), g.refs.end());
    // its joints from the scene's rows, which hold the geometry's segments in object space (its own rows held none)
    const std::vector<WtVec4> joints = leafJoints(g.refs, rows);
    tree.joints.insert(tree.joints.end(), joints.begin(), joints.end());
    // the instances of this geometry: their root (gatherInstances wrote the tree's own index)
    for (std::size_t i = triangleInstances; i < instances.size(); ++i)
      if (instances[i].root == std::uint32_t(&g - geometryTrees.data()) + kPrimitiveGeometryTag)
        rows.info[rows.infoFirst[WT_PRIM_INSTANCE] + i][0] = nodeBase;
    m_primitiveInstanceStack = std::max(m_primitiveInstanceStack, bvh4StackEntries(g.bvh4.stats));
    m_primitiveBuildSeconds += g.seconds;
  }

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
  geometry.leaf_joints = std::uint32_t(rows.data.size());
  rows.data.insert(rows.data.end(), tree.joints.begin(), tree.joints.end());
  // a leaf's test reads its entries' joints four at a time: room for the last leaf's
  rows.data.resize(rows.data.size() + (kPrimitiveLeafSize - 1) * WT_LEAF_JOINT_ROWS, kNoJoint);
  primitiveBytes = 0;
  primNodes = upload(context, tree.bvh4.nodes, primitiveBytes);
  primRefs = upload(context, tree.refs, primitiveBytes);
  primData = upload(context, rows.data, primitiveBytes);
  primInfo = upload(context, rows.info, primitiveBytes);
}

PrimitiveRows SceneBuffers::layoutPrimitiveInstances(const Scene& scene, const PrimitiveRows& full,
                                                     std::vector<InstancedPrimitives>& geometries,
                                                     const BvhBuildOptions& options,
                                                     std::vector<InstanceDesc>& instances,
                                                     std::vector<PrimitiveTree>& trees) {
  PrimitiveRows out;
  // gatherInstances counts the instances it leaves out again below: the triangles' ones not twice
  std::size_t keptInstances = 0;
  for (std::uint32_t id : full.ids) keptInstances += primType(id) == WT_PRIM_INSTANCE;
  out.skipped = full.skipped - (full.count[WT_PRIM_INSTANCE] - keptInstances);
  // the gathered items in instanced copies, per type: which copy and which geometry
  std::array<std::vector<std::uint8_t>, WT_PRIM_TYPES> omitted;
  std::array<std::vector<std::uint32_t>, WT_PRIM_TYPES> boxOf;  // an item's entry in full.bounds
  for (std::uint32_t type : {WT_PRIM_SPHERE, WT_PRIM_CURVE}) {
    const auto [lo, hi] = blockOf(full.info, full.infoFirst, type);
    omitted[type].assign(hi - lo, 0);
    boxOf[type].assign(hi - lo, 0xffffffffu);
  }
  for (std::size_t i = 0; i < full.ids.size(); ++i) {
    const std::uint32_t type = primType(full.ids[i]);
    if (type == WT_PRIM_SPHERE || type == WT_PRIM_CURVE) boxOf[type][primIndex(full.ids[i])] = std::uint32_t(i);
  }
  for (const InstancedPrimitives& g : geometries)
    if (g.type == WT_PRIM_SPHERE || g.type == WT_PRIM_CURVE)
      for (std::uint32_t c : g.copies) {
        const auto [lo, hi] = copyItems(scene, full, scene.primitiveInstances[c]);
        std::fill(omitted[g.type].begin() + lo, omitted[g.type].begin() + hi, 1);
      }
  // the ids that enter the scene's tree: other types' as gathered, the instanced types' renumbered below
  std::array<std::vector<std::uint32_t>, WT_PRIM_TYPES> renumber;
  // SDF grids and displaced meshes gathered again: every scene item (the
  // instanced copies' rows without their bricks, values, vertices or maps,
  // so indices stay the scene's), then each geometry's source once, in
  // object space (placed less its centre), whose boxes come out there
  std::array<PrimitiveRows, WT_PRIM_TYPES> regathered;
  std::vector<DisplacedMesh> objectMeshes;  // the displaced sources less their centres (kept for the gather)
  for (std::uint32_t type : {WT_PRIM_SDF_GRID, WT_PRIM_DISPLACED}) {
    if (std::none_of(geometries.begin(), geometries.end(), [&](const InstancedPrimitives& g) { return g.type == type; }))
      continue;
    const std::size_t sceneItems = type == WT_PRIM_SDF_GRID ? scene.sdfGrids.size() : scene.displacedMeshes.size();
    std::vector<std::uint8_t> drawn(sceneItems, 1);
    for (const InstancedPrimitives& g : geometries)
      if (g.type == type)
        for (std::uint32_t c : g.copies) {
          const PrimitiveInstance& copy = scene.primitiveInstances[c];
          std::fill(drawn.begin() + copy.first, drawn.begin() + copy.first + copy.count, 0);
        }
    PrimitiveRows& part = regathered[type];
    if (type == WT_PRIM_SDF_GRID) {
      std::vector<SdfGridRef> list;
      for (std::size_t i = 0; i < sceneItems; ++i)
        list.push_back({&scene.sdfGrids[i], scene.sdfGrids[i].latticeToScene, drawn[i] != 0});
      for (const InstancedPrimitives& g : geometries) {
        if (g.type != type) continue;
        const PrimitiveInstance& source = scene.primitiveInstances[g.copies[0]];
        for (std::uint32_t k = 0; k < source.count; ++k) {
          const SdfGrid& grid = scene.sdfGrids[source.first + k];
          list.push_back({&grid, glm::translate(glm::dmat4(1.0), -g.centre) * grid.latticeToScene, true});
        }
      }
      gatherSdfGridList(list, part);
    } else {
      std::size_t sources = 0;
      for (const InstancedPrimitives& g : geometries)
        if (g.type == type) sources += scene.primitiveInstances[g.copies[0]].count;
      objectMeshes.reserve(sources);  // no reallocation: the list points into it
      std::vector<DisplacedRef> list;
      for (std::size_t i = 0; i < sceneItems; ++i) list.push_back({&scene.displacedMeshes[i], drawn[i] != 0});
      for (const InstancedPrimitives& g : geometries) {
        if (g.type != type) continue;
        const PrimitiveInstance& source = scene.primitiveInstances[g.copies[0]];
        for (std::uint32_t k = 0; k < source.count; ++k) {
          DisplacedMesh mesh = scene.displacedMeshes[source.first + k];
          for (glm::vec3& p : mesh.positions) p = glm::vec3(glm::dvec3(p) - g.centre);
          objectMeshes.push_back(std::move(mesh));
          list.push_back({&objectMeshes.back(), true});
        }
      }
      gatherDisplacedList(list, part, WT_DISP_MAX_DEPTH);
    }
    const std::vector<std::uint32_t>& first = type == WT_PRIM_SDF_GRID ? part.sdfBricks : part.displacedTriangles;
    const std::vector<std::uint32_t>& fullFirst = type == WT_PRIM_SDF_GRID ? full.sdfBricks : full.displacedTriangles;
    // the scene's items: their own index, the copies' left out
    const std::uint32_t items = fullFirst.back();
    m_primDevice[type].assign(items, {0xffffffffu, 0xffffffffu});
    renumber[type].assign(items, 0xffffffffu);
    for (std::size_t i = 0; i < sceneItems; ++i) {
      if (!drawn[i]) continue;
      const std::uint32_t n = fullFirst[i + 1] - fullFirst[i];
      if (first[i + 1] - first[i] != n) throw std::logic_error("regathered items differ from the scene's");
      for (std::uint32_t k = 0; k < n; ++k) {
        renumber[type][fullFirst[i] + k] = first[i] + k;
        m_primDevice[type][fullFirst[i] + k] = {first[i] + k, 0xffffffffu};
        m_primScene[type].push_back(fullFirst[i] + k);  // device index first[i] + k: in order, no gaps
      }
    }
    // each geometry's items after them, with their object-space boxes
    std::vector<std::uint32_t> boxAt(part.count[type], 0xffffffffu);
    for (std::size_t i = 0; i < part.ids.size(); ++i)
      if (primType(part.ids[i]) == type) boxAt[primIndex(part.ids[i])] = std::uint32_t(i);
    std::size_t entry = sceneItems;
    for (InstancedPrimitives& g : geometries) {
      if (g.type != type) continue;
      const PrimitiveInstance& source = scene.primitiveInstances[g.copies[0]];
      g.base = first[entry];
      const std::uint32_t end = first[entry + source.count];
      entry += source.count;
      const auto [lo, hi] = copyItems(scene, full, source);
      if (end - g.base != hi - lo) throw std::logic_error("an instanced geometry's items differ from its copies'");
      for (std::uint32_t k = g.base; k < end; ++k) g.local.push_back(part.bounds[boxAt[k]]);
    }
  }
  for (const PrimitiveType& t : primitiveTypes()) {
    const std::uint32_t type = t.id;
    if (type == WT_PRIM_INSTANCE) {
      // triangle instances as they were, then one per instanced copy (roots patched once the trees are laid out)
      for (std::size_t gi = 0; gi < geometries.size(); ++gi) {
        InstancedPrimitives& g = geometries[gi];
        // the geometry's own tree over its items in object space (the source's less its centre)
        PrimitiveRows local;
        const auto [lo, hi] = copyItems(scene, full, scene.primitiveInstances[g.copies[0]]);
        for (std::uint32_t k = 0; k < hi - lo; ++k) {
          const std::uint32_t id = primId(g.type, g.base + k);
          if (!g.local.empty()) {  // regathered in object space
            local.bounds.push_back(g.local[k]);
            local.ids.push_back(id);
            continue;
          }
          // the source's box moved in double and widened past the float rounding of the move
          const Aabb& box = full.bounds[boxOf[g.type][lo + k]];  // every item of a copy is usable (copyMatchesSource)
          const glm::dvec3 a = glm::dvec3(box.lo) - g.centre, b = glm::dvec3(box.hi) - g.centre;
          const glm::dvec3 slack = 2.4e-7 * (glm::max(glm::abs(a), glm::abs(b)) + (b - a));
          Aabb moved;
          moved.lo = glm::vec3(a - slack);
          moved.hi = glm::vec3(b + slack);
          local.bounds.push_back(moved);
          local.ids.push_back(id);
        }
        trees.push_back(buildPrimitiveTree(local, options));
        const WtBvh4Node& root = trees.back().bvh4.nodes.front();
        const PrimitiveInstance& source = scene.primitiveInstances[g.copies[0]];
        const glm::dmat4 fromSource = glm::inverse(source.transform) * glm::translate(glm::dmat4(1.0), g.centre);
        for (std::uint32_t c : g.copies) {
          const PrimitiveInstance& copy = scene.primitiveInstances[c];
          InstanceDesc desc;
          desc.primitives = true;
          desc.root = kPrimitiveGeometryTag + std::uint32_t(gi);
          for (int k = 0; k < 4; ++k) {
            desc.rootBoxes[k].lo = glm::vec3(root.lo_x[k], root.lo_y[k], root.lo_z[k]);
            desc.rootBoxes[k].hi = glm::vec3(root.hi_x[k], root.hi_y[k], root.hi_z[k]);
          }
          desc.objectToScene = copy.transform * fromSource;
          const auto instance = std::uint32_t(instances.size());
          instances.push_back(desc);
          m_instanceOffset.push_back(0);
          m_instanceMirrored.push_back(glm::determinant(glm::dmat3(desc.objectToScene)) < 0.0);
          // the copy's items: the geometry's on this instance
          const auto [clo, chi] = copyItems(scene, full, copy);
          m_primInstanceFirst.resize(instances.size(), 0);
          m_primInstanceFirst[instance] = std::int64_t(clo) - std::int64_t(g.base);
          for (std::uint32_t k = 0; k < chi - clo; ++k)
            m_primDevice[g.type][clo + k] = {g.base + k, primId(WT_PRIM_INSTANCE, instance)};
        }
      }
      gatherInstances(instances, out);
      continue;
    }
    if (!renumber[type].empty() && type != WT_PRIM_SPHERE && type != WT_PRIM_CURVE) {
      // regathered above: rows count from their type's first row
      const PrimitiveRows& part = regathered[type];
      out.dataFirst[type] = std::uint32_t(out.data.size());
      out.infoFirst[type] = std::uint32_t(out.info.size());
      out.data.insert(out.data.end(), part.data.begin(), part.data.end());
      out.info.insert(out.info.end(), part.info.begin(), part.info.end());
      out.count[type] = part.count[type];
      continue;
    }
    if (type != WT_PRIM_SPHERE && type != WT_PRIM_CURVE) {
      // copied as gathered: rows count from their type's first row
      const auto [dlo, dhi] = blockOf(full.data, full.dataFirst, type);
      const auto [ilo, ihi] = blockOf(full.info, full.infoFirst, type);
      out.dataFirst[type] = std::uint32_t(out.data.size());
      out.infoFirst[type] = std::uint32_t(out.info.size());
      out.data.insert(out.data.end(), full.data.begin() + dlo, full.data.begin() + dhi);
      out.info.insert(out.info.end(), full.info.begin() + ilo, full.info.begin() + ihi);
      out.count[type] = full.count[type];
      continue;
    }
    // spheres, curves: the flat items, then each geometry's (the source's, object space)
    const std::uint32_t per = rowsPerItem(type);
    if (per == 2 && out.data.size() % 2 != 0) out.data.push_back({0.0f, 0.0f, 0.0f, 0.0f});
    out.dataFirst[type] = std::uint32_t(out.data.size());
    out.infoFirst[type] = std::uint32_t(out.info.size());
    const std::size_t items = omitted[type].size();
    m_primDevice[type].assign(items, {0xffffffffu, 0xffffffffu});
    renumber[type].assign(items, 0xffffffffu);
    for (std::uint32_t i = 0; i < items; ++i) {
      if (omitted[type][i]) continue;
      renumber[type][i] = std::uint32_t(m_primScene[type].size());
      m_primDevice[type][i] = {renumber[type][i], 0xffffffffu};
      m_primScene[type].push_back(i);
      for (std::uint32_t j = 0; j < per; ++j) out.data.push_back(full.data[full.dataFirst[type] + per * i + j]);
      out.info.push_back(full.info[full.infoFirst[type] + i]);
    }
    std::uint32_t next = std::uint32_t(m_primScene[type].size());
    for (InstancedPrimitives& g : geometries) {
      if (g.type != type) continue;
      g.base = next;
      const auto [lo, hi] = copyItems(scene, full, scene.primitiveInstances[g.copies[0]]);
      for (std::uint32_t i = lo; i < hi; ++i) {
        for (std::uint32_t j = 0; j < per; ++j) {
          const WtVec4& p = full.data[full.dataFirst[type] + per * i + j];
          const glm::vec3 q(glm::dvec3(p.x, p.y, p.z) - g.centre);
          out.data.push_back({q.x, q.y, q.z, p.w});  // the radius keeps its sign bit (curves' ends)
        }
        out.info.push_back(full.info[full.infoFirst[type] + i]);
      }
      next += hi - lo;
    }
    // items left out as gathered (degenerate) still count; the instanced copies' count once
    out.count[type] = full.count[type] - (items - m_primScene[type].size()) + (next - m_primScene[type].size());
  }
  // the scene tree's entries: every gathered id but the instanced copies', renumbered, then the instances
  for (std::size_t i = 0; i < full.ids.size(); ++i) {
    const std::uint32_t id = full.ids[i], type = primType(id);
    if (type == WT_PRIM_INSTANCE) continue;
    if (!renumber[type].empty()) {
      const std::uint32_t to = renumber[type][primIndex(id)];
      if (to == 0xffffffffu) continue;
      out.bounds.push_back(full.bounds[i]);
      out.ids.push_back(primId(type, to));
      continue;
    }
    out.bounds.push_back(full.bounds[i]);
    out.ids.push_back(id);
  }
  // gatherInstances wrote the instances' boxes and ids into out already (before the others: order does not matter)
  return out;
}

std::pair<std::uint32_t, std::uint32_t> SceneBuffers::devicePrimitive(std::uint32_t sceneId) const {
  const std::uint32_t type = primType(sceneId);
  if (sceneId == 0xffffffffu || type >= WT_PRIM_TYPES || m_primDevice[type].empty()) return {sceneId, 0xffffffffu};
  if (primIndex(sceneId) >= m_primDevice[type].size()) return {sceneId, 0xffffffffu};
  const auto [index, instance] = m_primDevice[type][primIndex(sceneId)];
  return {primId(type, index), instance};
}

std::uint32_t SceneBuffers::scenePrimitive(std::uint32_t deviceId, std::uint32_t instance) const {
  const std::uint32_t type = primType(deviceId);
  if (deviceId == 0xffffffffu || type >= WT_PRIM_TYPES || m_primDevice[type].empty()) return deviceId;
  if (instance != 0xffffffffu)
    return primId(type, std::uint32_t(std::int64_t(primIndex(deviceId)) + m_primInstanceFirst[primIndex(instance)]));
  return primId(type, m_primScene[type][primIndex(deviceId)]);
}

std::uint32_t SceneBuffers::sceneTriangle(std::uint32_t leafIndex, std::uint32_t instance) const {
  const std::uint32_t first = m_leafToScene[leafIndex];
  if (instance == 0xffffffffu) return first;
  return std::uint32_t(std::int64_t(first) + m_instanceOffset[primIndex(instance)]);
}

int SceneBuffers::stackSize() const {
  int needed = std::max({bvh4StackEntries(m_bvh4Stats), bvh4StackEntries(m_primStats), m_blasStackEntries,
                         m_primitiveInstanceStack});
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
// an oriented node takes a node's slot, its child and count where bvh_prims.cl's walks read them;
// bvh4_frame_hit reads origin and step as floats 12 and 15 and grid's planes by bvh_ray_planes' offsets
static_assert(sizeof(WtBvh4Oriented) == sizeof(WtBvh4Node) && offsetof(WtBvh4Oriented, child) == offsetof(WtBvh4Node, child) &&
              offsetof(WtBvh4Oriented, count) == offsetof(WtBvh4Node, count));
static_assert(offsetof(WtBvh4Oriented, origin) == 48 && offsetof(WtBvh4Oriented, step) == 60 && offsetof(WtBvh4Oriented, grid) == 72);
static_assert(offsetof(WtBvh4Node, lo_y) == 32 && offsetof(WtBvh4Node, lo_z) == 64);
// bvh_ray_planes (kernels/bvh.cl) addresses the planes by these float offsets
static_assert(offsetof(WtBvh4Node, hi_x) == 16 && offsetof(WtBvh4Node, hi_y) == 48 && offsetof(WtBvh4Node, hi_z) == 80);
static_assert(offsetof(WtBvh4Node, child) == 96 && offsetof(WtBvh4Node, count) == 112);
static_assert(sizeof(WtMaterial) == 160 && offsetof(WtMaterial, priority) == 144 && offsetof(WtMaterial, specular) == 80 && offsetof(WtMaterial, sheen) == 96 &&
              offsetof(WtMaterial, clearcoat) == 112 && offsetof(WtMaterial, iridescence) == 128);
static_assert(sizeof(WtTextureRef) == 48);
static_assert(sizeof(WtAlphaMaterial) == 16);
static_assert(sizeof(WtTexture) == 16 && sizeof(WtTextureLevel) == 16);
static_assert(sizeof(WtCamera) == 64);
static_assert(sizeof(WtFrameParams) == 64);
static_assert(sizeof(WtLight) == 64);
static_assert(sizeof(WtAliasSlot) == 16);
static_assert(sizeof(WtLightNode) == 64);
static_assert(sizeof(WtGeometry) == 16 + 12 * WT_PRIM_TYPES && offsetof(WtGeometry, data_first) == 16 &&
              offsetof(WtGeometry, info_first) == 16 + 4 * WT_PRIM_TYPES &&
              offsetof(WtGeometry, emitter_first) == 16 + 8 * WT_PRIM_TYPES);
