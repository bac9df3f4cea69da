// 4-wide collapse of a binary tree: structural invariants (every primitive
// in exactly one leaf, every leaf a whole binary subtree within the leaf
// limit, boxes containing what they hold, empty slots inverted), the
// collapse's optimality (against every collapse of small trees, and against
// the greedy collapse it replaced on real meshes), regression bounds, and
// the leaves' layout in blocks of four triangles (packLeavesIntoBlocks).
#include "bvh/bvh4.h"
#include "bvh/builders.h"
#include "bvh/bvh_checks.h"
#include "device/scene_buffers.h"
#include "geometry/primitives.h"
#include "scene/generators.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <unordered_map>
#include <random>
#include <utility>
#include <vector>

namespace wt {
namespace {

using test::triangleBounds;

Aabb slotBox(const WtBvh4Node& node, int k) {
  Aabb box;
  box.lo = {node.lo_x[k], node.lo_y[k], node.lo_z[k]};
  box.hi = {node.hi_x[k], node.hi_y[k], node.hi_z[k]};
  return box;
}

/// The primitive range (first, count) of every binary subtree, with its node.
std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> subtreeRanges(const Bvh& binary) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> ranges;
  std::function<std::pair<std::uint32_t, std::uint32_t>(std::uint32_t)> walk = [&](std::uint32_t i) {
    const WtBvhNode& node = binary.nodes[i];
    std::pair<std::uint32_t, std::uint32_t> range{node.first, node.count};
    if (node.count == 0) {
      const auto left = walk(node.first), right = walk(node.first + 1);
      range = {left.first, left.first + left.second == right.first ? left.second + right.second : 0u};
    }
    if (range.second > 0) ranges[range] = i;
    return range;
  };
  if (!binary.nodes.empty()) walk(0);
  return ranges;
}

/// Walk the 4-wide tree: every node reached once, every primitive of the
/// binary tree in exactly one leaf, every leaf a whole binary subtree (its
/// box) of at most maxLeaf primitives or one binary leaf, inner boxes
/// containing their children's, empty slots inverted and last.
::testing::AssertionResult checkBvh4(const Bvh4& tree, const Bvh& binary, std::span<const Aabb> prims,
                                     int maxLeaf = kBvh4MaxLeafSize) {
  const std::size_t n = binary.primIndices.size();
  if (n == 0) return tree.nodes.empty() ? ::testing::AssertionSuccess() : ::testing::AssertionFailure() << "nodes for no primitives";
  const auto ranges = subtreeRanges(binary);
  std::vector<int> covered(n, 0);
  std::vector<int> reached(tree.nodes.size(), 0);
  std::vector<std::pair<std::uint32_t, int>> stack{{0u, 0}};
  int depth = 0;
  std::size_t leaves = 0;
  while (!stack.empty()) {
    auto [index, d] = stack.back();
    stack.pop_back();
    if (index >= tree.nodes.size()) return ::testing::AssertionFailure() << "node " << index << " out of range";
    if (reached[index]++) return ::testing::AssertionFailure() << "node " << index << " reached twice";
    depth = std::max(depth, d);
    const WtBvh4Node& node = tree.nodes[index];
    bool sawEmpty = false;
    int used = 0;
    for (int k = 0; k < 4; ++k) {
      const Aabb box = slotBox(node, k);
      if (node.child[k] == WT_BVH4_EMPTY) {
        sawEmpty = true;
        if (!(box.lo.x == INFINITY && box.lo.y == INFINITY && box.lo.z == INFINITY && box.hi.x == -INFINITY &&
              box.hi.y == -INFINITY && box.hi.z == -INFINITY && node.count[k] == 0))
          return ::testing::AssertionFailure() << "node " << index << " slot " << k << " is empty but not inverted";
        continue;
      }
      if (sawEmpty) return ::testing::AssertionFailure() << "node " << index << " has a child after an empty slot";
      ++used;
      if (node.count[k] > 0) {
        ++leaves;
        const auto subtree = ranges.find({node.child[k], node.count[k]});
        if (subtree == ranges.end())
          return ::testing::AssertionFailure() << "leaf in node " << index << " slot " << k << " is no binary subtree";
        const WtBvhNode& b = binary.nodes[subtree->second];
        if (node.count[k] > std::uint32_t(maxLeaf) && b.count == 0)
          return ::testing::AssertionFailure() << "leaf in node " << index << " holds " << node.count[k] << " > " << maxLeaf;
        if (!(box.lo == glm::vec3(b.lo_x, b.lo_y, b.lo_z) && box.hi == glm::vec3(b.hi_x, b.hi_y, b.hi_z)))
          return ::testing::AssertionFailure() << "leaf box in node " << index << " is not its subtree's";
        for (std::uint32_t p = node.child[k]; p < node.child[k] + node.count[k]; ++p) {
          if (p >= n) return ::testing::AssertionFailure() << "leaf runs past the primitives";
          ++covered[p];
          if (!box.contains(prims[binary.primIndices[p]]))
            return ::testing::AssertionFailure() << "leaf box in node " << index << " misses primitive " << p;
        }
      } else {
        const WtBvh4Node& child = tree.nodes.at(node.child[k]);
        for (int c = 0; c < 4; ++c)
          if (child.child[c] != WT_BVH4_EMPTY && !box.contains(slotBox(child, c)))
            return ::testing::AssertionFailure() << "node " << index << " slot " << k << " misses a grandchild";
        stack.push_back({node.child[k], d + 1});
      }
    }
    // a binary tree of more than one leaf gives every node at least two
    // children, unless the whole tree became the root's one leaf
    const bool rootLeaf = index == 0 && used == 1 && node.count[0] > 0;
    if (binary.nodes.size() > 1 && used < 2 && !rootLeaf)
      return ::testing::AssertionFailure() << "node " << index << " has " << used << " children";
  }
  for (std::size_t i = 0; i < tree.nodes.size(); ++i)
    if (reached[i] != 1) return ::testing::AssertionFailure() << "node " << i << " reached " << reached[i] << " times";
  for (std::size_t p = 0; p < n; ++p)
    if (covered[p] != 1) return ::testing::AssertionFailure() << "primitive slot " << p << " in " << covered[p] << " leaves";
  if (leaves != tree.stats.leafCount)
    return ::testing::AssertionFailure() << leaves << " leaves, stats say " << tree.stats.leafCount;
  if (leaves > binary.stats.leafCount)
    return ::testing::AssertionFailure() << leaves << " leaves, the binary tree has only " << binary.stats.leafCount;
  if (depth != tree.stats.maxDepth)
    return ::testing::AssertionFailure() << "depth " << depth << ", stats say " << tree.stats.maxDepth;
  return ::testing::AssertionSuccess();
}

TEST(Bvh4, EmptyTreeGivesNoNodes) {
  Bvh binary;
  EXPECT_TRUE(collapseToBvh4(binary).nodes.empty());
  EXPECT_EQ(sahCost(collapseToBvh4(binary)), 0.0);
}

TEST(Bvh4, RootLeafBecomesOneSlot) {
  Scene scene = makeTriangleSoup(3, 1);
  std::vector<Aabb> prims = triangleBounds(scene);
  Bvh binary = buildLbvh(prims);
  ASSERT_EQ(binary.nodes.size(), 1u);
  Bvh4 tree = collapseToBvh4(binary);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(tree.nodes[0].count[0], 3u);
  EXPECT_TRUE(checkBvh4(tree, binary, prims));
}

TEST(Bvh4, InvariantsOnSoupsAndLeafSizes) {
  for (int leafSize : {1, 2, 4, 8})
    for (std::uint32_t count : {2u, 5u, 17u, 1000u, 30000u}) {
      Scene scene = makeTriangleSoup(count, count + leafSize, 0.2f);
      std::vector<Aabb> prims = triangleBounds(scene);
      BvhBuildOptions options;
      options.maxLeafSize = leafSize;
      Bvh binary = buildLbvh(prims, options);
      for (int wideLeaf : {1, 3, 8, 16}) {
        Bvh4Options wide;
        wide.maxLeafSize = wideLeaf;
        Bvh4 tree = collapseToBvh4(binary, wide);
        EXPECT_TRUE(checkBvh4(tree, binary, prims, wideLeaf))
            << count << " triangles, leaf size " << leafSize << ", 4-wide leaves of " << wideLeaf;
        // a 4-wide node covers at least one binary level, so the tree is never deeper
        EXPECT_LE(tree.stats.maxDepth, binary.stats.maxDepth) << count << " triangles, leaf size " << leafSize;
        EXPECT_LE(bvh4StackEntries(tree.stats), 3 * (binary.stats.maxDepth + 1) + 1);
      }
    }
}

// Two unit cubes side by side (the root box 2x1x1, area 10; each cube area 6),
// one triangle each: one test of both at the root's area (10) is cheaper than
// a test of each (6 + 6), so they become one leaf. Pulled apart (the root box
// 10x1x1, area 42) they stay two leaves.
Bvh twoCubes(float gap) {
  Bvh binary;
  binary.nodes = {WtBvhNode{0, 0, 0, 1, 2 + gap, 1, 1, 0}, WtBvhNode{0, 0, 0, 0, 1, 1, 1, 1},
                  WtBvhNode{1 + gap, 0, 0, 1, 2 + gap, 1, 1, 1}};
  binary.primIndices = {0, 1};
  binary.stats.leafCount = 2;
  return binary;
}

TEST(Bvh4, NeighbouringLeavesMergeWhenOneTestIsCheaper) {
  Bvh4Options options;
  options.nodeCost = 0.0;
  options.nodeBytesPerPrimitive = 0.0;  // one node for two triangles is over any budget
  Bvh4 tree = collapseToBvh4(twoCubes(0.0f), options);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(tree.nodes[0].count[0], 2u);
  EXPECT_EQ(tree.nodes[0].child[1], WT_BVH4_EMPTY);
  EXPECT_DOUBLE_EQ(tree.stats.collapseCost, 1.0 + 10.0 / 10.0);
  EXPECT_DOUBLE_EQ(sahCost(tree), 1.0 + 2.0 * 10.0 / 10.0);  // per triangle, as documented

  // leaves of one: no merging
  options.maxLeafSize = 1;
  tree = collapseToBvh4(twoCubes(0.0f), options);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(tree.nodes[0].count[0], 1u);
  EXPECT_EQ(tree.nodes[0].count[1], 1u);
  EXPECT_DOUBLE_EQ(tree.stats.collapseCost, 1.0 + (6.0 + 6.0) / 10.0);
}

TEST(Bvh4, DistantLeavesStaySeparate) {
  Bvh4Options options;
  options.nodeBytesPerPrimitive = 0.0;
  Bvh4 tree = collapseToBvh4(twoCubes(8.0f), options);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_EQ(tree.nodes[0].count[0], 1u);
  EXPECT_EQ(tree.nodes[0].count[1], 1u);
  EXPECT_DOUBLE_EQ(sahCost(tree), 1.0 + (6.0 + 6.0) / 42.0);
  EXPECT_NEAR(tree.stats.collapseCost, 1.0 + Bvh4Options{}.nodeCost + (6.0 + 6.0) / 42.0, 1e-12);
}

/// The least collapseCost over every collapse of a small binary tree, by
/// brute force: each binary node is labelled a 4-wide node, a leaf, or
/// dissolved (its children take its place among its parent's slots), and
/// every labelling that makes a valid tree is costed.
double bruteForceCollapseCost(const Bvh& binary, const Bvh4Options& options) {
  const std::size_t n = binary.nodes.size();
  std::vector<std::uint32_t> prims(n);
  std::vector<double> area(n);
  std::function<void(std::uint32_t)> measure = [&](std::uint32_t i) {
    const WtBvhNode& node = binary.nodes[i];
    area[i] = 2.0 * (double(node.hi_x - node.lo_x) * (node.hi_y - node.lo_y) +
                     double(node.hi_y - node.lo_y) * (node.hi_z - node.lo_z) +
                     double(node.hi_z - node.lo_z) * (node.hi_x - node.lo_x));
    if (node.count > 0) {
      prims[i] = node.count;
      return;
    }
    measure(node.first), measure(node.first + 1);
    prims[i] = prims[node.first] + prims[node.first + 1];
  };
  measure(0);
  enum Label { kNode, kLeaf, kDissolved };
  const double rootArea = area[0];
  auto leafCost = [&](std::uint32_t i) { return area[i] / rootArea * options.leafCost * double((prims[i] + 3) / 4); };
  const auto maxLeaf = std::uint32_t(options.maxLeafSize);
  std::vector<int> label(n);
  double best = std::numeric_limits<double>::infinity();
  std::size_t labellings = 1;
  for (std::size_t i = 0; i < n; ++i) labellings *= 3;
  for (std::size_t code = 0; code < labellings; ++code) {
    std::size_t c = code;
    for (std::size_t i = 0; i < n; ++i) label[i] = int(c % 3), c /= 3;
    // the slots of a 4-wide node: its children, through dissolved ones
    bool valid = true;
    std::function<void(std::uint32_t, std::vector<std::uint32_t>&)> slotsOf = [&](std::uint32_t i,
                                                                               std::vector<std::uint32_t>& out) {
      for (std::uint32_t child : {binary.nodes[i].first, binary.nodes[i].first + 1}) {
        if (label[child] == kDissolved && binary.nodes[child].count == 0) slotsOf(child, out);
        else if (label[child] == kDissolved) valid = false;
        else out.push_back(child);
      }
    };
    std::function<double(std::uint32_t)> nodeCost = [&](std::uint32_t i) -> double {
      std::vector<std::uint32_t> slots;
      slotsOf(i, slots);
      if (slots.size() > 4) valid = false;
      double cost = 0.0;
      for (std::uint32_t s : slots) {
        const bool binaryLeaf = binary.nodes[s].count > 0;
        if (label[s] == kLeaf) {
          if (prims[s] > maxLeaf && !binaryLeaf) valid = false;
          cost += leafCost(s);
        } else if (binaryLeaf) {
          valid = false;  // a binary leaf cannot be a node
        } else {
          cost += area[s] / rootArea + options.nodeCost + nodeCost(s);
        }
      }
      return cost;
    };
    double cost = 1.0 + options.nodeCost;  // the root's test
    if (label[0] == kLeaf) {
      if (prims[0] > maxLeaf && binary.nodes[0].count == 0) continue;
      cost += leafCost(0);
    } else if (label[0] == kNode && binary.nodes[0].count == 0) {
      cost += nodeCost(0);
    } else {
      continue;
    }
    if (valid) best = std::min(best, cost);
  }
  return best;
}

TEST(Bvh4, CollapseIsTheCheapestOfAllCollapsesOnSmallTrees) {
  int cases = 0;
  for (std::uint32_t count : {2u, 3u, 4u, 5u})  // 5 leaves: more than four slots, so nodes nest
    for (int seed = 0; seed < int(test::testSize(8, 2)); ++seed) {
      Scene scene = makeTriangleSoup(count, 100 * count + seed, 0.3f + 0.2f * float(seed));
      std::vector<Aabb> prims = triangleBounds(scene);
      BvhBuildOptions binaryOptions;
      binaryOptions.maxLeafSize = 1;
      Bvh binary = buildLbvh(prims, binaryOptions);
      for (int maxLeaf : {1, 2, 3, 8})
        for (double leafCost : {0.5, 1.0, 3.0})
          for (double nodeCost : {0.0, 1e-4, 0.05, 0.5}) {
            Bvh4Options options;
            options.maxLeafSize = maxLeaf;
            options.leafCost = leafCost;
            options.nodeCost = nodeCost;
            options.nodeBytesPerPrimitive = 0.0;  // no budget: the cost as given
            Bvh4 tree = collapseToBvh4(binary, options);
            ASSERT_TRUE(checkBvh4(tree, binary, prims, maxLeaf));
            const double best = bruteForceCollapseCost(binary, options);
            EXPECT_NEAR(tree.stats.collapseCost, best, 1e-5 * best)
                << count << " triangles, seed " << seed << ", leaves of " << maxLeaf << ", leaf cost " << leafCost
                << ", node cost " << nodeCost;
            ++cases;
          }
    }
  EXPECT_EQ(cases, 4 * int(test::testSize(8, 2)) * 4 * 3 * 4);
}

/// The collapse this one replaced: each 4-wide node takes a binary node's two
/// children and opens the inner child of largest area until it holds four;
/// leaves stay the binary tree's.
Bvh4 greedyCollapse(const Bvh& bvh) {
  Bvh4 out;
  const auto area = [](const WtBvhNode& n) {
    return 2.0 * (double(n.hi_x - n.lo_x) * (n.hi_y - n.lo_y) + double(n.hi_y - n.lo_y) * (n.hi_z - n.lo_z) +
                  double(n.hi_z - n.lo_z) * (n.hi_x - n.lo_x));
  };
  WtBvh4Node empty;
  for (int k = 0; k < 4; ++k) {
    empty.lo_x[k] = empty.lo_y[k] = empty.lo_z[k] = INFINITY;
    empty.hi_x[k] = empty.hi_y[k] = empty.hi_z[k] = -INFINITY;
    empty.child[k] = WT_BVH4_EMPTY;
    empty.count[k] = 0;
  }
  auto setSlot = [](WtBvh4Node& node, int k, const WtBvhNode& box, std::uint32_t child, std::uint32_t count) {
    node.lo_x[k] = box.lo_x, node.lo_y[k] = box.lo_y, node.lo_z[k] = box.lo_z;
    node.hi_x[k] = box.hi_x, node.hi_y[k] = box.hi_y, node.hi_z[k] = box.hi_z;
    node.child[k] = child;
    node.count[k] = count;
  };
  out.nodes.push_back(empty);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{0u, 0u}};  // binary, 4-wide
  while (!stack.empty()) {
    auto [binaryIndex, node] = stack.back();
    stack.pop_back();
    std::vector<std::uint32_t> kids{bvh.nodes[binaryIndex].first, bvh.nodes[binaryIndex].first + 1};
    while (kids.size() < 4) {
      int open = -1;
      for (int k = 0; k < int(kids.size()); ++k)
        if (bvh.nodes[kids[k]].count == 0 && (open < 0 || area(bvh.nodes[kids[k]]) > area(bvh.nodes[kids[open]])))
          open = k;
      if (open < 0) break;
      const std::uint32_t opened = kids[open];
      kids[open] = bvh.nodes[opened].first;
      kids.push_back(bvh.nodes[opened].first + 1);
    }
    for (int k = 0; k < int(kids.size()); ++k) {
      const WtBvhNode& kid = bvh.nodes[kids[k]];
      if (kid.count > 0) {
        setSlot(out.nodes[node], k, kid, kid.first, kid.count);
      } else {
        out.nodes.push_back(empty);
        setSlot(out.nodes[node], k, kid, std::uint32_t(out.nodes.size() - 1), 0);
        stack.push_back({kids[k], std::uint32_t(out.nodes.size() - 1)});
      }
    }
  }
  return out;
}

TEST(Bvh4, CollapseCostsNoMoreThanTheGreedyCollapse) {
  const std::vector<std::pair<const char*, Scene>> meshes = {
      {"bumpy grid 50k", makeBumpyGrid(50000)},
      {"icosphere 5", makeIcosphere(5, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)))},
      {"soup 20k", makeTriangleSoup(20000, 3, 0.05f)}};
  for (const auto& [name, scene] : meshes)
    for (int leafSize : {1, 4}) {
      std::vector<Aabb> prims = triangleBounds(scene);
      BvhBuildOptions options;
      options.maxLeafSize = leafSize;
      Bvh binary = buildLbvh(prims, options);
      Bvh4 tree = collapseToBvh4(binary);
      ASSERT_TRUE(checkBvh4(tree, binary, prims)) << name;
      // the stats hold the objective of the tree made, and the greedy tree is one of those it chose from
      Bvh4Options used;
      used.nodeCost = tree.stats.nodeCost;
      EXPECT_NEAR(tree.stats.collapseCost, collapseCost(tree, used), 1e-9 * tree.stats.collapseCost);
      const double greedy = collapseCost(greedyCollapse(binary), used);
      EXPECT_LE(tree.stats.collapseCost, greedy * (1.0 + 1e-6)) << name << ", leaves of " << leafSize;
      RecordProperty(std::string(name) + " leaf " + std::to_string(leafSize), std::to_string(tree.stats.collapseCost) + " vs greedy " + std::to_string(greedy));
    }
}

TEST(Bvh4, TraversableTreesFitIn64BytesPerTriangle) {
  // 52 bytes of triangle data (three float4 corners, a material index) leave
  // 12 for nodes: the collapse's budget, met small and large
  const auto nodeBytes = [](const Bvh4& tree, std::size_t prims) {
    return double(tree.nodes.size() * sizeof(WtBvh4Node)) / double(prims);
  };
  BvhBuildOptions given;
  given.maxLeafSize = 0;  // as the renderer passes it
  for (const Scene& scene : {makeBumpyGrid(15000), makeIcosphere(5, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f))),
                             makeBumpyGrid(200000), makeIcosphere(6, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)))}) {
    std::vector<Aabb> prims = triangleBounds(scene);
    Bvh binary = buildBvh(prims, binaryBuildOptions(given, prims.size()));
    Bvh4 tree = collapseToBvh4(binary, bvh4Options(given));
    EXPECT_TRUE(checkBvh4(tree, binary, prims, kBvh4MaxLeafSize));
    EXPECT_LE(nodeBytes(tree, prims.size()), 12.0) << prims.size();
  }
  // the budget is what keeps the small grid within it (13.7 B/tri without)
  std::vector<Aabb> prims = triangleBounds(makeBumpyGrid(15000));
  Bvh binary = buildBvh(prims, binaryBuildOptions(given, prims.size()));
  Bvh4Options unbounded = bvh4Options(given);
  unbounded.nodeBytesPerPrimitive = 0.0;
  Bvh4 loose = collapseToBvh4(binary, unbounded), tight = collapseToBvh4(binary, bvh4Options(given));
  EXPECT_GT(nodeBytes(loose, prims.size()), 12.0);
  EXPECT_EQ(loose.stats.nodeCost, Bvh4Options{}.nodeCost);
  EXPECT_GT(tight.stats.nodeCost, loose.stats.nodeCost);
}

/// The tree as its slots read depth first from the root, whatever the node order.
std::vector<std::array<float, 8>> canonical(const Bvh4& tree) {
  std::vector<std::array<float, 8>> slots;
  std::vector<std::uint32_t> stack;
  if (!tree.nodes.empty()) stack.push_back(0);
  while (!stack.empty()) {
    const WtBvh4Node& node = tree.nodes[stack.back()];
    stack.pop_back();
    for (int k = 3; k >= 0; --k)
      if (node.child[k] != WT_BVH4_EMPTY && node.count[k] == 0) stack.push_back(node.child[k]);
    for (int k = 0; k < 4; ++k) {
      const bool leaf = node.count[k] > 0;
      slots.push_back({node.lo_x[k], node.lo_y[k], node.lo_z[k], node.hi_x[k], node.hi_y[k], node.hi_z[k],
                       leaf ? float(node.child[k]) : -1.0f, float(node.count[k])});
    }
  }
  return slots;
}

TEST(Bvh4, PartsGiveTheSameTreeOnAnyThreadCount) {
  // large trees are evaluated and laid out in parts on threads: the same
  // nodes byte for byte on 1, 2 or 3 threads, and the same tree as the
  // collapse in one piece, in another order
  BvhBuildOptions given;
  given.maxLeafSize = 0;
  std::vector<Aabb> prims = triangleBounds(makeBumpyGrid(200000));
  Bvh binary = buildBvh(prims, binaryBuildOptions(given, prims.size()));
  Bvh4Options whole = bvh4Options(given);
  whole.partsFromPrimitives = std::numeric_limits<std::size_t>::max();
  const Bvh4 reference = collapseToBvh4(binary, whole);
  ASSERT_TRUE(checkBvh4(reference, binary, prims));
  std::vector<Bvh4> inParts;
  for (int threads : {1, 2, 3}) {
    Bvh4Options options = bvh4Options(given);
    options.threads = threads;
    ASSERT_LE(options.partsFromPrimitives, prims.size());
    inParts.push_back(collapseToBvh4(binary, options));
    const Bvh4& tree = inParts.back();
    ASSERT_TRUE(checkBvh4(tree, binary, prims)) << threads << " threads";
    EXPECT_EQ(tree.stats.nodeCount, reference.stats.nodeCount);
    EXPECT_EQ(tree.stats.leafCount, reference.stats.leafCount);
    EXPECT_EQ(tree.stats.maxDepth, reference.stats.maxDepth);
    // summed in node order: equal but for rounding
    EXPECT_NEAR(tree.stats.collapseCost, reference.stats.collapseCost, 1e-12 * reference.stats.collapseCost);
    EXPECT_TRUE(canonical(tree) == canonical(reference)) << threads << " threads";
  }
  // the parts do reorder the nodes (or this test would not see them)
  EXPECT_NE(std::memcmp(inParts[0].nodes.data(), reference.nodes.data(), reference.nodes.size() * sizeof(WtBvh4Node)), 0);
  for (std::size_t t = 1; t < inParts.size(); ++t)
    EXPECT_EQ(std::memcmp(inParts[t].nodes.data(), inParts[0].nodes.data(), inParts[0].nodes.size() * sizeof(WtBvh4Node)), 0);
  // small and shallow trees in parts (fewer levels than the split depth, a root leaf)
  for (std::size_t count : {1u, 2u, 5u, 40u, 3000u}) {
    std::vector<Aabb> soup(prims.begin(), prims.begin() + std::ptrdiff_t(count));
    Bvh small = buildBvh(soup, binaryBuildOptions(given, soup.size()));
    Bvh4Options parts = bvh4Options(given), one = bvh4Options(given);
    parts.partsFromPrimitives = 0;
    one.partsFromPrimitives = std::numeric_limits<std::size_t>::max();
    const Bvh4 a = collapseToBvh4(small, parts), b = collapseToBvh4(small, one);
    EXPECT_TRUE(checkBvh4(a, small, soup)) << count;
    EXPECT_TRUE(canonical(a) == canonical(b)) << count;
  }
}

// ---- SAH regression --------------------------------------------------------------
// Fixed meshes, fixed builds: the costs below were measured when the collapse
// was written (binary LBVH with leaves of <= 4, then the collapse with its
// default options). A change to the LBVH or the collapse that makes the tree
// worse by more than 2% fails here; one that makes it better should lower the bound.

struct SahCase {
  const char* name;
  double binaryMeasured, bvh4Measured;
};

double binarySah(const Scene& scene, Bvh4* collapsed) {
  std::vector<Aabb> prims = triangleBounds(scene);
  Bvh binary = buildLbvh(prims);
  *collapsed = collapseToBvh4(binary);
  EXPECT_TRUE(checkBvh4(*collapsed, binary, prims));
  return binary.stats.sahCost;
}

/// packLeavesIntoBlocks(after) of the tree `before`: nodes the same but for
/// leaf slots, every leaf the same primitives in the same order at its new
/// place, the order a permutation, and misfits counted as they are.
testing::AssertionResult checkPacking(const Bvh4& before, const Bvh4& after, const LeafPacking& packing,
                                      std::size_t prims) {
  if (packing.order.size() != prims) return testing::AssertionFailure() << "order holds " << packing.order.size();
  std::vector<int> seen(prims, 0);
  for (std::uint32_t p : packing.order) {
    if (p >= prims || seen[p]++) return testing::AssertionFailure() << "order repeats or leaves the range: " << p;
  }
  if (after.nodes.size() != before.nodes.size()) return testing::AssertionFailure() << "node count changed";
  std::size_t misfits = 0;
  for (std::size_t n = 0; n < before.nodes.size(); ++n) {
    WtBvh4Node a = before.nodes[n], b = after.nodes[n];
    for (int k = 0; k < 4; ++k) {
      if (a.count[k] == 0) continue;
      const std::uint32_t first = b.child[k], count = a.count[k];
      if (first + count > prims) return testing::AssertionFailure() << "node " << n << " slot " << k << " leaves the range";
      for (std::uint32_t i = 0; i < count; ++i)
        if (packing.order[first + i] != a.child[k] + i)
          return testing::AssertionFailure() << "node " << n << " slot " << k << " lost its primitive " << i;
      const std::uint32_t blocks = (first + count - 1) / kTriangleBlock - first / kTriangleBlock + 1;
      misfits += blocks > (count + kTriangleBlock - 1) / kTriangleBlock;
      a.child[k] = b.child[k];
    }
    if (std::memcmp(&a, &b, sizeof a) != 0) return testing::AssertionFailure() << "node " << n << " changed beyond leaf slots";
  }
  if (misfits != packing.misfits)
    return testing::AssertionFailure() << "misfits reported " << packing.misfits << ", counted " << misfits;
  return testing::AssertionSuccess();
}

TEST(Bvh4, LeavesPackIntoBlocksWithTheirPrimitives) {
  // over the LBVH's trees, which the bound was measured on (PLOC's, which the
  // auto builder makes below 65 536 triangles, have other leaf sizes: 894
  // misfits of about 5 430 leaves on the level-5 icosphere, 2026-12-04)
  BvhBuildOptions given;
  given.builder = BvhBuilder::Lbvh;
  given.maxLeafSize = 0;
  for (const Scene& scene : {makeBumpyGrid(15000), makeIcosphere(5, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f))),
                             makeTriangleSoup(5000, 7), makeBumpyGrid(200000)}) {
    std::vector<Aabb> prims = triangleBounds(scene);
    Bvh binary = buildBvh(prims, binaryBuildOptions(given, prims.size()));
    const Bvh4 before = collapseToBvh4(binary, bvh4Options(given));
    Bvh4 after = before;
    const LeafPacking packing = packLeavesIntoBlocks(after, prims.size());
    EXPECT_TRUE(checkPacking(before, after, packing, prims.size())) << prims.size() << " triangles";
    // regression bound. Measured 2026-12-02: 0.7-11% of the leaves, at or
    // within 2 of the least the leaf sizes allow without padding (leaves of
    // 3 or 7 beyond those of 1 or 5 pair with one of 2 or 6 and one more of 3
    // or 7, one misfit per such three: the icosphere's 632 / 1184 / 1864
    // leaves of sizes 1 or 5 / 2 or 6 / 3 or 7 give (1864 - 632) / 2 = 616)
    EXPECT_LT(packing.misfits, before.stats.leafCount / 8) << prims.size() << " triangles, misfits " << packing.misfits;
    RecordProperty("misfits_" + std::to_string(prims.size()), std::to_string(packing.misfits));
  }
}

TEST(Bvh4, ChildSlotsLeavesFirstThenTheLargestBox) {
  BvhBuildOptions given;
  given.maxLeafSize = 0;
  for (const Scene& scene : {makeBumpyGrid(15000), makeTriangleSoup(5000, 3)}) {
    const std::vector<Aabb> prims = triangleBounds(scene);
    Bvh4 before = collapseToBvh4(buildBvh(prims, binaryBuildOptions(given, prims.size())), bvh4Options(given));
    packLeavesIntoBlocks(before, prims.size());
    Bvh4 after = before;
    orderChildSlots(after);
    ASSERT_EQ(after.nodes.size(), before.nodes.size());
    std::size_t moved = 0;
    for (std::size_t i = 0; i < after.nodes.size(); ++i) {
      const WtBvh4Node& a = after.nodes[i];
      const WtBvh4Node& b = before.nodes[i];
      // the same children with the same boxes, each once
      std::vector<std::array<float, 8>> was, is;
      for (int k = 0; k < 4; ++k) {
        was.push_back({b.lo_x[k], b.hi_x[k], b.lo_y[k], b.hi_y[k], b.lo_z[k], b.hi_z[k], float(b.child[k]), float(b.count[k])});
        is.push_back({a.lo_x[k], a.hi_x[k], a.lo_y[k], a.hi_y[k], a.lo_z[k], a.hi_z[k], float(a.child[k]), float(a.count[k])});
      }
      std::vector<std::array<float, 8>> sortedWas = was, sortedIs = is;
      std::sort(sortedWas.begin(), sortedWas.end());
      std::sort(sortedIs.begin(), sortedIs.end());
      EXPECT_EQ(sortedWas, sortedIs) << "node " << i;
      moved += was != is;
      // leaves (in their order), inner children by area, largest first, empty slots
      int phase = 0;  // 0 leaves, 1 inner, 2 empty
      float lastArea = std::numeric_limits<float>::infinity();
      std::vector<std::uint32_t> leavesWas, leavesIs;
      for (int k = 0; k < 4; ++k) {
        if (b.child[k] != WT_BVH4_EMPTY && b.count[k] > 0) leavesWas.push_back(b.child[k]);
        const int kind = a.child[k] == WT_BVH4_EMPTY ? 2 : a.count[k] > 0 ? 0 : 1;
        EXPECT_GE(kind, phase) << "node " << i << " slot " << k;
        phase = kind;
        if (kind == 0) leavesIs.push_back(a.child[k]);
        if (kind == 1) {
          const float ex = a.hi_x[k] - a.lo_x[k], ey = a.hi_y[k] - a.lo_y[k], ez = a.hi_z[k] - a.lo_z[k];
          const float area = ex * ey + ey * ez + ez * ex;
          EXPECT_LE(area, lastArea) << "node " << i << " slot " << k;
          lastArea = area;
        }
      }
      EXPECT_EQ(leavesIs, leavesWas) << "node " << i;
    }
    EXPECT_GT(moved, after.nodes.size() / 10);  // the order was not already so
  }
}

TEST(Bvh4, LeavesWhoseSizesAddUpToBlocksShareThem) {
  // leaves of 3, 2, 1, 2 | 6, 2 | 5, 4, 3 | 4, 8 | 7, 1 in this order pack
  // into whole blocks when the 2 waits for the 1 and the second 4 for the 3
  const std::vector<std::vector<std::uint32_t>> slots = {{3}, {2, 1, 2, 6}, {2, 5, 4, 3}, {4, 8, 7, 1}};
  Bvh4 tree;
  tree.nodes.resize(4);
  std::uint32_t first = 0;
  for (std::uint32_t n = 0; n < 4; ++n) {
    WtBvh4Node& node = tree.nodes[n];
    for (int k = 0; k < 4; ++k) {
      node.lo_x[k] = node.lo_y[k] = node.lo_z[k] = 0.0f;
      node.hi_x[k] = node.hi_y[k] = node.hi_z[k] = 1.0f;
      node.child[k] = WT_BVH4_EMPTY;
      node.count[k] = 0;
    }
  }
  tree.nodes[0].child[0] = 0, tree.nodes[0].count[0] = 3;
  for (std::uint32_t n = 1; n < 4; ++n) tree.nodes[0].child[n] = n;
  first = 3;
  for (std::uint32_t n = 1; n < 4; ++n)
    for (int k = 0; k < 4; ++k) {
      tree.nodes[n].child[k] = first;
      tree.nodes[n].count[k] = slots[n][std::size_t(k)];
      first += slots[n][std::size_t(k)];
    }
  ASSERT_EQ(first, 48u);
  Bvh4 packed = tree;
  const LeafPacking packing = packLeavesIntoBlocks(packed, first);
  EXPECT_TRUE(checkPacking(tree, packed, packing, first));
  EXPECT_EQ(packing.misfits, 0u);
  // nothing held back: the 2 after the 3 and the 4 after the 5 cross blocks
  Bvh4 eager = tree;
  const LeafPacking greedy = packLeavesIntoBlocks(eager, first, 0);
  EXPECT_TRUE(checkPacking(tree, eager, greedy, first));
  EXPECT_GT(greedy.misfits, 0u);
}

constexpr double kSahSlack = 1.02;

TEST(Bvh4, SahRegressionBumpyGrid) {
  // measured 2026-12-04: binary with cubic Morton cells and the grid's regions
  // keyed with their height last (flat regions; 52.65 and 24.70 without, measured
  // 2026-12-02); 4-wide collapseCost of the optimal collapse (the greedy one's
  // per-triangle SAH was 31.52)
  const double kBinary = 48.24, kBvh4 = 21.93;
  Bvh4 tree;
  double binary = binarySah(makeBumpyGrid(200000), &tree);
  RecordProperty("binary_sah", std::to_string(binary));
  RecordProperty("bvh4_collapse_cost", std::to_string(tree.stats.collapseCost));
  EXPECT_LE(binary, kBinary * kSahSlack);
  EXPECT_LE(tree.stats.collapseCost, kBvh4 * kSahSlack);
}

TEST(Bvh4, SahRegressionIcosphere) {
  // measured 2026-12-04 with 16 of the sphere's 25 sampled regions keyed as flat
  // patches (48.98 and 22.10 before: 2026-11-23 binary, 2026-12-02 collapseCost)
  const double kBinary = 48.23, kBvh4 = 21.78;
  Bvh4 tree;
  double binary = binarySah(makeIcosphere(6, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f))), &tree);
  RecordProperty("binary_sah", std::to_string(binary));
  RecordProperty("bvh4_collapse_cost", std::to_string(tree.stats.collapseCost));
  EXPECT_LE(binary, kBinary * kSahSlack);
  EXPECT_LE(tree.stats.collapseCost, kBvh4 * kSahSlack);
}

/// The primitive tree over every type beside triangles at once (spheres,
/// curve segments, an SDF grid's bricks, displaced base triangles): every
/// kept primitive sits in one leaf, the leaf's box and every box above it,
/// each in its node's frame (oriented nodes), hold the gathered box of each
/// primitive it names (a curve segment: its hull), no leaf names an unknown
/// id, and some curve nodes are oriented.
TEST(Bvh4, PrimitiveTreeOverEveryTypeKeepsTheInvariants) {
  const WtMaterial white = makeMaterial(glm::vec3(0.5f));
  Scene scene = makeSphereField(300, 5);
  scene.displacedMeshes = makeDisplacedSphere(1, glm::vec3(40.0f, 0.0f, 0.0f), 3.0f, 8, 0.3f, 0.0f, 2, white).displacedMeshes;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int c = 0; c < 40; ++c) {  // bent strands, some diagonal
    scene.curves.push_back({std::uint32_t(scene.curvePoints.size()), 6, 0, c % 2 ? CurveBasis::kLinear : CurveBasis::kBSpline});
    glm::vec3 p(20.0f * u(rng), 5.0f + u(rng), 20.0f * u(rng));
    for (int k = 0; k < 6; ++k, p += glm::vec3(u(rng), 1.0f, u(rng))) scene.curvePoints.push_back({p.x, p.y, p.z, 0.02f});
  }
  SdfGrid grid;  // a ball of radius 10 cells in 24^3 cells of 0.5: several bricks
  grid.cells = glm::uvec3(24);
  for (int z = 0; z <= 24; ++z)
    for (int y = 0; y <= 24; ++y)
      for (int x = 0; x <= 24; ++x) grid.values.push_back(glm::length(glm::vec3(x, y, z) - glm::vec3(12.0f)) - 10.0f);
  grid.latticeToScene = glm::dmat4(0.5);
  grid.latticeToScene[3] = glm::dvec4(-30.0, 0.0, 0.0, 1.0);
  scene.sdfGrids.push_back(grid);
  const PrimitiveRows rows = gatherPrimitives(scene);
  for (std::uint32_t type : {WT_PRIM_SPHERE, WT_PRIM_CURVE, WT_PRIM_SDF_GRID, WT_PRIM_DISPLACED})
    ASSERT_GT(rows.count[type], 1u) << primTypeName(type);
  const PrimitiveTree tree = buildPrimitiveTree(rows, BvhBuildOptions{});
  std::unordered_map<std::uint32_t, std::size_t> row;
  for (std::size_t i = 0; i < rows.ids.size(); ++i) row[rows.ids[i]] = i;
  std::unordered_map<std::uint32_t, int> seen;
  // a slot as (node with its WT_BVH4_ORIENTED bit, k); a point's place in the slot's frame
  using Slot = std::pair<std::uint32_t, int>;
  auto local = [&](Slot s, const glm::dvec3& p) {
    if (!(s.first & WT_BVH4_ORIENTED)) return p;
    WtBvh4Oriented f;
    std::memcpy(&f, &tree.bvh4.nodes.at(s.first & ~WT_BVH4_ORIENTED), sizeof f);
    const glm::dvec3 w = p - glm::dvec3(f.rows[0][3], f.rows[1][3], f.rows[2][3]);
    glm::dvec3 q;
    for (int i = 0; i < 3; ++i) q[i] = glm::dot(glm::dvec3(f.rows[i][0], f.rows[i][1], f.rows[i][2]), w);
    return q;
  };
  // the slot's box: an oriented node's from its grid (WtBvh4Oriented), in exact arithmetic
  auto box = [&](Slot s) {
    const WtBvh4Node& node = tree.bvh4.nodes.at(s.first & ~WT_BVH4_ORIENTED);
    if (!(s.first & WT_BVH4_ORIENTED)) {
      const Aabb b = slotBox(node, s.second);
      return std::pair{glm::dvec3(b.lo), glm::dvec3(b.hi)};
    }
    WtBvh4Oriented f;
    std::memcpy(&f, &node, sizeof f);
    std::uint8_t grid[24];
    std::memcpy(grid, f.grid, sizeof grid);
    glm::dvec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = double(f.origin[a]) + double(grid[8 * a + s.second]) * double(f.step[a]);
      hi[a] = double(f.origin[a]) + double(grid[8 * a + 4 + s.second]) * double(f.step[a]);
    }
    return std::pair{lo, hi};
  };
  // a ball (centre p, radius r) inside the slot's box, in the slot's frame
  auto holds = [&](Slot s, const glm::dvec3& p, double r) {
    const auto [lo, hi] = box(s);
    const glm::dvec3 q = local(s, p);
    const double tol = 1e-6 * (std::abs(p.x) + std::abs(p.y) + std::abs(p.z) + r);
    return glm::all(glm::greaterThanEqual(q - r, lo - tol)) && glm::all(glm::lessThanEqual(q + r, hi + tol));
  };
  std::size_t problems = 0, oriented = 0;
  std::unordered_map<std::uint32_t, std::vector<std::vector<Slot>>> curvePaths;  // per segment: the slots down to each leaf naming it
  std::vector<Slot> path;
  std::function<void(std::uint32_t)> visit = [&](std::uint32_t n) {
    oriented += (n & WT_BVH4_ORIENTED) != 0;
    const WtBvh4Node& node = tree.bvh4.nodes.at(n & ~WT_BVH4_ORIENTED);
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) continue;
      path.push_back({n, k});
      if (node.count[k] == 0) {
        visit(node.child[k]);
        path.pop_back();
        continue;
      }
      for (std::uint32_t i = node.child[k]; i < node.child[k] + node.count[k]; ++i) {
        const std::uint32_t id = tree.refs[i];
        const auto at = row.find(id);
        if (at == row.end()) {
          ADD_FAILURE() << "a leaf names id " << id << ", which was not gathered", ++problems;
          continue;
        }
        ++seen[id];
        if (primType(id) == WT_PRIM_CURVE) {
          curvePaths[id].push_back(path);
          continue;
        }
        // other types: the gathered box's corners inside the leaf's slot and every slot above it
        const Aabb& b = rows.bounds[at->second];
        for (const Slot& s : path)
          for (int c = 0; c < 8; ++c)
            if (!holds(s, glm::dvec3(c & 1 ? b.hi.x : b.lo.x, c & 2 ? b.hi.y : b.lo.y, c & 4 ? b.hi.z : b.lo.z), 0.0)) {
              ADD_FAILURE() << primTypeName(primType(id)) << " " << primIndex(id) << " leaves the box of node "
                            << (s.first & ~WT_BVH4_ORIENTED) << " slot " << s.second, ++problems;
              break;
            }
      }
      path.pop_back();
    }
  };
  visit(0);
  // a curve segment: every point of its axis, its radius around it, inside the leaf naming it and that leaf's
  // ancestors
  for (const auto& [id, paths] : curvePaths) {
    const std::size_t r = rows.dataFirst[WT_PRIM_CURVE] + 2 * std::size_t(primIndex(id));
    const glm::dvec4 a(rows.data[r].x, rows.data[r].y, rows.data[r].z, std::fabs(rows.data[r].w));
    const glm::dvec4 b(rows.data[r + 1].x, rows.data[r + 1].y, rows.data[r + 1].z, std::fabs(rows.data[r + 1].w));
    for (int i = 0; i <= 64 && problems <= 20; ++i) {
      const glm::dvec4 p = a + (i / 64.0) * (b - a);
      const bool in = std::any_of(paths.begin(), paths.end(), [&](const std::vector<Slot>& slots) {
        return std::all_of(slots.begin(), slots.end(), [&](Slot s) { return holds(s, glm::dvec3(p), p.w); });
      });
      if (!in) ADD_FAILURE() << "curve segment " << primIndex(id) << " at " << i / 64.0 << " is in no leaf's box", ++problems;
    }
  }
  EXPECT_GT(oriented, 0u);  // the strands' nodes low in the tree take frames along them
  for (std::uint32_t id : rows.ids) {
    const int times = seen.count(id) ? seen[id] : 0;
    if (times != 1)
      ADD_FAILURE() << primTypeName(primType(id)) << " " << primIndex(id) << " is in " << times << " leaves", ++problems;
    if (problems > 20) break;
  }
}

}  // namespace
}  // namespace wt
