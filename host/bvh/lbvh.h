// Linear BVH build on the host (Karras 2012 hierarchy over a parallel radix
// sort of Morton codes), flattened into the node layout the kernels traverse.
#pragma once

#include "core/math.h"
#include "shared/types.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

namespace wt {

/// Which tree buildBvh (host/bvh/builders.h) makes.
enum class BvhBuilder {
  Auto,  ///< buildAutoBvh: PLOC for small parts, the LBVH for large ones, one tree per repeated geometry
  Lbvh,  ///< buildLbvh: Morton codes and the Karras hierarchy; fastest
  Ploc,  ///< buildPlocBvh: PLOC clustering in Morton order, binned SAH over the top
  Sah,   ///< buildSahBvh: top-down binned SAH; slow, the quality yardstick
};

/// Whether SceneBuffers stores a geometry placed several times once, as a
/// two-level tree (instances over per-geometry trees), or flattens every copy.
enum class Instancing {
  Off,   ///< every copy's triangles in the one tree, world space (the flattened form)
  On,    ///< every eligible geometry once (SceneBuffers::kMinInstanceTriangles, no emission)
  Auto,  ///< On where the flattened copies would outgrow the device's cache (SceneBuffers::instancingPays)
};

struct BvhBuildOptions {
  /// Subtrees with at most this many primitives become one leaf; 0: 4
  /// (buildBvh only; the builders themselves take it as given). SceneBuffers
  /// and the bench read it as the limit of the 4-wide tree's leaves instead
  /// (binaryBuildOptions, host/bvh/bvh4.h).
  int maxLeafSize = 4;
  int threads = 0;      ///< 0: std::thread::hardware_concurrency()
  BvhBuilder builder = BvhBuilder::Auto;  ///< read by buildBvh, not by buildLbvh
  int plocRadius = 16;  ///< Ploc: neighbours searched on each side in Morton order (1 to 64)
  /// Ploc: clustering stops where clusters average this many primitives and a
  /// binned SAH pass builds the tree above them; 0: PLOC up to the root.
  int plocTopPrims = 16;
  Instancing instancing = Instancing::Off;  ///< read by SceneBuffers only
  /// Read by SceneBuffers only: per-vertex texture coordinates, tangents,
  /// COLOR_0 and the alpha bits for every vertex and triangle even where no
  /// material reads them, for the general program (generalKernelFeatures).
  bool allSurfaceAttributes = false;
  /// Read by SceneBuffers only: the scene outlives the buffers and stays
  /// unchanged, so a CPU device reads its texels in place (readOnlyBuffer).
  bool texelsInPlace = false;
  /// Read by SceneBuffers only: materials that are exactly Lambertian go to
  /// the device as the Lambertian model (kernelMaterial, scene/generators.h);
  /// false keeps their own model (A/B measurements, tests).
  bool lambertianForms = true;
};

/// Primitives [first, first + count) are a placed copy of `geometry`: the
/// same primitives in the same order as every other copy with that id, each
/// moved by the copy's transform (BvhBuilder::Auto builds one tree per
/// geometry and refits it to every copy). Copies must not overlap.
struct BvhInstance {
  std::uint32_t first = 0;
  std::uint32_t count = 0;
  std::uint32_t geometry = 0;
};

struct BvhBuildStats {
  double buildSeconds = 0.0;  ///< wall time of the whole build (buildLbvh, or the builder that made the tree)
  std::size_t nodeCount = 0;
  std::size_t leafCount = 0;
  int maxDepth = 0;           ///< root = depth 0
  double sahCost = 0.0;       ///< see sahCost()
  std::size_t copiesPlaced = 0;  ///< BvhBuilder::Auto: copies given their geometry's shared tree
  int clusterRounds = 0;         ///< BvhBuilder::Ploc: clustering rounds before the SAH pass
  /// The LBVH (and Auto, where it builds with it): regions of the scene found to be
  /// sheets across one axis (a height field) and keyed with that axis last.
  std::size_t flatRegions = 0;
};

/// std::allocator, except that resize() leaves new elements default-initialised
/// (for the node and index types, unset) instead of zeroing them: the builders
/// write every element, and zeroing a 1 M-triangle tree's nodes and indices
/// first would be a noticeable share of the build.
template <class T>
struct UninitialisedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <class U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    static_assert(std::is_trivially_default_constructible_v<U> && std::is_trivially_copyable_v<U>);
    ::new (static_cast<void*>(p)) U;
#ifndef NDEBUG
    // Debug and sanitizer builds fill new elements with a pattern, so that an
    // element a builder forgets to write fails the tests instead of reading as zero.
    std::memset(static_cast<void*>(p), 0xa5, sizeof(U));
#endif
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

using BvhNodes = std::vector<WtBvhNode, UninitialisedAllocator<WtBvhNode>>;
using PrimIndices = std::vector<std::uint32_t, UninitialisedAllocator<std::uint32_t>>;

/// nodes[0] is the root. An internal node has count == 0 and children at
/// first and first + 1; a leaf covers primIndices[first .. first+count).
/// Empty input gives no nodes.
struct Bvh {
  BvhNodes nodes;
  PrimIndices primIndices;  ///< leaf order -> input primitive index
  BvhBuildStats stats;
};

/// Build over per-primitive bounds (any geometry type). Degenerate inputs
/// (all centroids equal, one primitive, collinear) are handled.
Bvh buildLbvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {});

/// Surface-area-heuristic cost of the tree: sum over nodes of
/// area(node)/area(root) * (1 for internal nodes, count for leaves).
double sahCost(const Bvh& bvh);

}  // namespace wt
