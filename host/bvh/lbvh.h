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

struct BvhBuildOptions {
  int maxLeafSize = 4;  ///< subtrees with at most this many primitives become one leaf
  int threads = 0;      ///< 0: std::thread::hardware_concurrency()
};

struct BvhBuildStats {
  double buildSeconds = 0.0;  ///< wall time of buildLbvh
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
