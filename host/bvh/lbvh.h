// Linear BVH build on the host (Karras 2012 hierarchy over a parallel radix
// sort of Morton codes), flattened into the node layout the kernels traverse.
#pragma once

#include "core/math.h"
#include "shared/types.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace wt {

/// Which tree buildBvh (host/bvh/builders.h) makes.
enum class BvhBuilder {
  Lbvh,  ///< buildLbvh: Morton codes and the Karras hierarchy; fastest
  Ploc,  ///< buildPlocBvh: PLOC clustering in Morton order, binned SAH over the top
  Sah,   ///< buildSahBvh: top-down binned SAH; slow, the quality yardstick
};

/// The leaf size buildBvh takes for maxLeafSize 0: 4 primitives below
/// 65 536, 8 from there on. Larger leaves halve the 4-wide node count, so
/// nodes plus triangle data fit in 64 bytes per triangle, at about the same
/// throughput on large scenes; on small ones memory is no concern and
/// smaller leaves trace coherent rays faster (docs/performance.md, "Memory").
inline int autoLeafSize(std::size_t primitives) { return primitives >= 65536 ? 8 : 4; }

struct BvhBuildOptions {
  /// subtrees with at most this many primitives become one leaf; 0: autoLeafSize
  /// (buildBvh only; the builders themselves take it as given)
  int maxLeafSize = 4;
  int threads = 0;      ///< 0: std::thread::hardware_concurrency()
  BvhBuilder builder = BvhBuilder::Lbvh;  ///< read by buildBvh, not by buildLbvh
  int plocRadius = 16;  ///< Ploc: neighbours searched on each side in Morton order (1 to 64)
  /// Ploc: clustering stops where clusters average this many primitives and a
  /// binned SAH pass builds the tree above them; 0: PLOC up to the root.
  int plocTopPrims = 16;
};

struct BvhBuildStats {
  double buildSeconds = 0.0;  ///< wall time of the whole build (buildLbvh, or the builder that made the tree)
  std::size_t nodeCount = 0;
  std::size_t leafCount = 0;
  int maxDepth = 0;           ///< root = depth 0
  double sahCost = 0.0;       ///< see sahCost()
};

/// nodes[0] is the root. An internal node has count == 0 and children at
/// first and first + 1; a leaf covers primIndices[first .. first+count).
/// Empty input gives no nodes.
struct Bvh {
  std::vector<WtBvhNode> nodes;
  std::vector<std::uint32_t> primIndices;  ///< leaf order -> input primitive index
  BvhBuildStats stats;
};

/// Build over per-primitive bounds (any geometry type). Degenerate inputs
/// (all centroids equal, one primitive, collinear) are handled.
Bvh buildLbvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {});

/// Surface-area-heuristic cost of the tree: sum over nodes of
/// area(node)/area(root) * (1 for internal nodes, count for leaves).
double sahCost(const Bvh& bvh);

}  // namespace wt
