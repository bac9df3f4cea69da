// 4-wide BVH collapsed from a binary tree. Which binary nodes become 4-wide
// nodes, and which subtrees become leaves, is chosen by dynamic programming
// over the number of child slots each binary subtree may fill: the collapse
// of least cost (surface-area heuristic with the kernels' four-at-a-time
// leaf test, plus a cost per node for its memory) among all collapses of
// that binary tree (the formulation of Ylitie, Karras and Laine 2017, here
// for four slots). Leaves are whole binary subtrees, so the binary tree's
// leaf order of the primitives stays valid.
#pragma once

#include "bvh/lbvh.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace wt {

/// The 4-wide leaf limit for maxLeafSize 0 (every traversable tree unless
/// the user asks otherwise): four blocks of four triangles (one four-lane
/// test each): with triangle blocks an extra block is one cheap test, and
/// larger leaves mean fewer nodes (docs/lab/2026-12-02-performance-log.md,
/// "Triangle blocks").
constexpr int kBvh4MaxLeafSize = 16;

struct Bvh4Options {
  /// A leaf holds at most this many primitives; a binary leaf that holds
  /// more (built with larger leaves) stays whole.
  int maxLeafSize = kBvh4MaxLeafSize;
  /// Testing a leaf, per group of four primitives (one triangle_intersect4
  /// call), in units of one node's four-box test.
  double leafCost = 1.0;
  /// The cost of a node in its own right, its 128 bytes, as a fraction of
  /// one test at the root: a node is kept only where it saves more than a
  /// test by that fraction of all rays (docs/lab/2026-11-23-performance-log.md,
  /// "The 4-wide collapse", has what it measured).
  double nodeCost = 1e-4;
  /// Node memory allowed per primitive: a tree over budget is collapsed
  /// again with nodeCost doubled, up to kBudgetRounds times. 12 keeps a
  /// triangle scene within 64 bytes per triangle (52 of triangle data); 0: no budget.
  double nodeBytesPerPrimitive = 12.0;
  static constexpr int kBudgetRounds = 8;
  /// Trees of at least this many primitives are collapsed in parts, on
  /// `threads` threads (0: all the host has): the same tree for any thread
  /// count, with its nodes laid out by part (the top nodes, then each part's
  /// block) rather than depth first throughout.
  std::size_t partsFromPrimitives = 65536;
  int threads = 0;
};

struct Bvh4Stats {
  double collapseSeconds = 0.0;  ///< wall time of collapseToBvh4
  std::size_t nodeCount = 0;
  std::size_t leafCount = 0;
  int maxDepth = 0;              ///< root = depth 0
  double sahCost = 0.0;          ///< see sahCost(const Bvh4&)
  double collapseCost = 0.0;     ///< the collapse's own objective at nodeCost, see collapseCost()
  double nodeCost = 0.0;         ///< Bvh4Options::nodeCost the tree was made with (raised to meet the memory budget)
};

/// nodes[0] is the root; children slots as WtBvh4Node describes. A binary
/// tree that is a single leaf gives one root holding that leaf; an empty one
/// gives no nodes.
struct Bvh4 {
  std::vector<WtBvh4Node> nodes;
  Bvh4Stats stats;
};

/// Collapse; bvh.primIndices stay valid for the result. The binary tree's
/// nodes must hold their boxes, and a subtree's primitives must be
/// contiguous in leaf order, left child first (every builder's flatten).
Bvh4 collapseToBvh4(const Bvh& bvh, const Bvh4Options& options = {});

/// The binary build options for a traversable tree over `primitives` whose
/// leaves hold at most given.maxLeafSize primitives (0: kBvh4MaxLeafSize):
/// binary leaves of at most four, which the collapse merges where a merged
/// leaf is cheaper; from 65 536 primitives of at most eight, since there
/// the build time matters more than the small rise in collapse cost
/// (docs/lab/2026-11-23-performance-log.md, "The 4-wide collapse").
inline BvhBuildOptions binaryBuildOptions(const BvhBuildOptions& given, std::size_t primitives) {
  BvhBuildOptions options = given;
  const int binaryLeaf = primitives >= 65536 ? 8 : 4;
  options.maxLeafSize = std::min(given.maxLeafSize > 0 ? given.maxLeafSize : kBvh4MaxLeafSize, binaryLeaf);
  return options;
}

/// The collapse options that go with binaryBuildOptions(given).
inline Bvh4Options bvh4Options(const BvhBuildOptions& given) {
  Bvh4Options options;
  options.maxLeafSize = given.maxLeafSize > 0 ? given.maxLeafSize : kBvh4MaxLeafSize;
  options.threads = given.threads;
  return options;
}

/// Surface-area-heuristic cost: sum over inner nodes of area(node)/area(root)
/// (one four-box test each) plus, over leaves, area(leaf)/area(root) * count.
/// The binary tree's sahCost counts one per binary node instead, so compare
/// the two with care: a 4-wide tree visits about half as many nodes.
double sahCost(const Bvh4& bvh);

/// The objective collapseToBvh4 minimises, for any 4-wide tree: over nodes,
/// (area(node) / area(root) + options.nodeCost), plus over leaves
/// area(leaf) / area(root) * options.leafCost * ceil(count / 4).
double collapseCost(const Bvh4& bvh, const Bvh4Options& options);

/// Traversal stack entries the tree can need: at most three pushes per level,
/// and one more that the stream traversal pushes and pops at once
/// (kernels/bvh_stream.cl pushes every inner child entered, then pops one).
int bvh4StackEntries(const Bvh4Stats& stats);

/// Triangles per block of the kernels' triangle layout (WT_TRIANGLE_BLOCK,
/// shared/types.h): one four-lane test covers the lanes of one block.
constexpr std::uint32_t kTriangleBlock = 4;

struct LeafPacking {
  /// position in the packed order -> position in the order the tree's
  /// leaves addressed before (the binary tree's leaf order)
  PrimIndices order;
  /// leaves that touch more blocks than their size needs (one more four-lane
  /// test each): where no leaf that would fit is near enough in the order
  std::size_t misfits = 0;
};

/// Lay the leaves out again so that each touches as few blocks of
/// kTriangleBlock as its size allows (a leaf of 1-4 one block, of 5-8 two, ...),
/// without padding: a leaf may start inside a block when it still ends in
/// the block its size needs, so leaves whose sizes add up to a block share
/// one (3 + 1, 6 + 2, 5 + 3, ...). Leaves keep their own primitives in
/// their order, and the packed order follows the old one but for leaves
/// taken early to fill a block: at most `window` leaves ahead of the oldest
/// one not yet laid out. Points the tree's leaf slots at the new positions.
/// Deterministic. `primitives`: the number the leaves cover (a leaf set
/// that covers more or fewer throws std::logic_error).
LeafPacking packLeavesIntoBlocks(Bvh4& bvh, std::size_t primitives, std::size_t window = 256);

/// Order every node's child slots: leaves first, in their order; then the
/// inner children by the surface area of their boxes, largest first; empty
/// slots last. Closest-hit traversal sorts the children it enters by
/// distance, so only the any-hit loops (which descend into the first inner
/// child they enter and push the others) see the order: the largest box,
/// likeliest to hold a blocker, is searched first
/// (docs/lab/2026-12-01-performance-log.md, "Child slots by area"). Boxes,
/// children and leaf ranges are unchanged, only their slots.
void orderChildSlots(Bvh4& bvh);

}  // namespace wt
