// The binary tree the SAH and PLOC builders make before it is laid out as the
// Bvh that the 4-wide collapse and the kernels read.
#pragma once

#include "bvh/lbvh.h"

#include <cstdint>
#include <span>
#include <memory>
#include <utility>
#include <vector>

namespace wt::bvh_detail {

struct BuildNode {
  Aabb box;                 ///< exact union of the children's boxes, or of the leaf's primitives
  std::uint32_t left = 0;   ///< internal: BuildNode index of a child
  std::uint32_t right = 0;
  std::uint32_t first = 0;  ///< leaf: prims[first .. first + count) of layoutTree's list
  std::uint32_t count = 0;  ///< 0: internal
};

/// A node's box, and the box written into a node.
inline Aabb nodeBox(const WtBvhNode& node) {
  Aabb box;
  box.lo = {node.lo_x, node.lo_y, node.lo_z};
  box.hi = {node.hi_x, node.hi_y, node.hi_z};
  return box;
}
inline void setBox(WtBvhNode& node, const Aabb& box) {
  node.lo_x = box.lo.x, node.lo_y = box.lo.y, node.lo_z = box.lo.z;
  node.hi_x = box.hi.x, node.hi_y = box.hi.y, node.hi_z = box.hi.z;
}

/// Make nodes[parent] an inner node whose two children are appended to
/// `nodes` as a pair (the layout every builder gives); returns the first.
inline std::uint32_t appendChildPair(BvhNodes& nodes, std::uint32_t parent) {
  const std::uint32_t pair = std::uint32_t(nodes.size());
  nodes[parent].first = pair;
  nodes[parent].count = 0;
  nodes.emplace_back();
  nodes.emplace_back();
  return pair;
}

/// Lay the tree below `root` out depth first as Bvh nodes: a node's children
/// are appended as a pair when it is opened and its left subtree is laid out
/// next (as buildLbvh does). A subtree of at most maxLeaf primitives becomes
/// one leaf, as in buildLbvh. primIndices list the leaves' primitives in
/// layout order; stats are filled but buildSeconds.
Bvh layoutTree(std::span<const BuildNode> nodes, std::uint32_t root, std::span<const std::uint32_t> prims,
               std::uint32_t maxLeaf);

/// A subtree the top SAH pass treats as one item.
struct TopCluster {
  Aabb box;
  std::uint32_t node;   ///< BuildNode index
  std::uint32_t prims;  ///< primitives below: the SAH weight
};

/// Binned SAH (32 bins, three axes) top down over the clusters, weighted by
/// their primitive counts, on up to `threads` threads. The inner nodes go to
/// nodes[first .. first + clusters.size() - 1): a subtree over m clusters owns
/// m - 1 consecutive slots (its root, then its descendants'), so the numbering
/// does not depend on which thread builds what; their children are the other
/// slots or the clusters' nodes. Returns the root: nodes[first] unless there
/// is a single cluster. Reorders `clusters`.
std::uint32_t buildTopSah(std::vector<TopCluster>& clusters, std::vector<BuildNode>& nodes, std::uint32_t first,
                          int threads);

/// Input indices sorted by the Morton code of their centroids, as buildLbvh
/// sorts them (ties in index order).
std::vector<std::uint32_t> mortonOrder(std::span<const Aabb> primBounds, int threads);

/// The LBVH's keys of large inputs, for tests: each primitive's Morton key,
/// its key with flat patches reordered (host/bvh/lbvh.cpp), and the key
/// ranges of the candidate regions that were re-keyed or kept in Morton order.
struct FlatPatchKeys {
  std::vector<std::uint64_t> morton, keys;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> accepted, rejected;
};
FlatPatchKeys flatPatchKeys(std::span<const Aabb> primBounds, int threads);

/// The LBVH's key sort, for tests: keys[0..n) ascending, primIndices[i] the
/// input position of sorted key i, equal keys in input order (a stable sort).
void sortKeysWithIndices(int threads, std::size_t n, std::unique_ptr<std::uint64_t[]>& keys,
                         std::vector<std::uint32_t>& primIndices);

/// options.threads resolved as buildLbvh does: 0 means every hardware thread,
/// and no more threads than work for them.
int builderThreads(const BvhBuildOptions& options, std::size_t prims);

}  // namespace wt::bvh_detail
