#include "bvh/build_tree.h"

#include "bvh/parallel.h"

#include <algorithm>

namespace wt::bvh_detail {

Bvh layoutTree(std::span<const BuildNode> nodes, std::uint32_t root, std::span<const std::uint32_t> prims,
               std::uint32_t maxLeaf) {
  Bvh bvh;
  if (nodes.empty()) return bvh;

  // subtree primitive counts, children before parents (reversed preorder)
  std::vector<std::uint32_t> subtree(nodes.size(), 0);
  std::vector<std::uint32_t> order;
  order.reserve(nodes.size());
  std::vector<std::uint32_t> stack{root};
  while (!stack.empty()) {
    std::uint32_t b = stack.back();
    stack.pop_back();
    order.push_back(b);
    if (nodes[b].count == 0) stack.push_back(nodes[b].left), stack.push_back(nodes[b].right);
  }
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    const BuildNode& b = nodes[*it];
    subtree[*it] = b.count > 0 ? b.count : subtree[b.left] + subtree[b.right];
  }

  bvh.nodes.reserve(2 * std::size_t(subtree[root]) / std::max<std::uint32_t>(maxLeaf, 1) + 1);
  bvh.primIndices.reserve(subtree[root]);
  struct Open {
    std::uint32_t build, out;
    int depth;
  };
  std::vector<Open> open{{root, 0, 0}};
  bvh.nodes.emplace_back();
  std::vector<std::uint32_t> gather;
  while (!open.empty()) {
    const Open o = open.back();
    open.pop_back();
    const BuildNode& b = nodes[o.build];
    bvh.stats.maxDepth = std::max(bvh.stats.maxDepth, o.depth);
    setBox(bvh.nodes[o.out], b.box);
    if (b.count > 0 || subtree[o.build] <= maxLeaf) {
      // a leaf: the primitives of every build leaf below, left to right
      WtBvhNode& leaf = bvh.nodes[o.out];
      leaf.first = std::uint32_t(bvh.primIndices.size());
      leaf.count = subtree[o.build];
      gather.assign(1, o.build);
      while (!gather.empty()) {
        const BuildNode& g = nodes[gather.back()];
        gather.pop_back();
        if (g.count > 0)
          bvh.primIndices.insert(bvh.primIndices.end(), prims.begin() + g.first, prims.begin() + g.first + g.count);
        else
          gather.push_back(g.right), gather.push_back(g.left);
      }
      ++bvh.stats.leafCount;
      continue;
    }
    const std::uint32_t pair = appendChildPair(bvh.nodes, o.out);
    open.push_back({b.right, pair + 1, o.depth + 1});
    open.push_back({b.left, pair, o.depth + 1});
  }
  bvh.stats.nodeCount = bvh.nodes.size();
  bvh.stats.sahCost = sahCost(bvh);
  return bvh;
}

int builderThreads(const BvhBuildOptions& options, std::size_t prims) {
  return teamThreads(options.threads, prims);  // as buildLbvh
}

}  // namespace wt::bvh_detail
