// What every binary BVH over a set of boxes must satisfy, whichever builder
// made it, and the random inputs the builder tests share.
#pragma once

#include "bvh/lbvh.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <sstream>
#include <string>
#include <vector>

namespace wt::test {

inline Aabb nodeBox(const WtBvhNode& node) {
  Aabb box;
  box.lo = {node.lo_x, node.lo_y, node.lo_z};
  box.hi = {node.hi_x, node.hi_y, node.hi_z};
  return box;
}

inline bool sameBox(const Aabb& a, const Aabb& b) { return a.lo == b.lo && a.hi == b.hi; }

inline std::string describe(const Aabb& box) {
  std::ostringstream out;
  out << "[(" << box.lo.x << ", " << box.lo.y << ", " << box.lo.z << ") - (" << box.hi.x << ", " << box.hi.y << ", "
      << box.hi.z << ")]";
  return out.str();
}

/// Everything a valid tree over `prims` must satisfy. With checkBoxes off (NaN input)
/// only the topology and the primitive permutation are checked.
inline ::testing::AssertionResult checkBvhInvariants(const Bvh& bvh, std::span<const Aabb> prims, int maxLeafSize = 4,
                                              bool checkBoxes = true) {
  const std::size_t n = prims.size();
  const BvhNodes& nodes = bvh.nodes;
  if (n == 0) {
    if (!nodes.empty() || !bvh.primIndices.empty()) return ::testing::AssertionFailure() << "empty input, non-empty tree";
    return ::testing::AssertionSuccess();
  }
  if (nodes.empty()) return ::testing::AssertionFailure() << "no nodes for " << n << " primitives";
  if (bvh.primIndices.size() != n)
    return ::testing::AssertionFailure() << "primIndices has " << bvh.primIndices.size() << " entries, want " << n;

  // Topology: in-range children, every node but the root referenced exactly once.
  std::vector<int> references(nodes.size(), 0);
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const WtBvhNode& node = nodes[i];
    if (node.count > 0) continue;
    if (std::size_t(node.first) + 1 >= nodes.size())
      return ::testing::AssertionFailure() << "node " << i << " has children " << node.first << " out of range";
    if (node.first == 0) return ::testing::AssertionFailure() << "node " << i << " points at the root";
    ++references[node.first];
    ++references[node.first + 1];
  }
  for (std::size_t i = 1; i < nodes.size(); ++i)
    if (references[i] != 1)
      return ::testing::AssertionFailure() << "node " << i << " is referenced " << references[i] << " times";
  if (references[0] != 0) return ::testing::AssertionFailure() << "the root is referenced";

  // Walk from the root: every node reached once, leaves tile primIndices exactly once.
  std::vector<int> covered(n, 0);
  std::vector<std::uint32_t> subtreePrims(nodes.size(), 0);
  std::vector<char> visited(nodes.size(), 0);
  std::vector<std::pair<std::uint32_t, int>> stack{{0u, 0}};
  std::vector<std::uint32_t> order;  // preorder; reversed, children come before parents
  int depth = 0;
  std::size_t leaves = 0;
  while (!stack.empty()) {
    const auto [index, nodeDepth] = stack.back();
    stack.pop_back();
    if (visited[index]) return ::testing::AssertionFailure() << "node " << index << " reached twice";
    visited[index] = 1;
    order.push_back(index);
    depth = std::max(depth, nodeDepth);
    const WtBvhNode& node = nodes[index];
    if (node.count == 0) {
      stack.push_back({node.first, nodeDepth + 1});
      stack.push_back({node.first + 1, nodeDepth + 1});
      continue;
    }
    ++leaves;
    if (node.count > std::uint32_t(maxLeafSize))
      return ::testing::AssertionFailure() << "leaf " << index << " holds " << node.count << " > " << maxLeafSize;
    if (std::size_t(node.first) + node.count > n)
      return ::testing::AssertionFailure() << "leaf " << index << " range runs past primIndices";
    for (std::uint32_t k = node.first; k < node.first + node.count; ++k) ++covered[k];
    subtreePrims[index] = node.count;
  }
  if (order.size() != nodes.size())
    return ::testing::AssertionFailure() << order.size() << " of " << nodes.size() << " nodes reachable";
  for (std::size_t k = 0; k < n; ++k)
    if (covered[k] != 1)
      return ::testing::AssertionFailure() << "primIndices[" << k << "] is in " << covered[k] << " leaves";
  std::vector<int> seen(n, 0);
  for (std::uint32_t prim : bvh.primIndices) {
    if (prim >= n) return ::testing::AssertionFailure() << "primitive index " << prim << " out of range";
    if (seen[prim]++) return ::testing::AssertionFailure() << "primitive " << prim << " appears twice";
  }

  // Bottom-up: subtree sizes (a small subtree must have been collapsed) and boxes.
  for (auto it = order.rbegin(); it != order.rend(); ++it) {
    const std::uint32_t index = *it;
    const WtBvhNode& node = nodes[index];
    const Aabb box = nodeBox(node);
    if (node.count == 0) {
      subtreePrims[index] = subtreePrims[node.first] + subtreePrims[node.first + 1];
      if (subtreePrims[index] <= std::uint32_t(maxLeafSize))
        return ::testing::AssertionFailure() << "internal node " << index << " holds only " << subtreePrims[index]
                                             << " primitives; it should be one leaf";
      if (!checkBoxes) continue;
      Aabb tight = nodeBox(nodes[node.first]);
      tight.extend(nodeBox(nodes[node.first + 1]));
      for (std::uint32_t child : {node.first, node.first + 1})
        if (!box.contains(nodeBox(nodes[child])))
          return ::testing::AssertionFailure() << "node " << index << " " << describe(box) << " misses child "
                                               << child << " " << describe(nodeBox(nodes[child]));
      if (!sameBox(box, tight))
        return ::testing::AssertionFailure() << "node " << index << " " << describe(box) << " is not the union "
                                             << describe(tight) << " of its children";
    } else if (checkBoxes) {
      Aabb tight;
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
        const Aabb& prim = prims[bvh.primIndices[k]];
        if (!box.contains(prim))
          return ::testing::AssertionFailure() << "leaf " << index << " " << describe(box) << " misses primitive "
                                               << bvh.primIndices[k] << " " << describe(prim);
        tight.extend(prim);
      }
      if (!sameBox(box, tight))
        return ::testing::AssertionFailure() << "leaf " << index << " " << describe(box) << " is not the union "
                                             << describe(tight) << " of its primitives";
    }
  }

  if (bvh.stats.maxDepth != depth)
    return ::testing::AssertionFailure() << "stats.maxDepth " << bvh.stats.maxDepth << ", real depth " << depth;
  if (bvh.stats.nodeCount != nodes.size())
    return ::testing::AssertionFailure() << "stats.nodeCount " << bvh.stats.nodeCount << ", real " << nodes.size();
  if (bvh.stats.leafCount != leaves)
    return ::testing::AssertionFailure() << "stats.leafCount " << bvh.stats.leafCount << ", real " << leaves;
  // The build sums the cost per subtree, so it may differ from sahCost() in the last bits.
  const double cost = sahCost(bvh);
  if (!std::isfinite(cost) || !(std::abs(bvh.stats.sahCost - cost) <= 1e-9 * cost))
    return ::testing::AssertionFailure() << "stats.sahCost " << bvh.stats.sahCost << ", sahCost() " << cost;
  if (!(bvh.stats.buildSeconds >= 0.0)) return ::testing::AssertionFailure() << "negative build time";
  return ::testing::AssertionSuccess();
}

inline Aabb boxAround(const glm::vec3& center, const glm::vec3& halfSize) {
  Aabb box;
  box.lo = center - halfSize;
  box.hi = center + halfSize;
  return box;
}

/// The bounds of the scene's triangles, in triangle order.
inline std::vector<Aabb> triangleBounds(const Scene& scene) {
  std::vector<Aabb> bounds(scene.triangles.size());
  for (std::size_t i = 0; i < bounds.size(); ++i) bounds[i] = scene.triangleBounds(std::uint32_t(i));
  return bounds;
}

/// Boxes with centres uniform in [0,1)^3 and half-sizes up to maxHalf, then mapped by offset + scale * p.
inline std::vector<Aabb> randomBoxes(std::size_t n, unsigned seed, float maxHalf = 0.02f, float offset = 0.0f,
                              float scale = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Aabb> boxes(n);
  for (Aabb& box : boxes) {
    const glm::vec3 c{unit(rng), unit(rng), unit(rng)};
    const glm::vec3 h{maxHalf * unit(rng), maxHalf * unit(rng), maxHalf * unit(rng)};
    box.lo = offset + scale * (c - h);
    box.hi = offset + scale * (c + h);
  }
  return boxes;
}

}  // namespace wt::test
