// 4-wide BVH collapsed from the binary LBVH: each 4-wide node takes the two
// children of a binary node and repeatedly opens the inner child of largest
// surface area until it holds four (or only leaves are left). Leaves and the
// leaf order of the primitives are the binary tree's, unchanged.
#pragma once

#include "bvh/lbvh.h"

#include <cstddef>
#include <vector>

namespace wt {

struct Bvh4Stats {
  double collapseSeconds = 0.0;  ///< wall time of collapseToBvh4
  std::size_t nodeCount = 0;
  std::size_t leafCount = 0;
  int maxDepth = 0;              ///< root = depth 0
  double sahCost = 0.0;          ///< see sahCost(const Bvh4&)
};

/// nodes[0] is the root; children slots as WtBvh4Node describes. A binary
/// tree that is a single leaf gives one root holding that leaf; an empty one
/// gives no nodes.
struct Bvh4 {
  std::vector<WtBvh4Node> nodes;
  Bvh4Stats stats;
};

/// Collapse; bvh.primIndices stay valid for the result.
Bvh4 collapseToBvh4(const Bvh& bvh);

/// Surface-area-heuristic cost: sum over inner nodes of area(node)/area(root)
/// (one four-box test each) plus, over leaves, area(leaf)/area(root) * count.
/// The binary tree's sahCost counts one per binary node instead, so compare
/// the two with care: a 4-wide tree visits about half as many nodes.
double sahCost(const Bvh4& bvh);

/// Traversal stack entries the tree can need: at most three pushes per level.
int bvh4StackEntries(const Bvh4Stats& stats);

}  // namespace wt
