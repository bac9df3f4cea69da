// Every BVH builder (LBVH, PLOC over the LBVH's leaves, binned SAH): the
// binary tree's invariants on regular and degenerate inputs, determinism
// across thread counts, the 4-wide collapse of each, and the tree-quality
// regression: the SAH cost of each builder's tree on fixed generated meshes,
// bounded relative to the binned-SAH tree of the same mesh.
#include "bvh/builders.h"
#include "bvh/bvh4.h"
#include "bvh/bvh_checks.h"
#include "scene/generators.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {
namespace {

using namespace wt::test;

BvhBuildOptions optionsFor(BvhBuilder builder, int maxLeafSize = 4, int threads = 0) {
  BvhBuildOptions options;
  options.builder = builder;
  options.maxLeafSize = maxLeafSize;
  options.threads = threads;
  return options;
}

class Builder : public ::testing::TestWithParam<BvhBuilder> {
 protected:
  Bvh build(std::span<const Aabb> prims, int maxLeafSize = 4, int threads = 0) {
    return buildBvh(prims, optionsFor(GetParam(), maxLeafSize, threads));
  }
};

TEST_P(Builder, NamesRoundTrip) {
  EXPECT_EQ(parseBvhBuilder(bvhBuilderName(GetParam())), GetParam());
  EXPECT_FALSE(parseBvhBuilder("no-such-builder").has_value());
}

TEST_P(Builder, EmptyInputGivesEmptyTree) {
  const Bvh bvh = build({});
  EXPECT_TRUE(bvh.nodes.empty());
  EXPECT_TRUE(bvh.primIndices.empty());
}

TEST_P(Builder, RandomBoxes) {
  for (std::size_t n : {1u, 2u, 3u, 5u, 9u, 100u, 10000u, 100000u})
    for (unsigned seed : {1u, 2u}) {
      const std::vector<Aabb> prims = randomBoxes(n, seed);
      EXPECT_TRUE(checkBvhInvariants(build(prims), prims)) << n << " boxes, seed " << seed;
    }
}

TEST_P(Builder, LeafSizes) {
  for (int leaf : {1, 2, 8}) {
    const std::vector<Aabb> prims = randomBoxes(20000, 10 + leaf);
    const Bvh bvh = build(prims, leaf);
    EXPECT_TRUE(checkBvhInvariants(bvh, prims, leaf)) << "leaf size " << leaf;
    if (leaf == 1) {
      EXPECT_EQ(bvh.nodes.size(), 2 * prims.size() - 1);
    }
  }
}

TEST_P(Builder, TraversableTreesTakeTheirLeafLimit) {
  // SceneBuffers and the bench read maxLeafSize as the 4-wide tree's leaf
  // limit (0: kBvh4MaxLeafSize): binary leaves of at most 4, merged by the
  // collapse up to the limit, never beyond it
  const std::vector<Aabb> prims = triangleBounds(makeBumpyGrid(20000));
  for (int limit : {0, 1, 2, 4, 8, 16}) {
    BvhBuildOptions given = optionsFor(GetParam(), limit);
    const Bvh binary = buildBvh(prims, binaryBuildOptions(given, prims.size()));
    const int wideLimit = limit > 0 ? limit : kBvh4MaxLeafSize;
    EXPECT_TRUE(checkBvhInvariants(binary, prims, std::min(wideLimit, 4))) << limit;
    const Bvh4 tree = collapseToBvh4(binary, bvh4Options(given));
    std::uint32_t largest = 0;
    for (const WtBvh4Node& node : tree.nodes)
      for (int k = 0; k < 4; ++k)
        if (node.child[k] != WT_BVH4_EMPTY) largest = std::max(largest, node.count[k]);
    EXPECT_LE(largest, std::uint32_t(wideLimit)) << limit;
    // merging pays here: leaves larger than the binary tree's are used
    if (wideLimit > 4) {
      EXPECT_GT(largest, 4u) << limit;
    }
  }
}

TEST_P(Builder, DegenerateInputs) {
  struct Case {
    const char* name;
    std::vector<Aabb> prims;
  };
  std::vector<Case> cases;
  cases.push_back(Case{"all centroids equal", std::vector<Aabb>(1000, boxAround({0.5f, -2.0f, 3.0f}, {0.1f, 0.2f, 0.3f}))});
  cases.push_back(Case{"all at one point", std::vector<Aabb>(100, boxAround({1, 1, 1}, {0, 0, 0}))});
  {
    std::mt19937 rng(5);
    std::uniform_int_distribution<int> cluster(0, 9);
    std::vector<Aabb> prims(30000);
    for (Aabb& box : prims) {
      const float c = float(cluster(rng));
      box = boxAround({c, 2.0f * c, -c}, {0.5f, 0.5f, 0.5f});
    }
    cases.push_back(Case{"clustered duplicates", prims});
  }
  {
    std::vector<Aabb> prims = randomBoxes(20000, 21);
    for (Aabb& box : prims) box.lo.z = -0.01f, box.hi.z = 0.01f;
    cases.push_back(Case{"coplanar", prims});
  }
  {
    std::vector<Aabb> prims(2000);
    for (std::size_t i = 0; i < prims.size(); ++i)
      prims[i] = boxAround({-5.0f + 0.005f * float((i * 7919) % 2000), 1.0f, 7.0f}, {0.001f, 0.3f, 0.3f});
    cases.push_back(Case{"collinear", prims});
  }
  cases.push_back(Case{"point boxes", randomBoxes(20000, 22, 0.0f)});
  cases.push_back(Case{"large offset", randomBoxes(20000, 31, 0.02f, 1.0e6f, 100.0f)});
  cases.push_back(Case{"tiny scale", randomBoxes(20000, 32, 0.02f, 0.0f, 1.0e-6f)});
  cases.push_back(Case{"tiny boxes far away", randomBoxes(5000, 33, 0.02f, 1.0e6f, 1.0e-6f)});
  cases.push_back(Case{"huge coordinates", randomBoxes(1000, 34, 0.02f, 0.0f, 3.0e38f)});
  {
    std::vector<Aabb> prims = randomBoxes(3000, 42);
    for (std::size_t i = 0; i < prims.size(); i += 17) {
      prims[i].lo.x = -std::numeric_limits<float>::infinity();
      prims[i].hi.z = std::numeric_limits<float>::infinity();
    }
    cases.push_back(Case{"infinite bounds", prims});
  }
  for (const auto& [name, prims] : cases) {
    const Bvh bvh = build(prims, 4, 2);
    EXPECT_TRUE(checkBvhInvariants(bvh, prims)) << name;
    EXPECT_TRUE(std::isfinite(bvh.stats.sahCost)) << name;
  }
}

TEST_P(Builder, NonFiniteBoundsDoNotBreakTheTree) {
  std::vector<Aabb> prims = randomBoxes(3000, 41);
  for (std::size_t i = 0; i < prims.size(); i += 7) prims[i].lo.y = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 3; i < prims.size(); i += 11) prims[i] = Aabb{};
  for (std::size_t i = 5; i < prims.size(); i += 13) prims[i].hi.x = std::numeric_limits<float>::infinity();
  const Bvh bvh = build(prims, 4, 2);
  EXPECT_TRUE(checkBvhInvariants(bvh, prims, 4, /*checkBoxes=*/false));
}

TEST_P(Builder, ThreadCountDoesNotChangeTheTree) {
  const std::vector<Aabb> prims = randomBoxes(200000, 51);
  const Bvh one = build(prims, 4, 1);
  ASSERT_TRUE(checkBvhInvariants(one, prims));
  for (int threads : {2, 3}) {
    const Bvh many = build(prims, 4, threads);
    ASSERT_EQ(one.nodes.size(), many.nodes.size()) << threads << " threads";
    EXPECT_EQ(0, std::memcmp(one.nodes.data(), many.nodes.data(), one.nodes.size() * sizeof(WtBvhNode)))
        << threads << " threads";
    EXPECT_EQ(one.primIndices, many.primIndices) << threads << " threads";
  }
}

TEST_P(Builder, CollapsesToBvh4) {
  // the 4-wide collapse keeps every primitive once and the leaves' order
  const Scene scene = makeTriangleSoup(30000, 3, 0.2f);
  const std::vector<Aabb> prims = triangleBounds(scene);
  const Bvh binary = build(prims);
  const Bvh4 tree = collapseToBvh4(binary);
  ASSERT_FALSE(tree.nodes.empty());
  std::vector<int> covered(prims.size(), 0);
  for (const WtBvh4Node& node : tree.nodes)
    for (int k = 0; k < 4; ++k)
      if (node.child[k] != WT_BVH4_EMPTY && node.count[k] > 0)
        for (std::uint32_t p = node.child[k]; p < node.child[k] + node.count[k]; ++p) ++covered.at(p);
  for (std::size_t p = 0; p < covered.size(); ++p) ASSERT_EQ(covered[p], 1) << "slot " << p;
  // leaves are binary leaves or merged binary subtrees
  EXPECT_LE(tree.stats.leafCount, binary.stats.leafCount);
}

INSTANTIATE_TEST_SUITE_P(All, Builder,
                         ::testing::Values(BvhBuilder::Auto, BvhBuilder::Lbvh, BvhBuilder::Ploc, BvhBuilder::Sah),
                         [](const ::testing::TestParamInfo<BvhBuilder>& param) {
                           return std::string(bvhBuilderName(param.param));
                         });

TEST(Ploc, EqualBoxesPairOff) {
  // Equal union areas everywhere: the neighbour search's tie order must pair
  // the clusters off two by two, so the tree is balanced (depth 12 over 4 096
  // single-primitive leaves). Ties to the lowest position in the window merged
  // one pair per window and round: a chain of depth 4 095 here, and 63 s for
  // 60 000 boxes.
  const std::vector<Aabb> prims(4096, boxAround({0.5f, -2.0f, 3.0f}, {0.1f, 0.2f, 0.3f}));
  BvhBuildOptions options = optionsFor(BvhBuilder::Ploc, 1, 2);
  options.plocTopPrims = 0;  // PLOC to the root
  const Bvh bvh = buildBvh(prims, options);
  ASSERT_TRUE(checkBvhInvariants(bvh, prims, 1));
  EXPECT_LE(bvh.stats.maxDepth, 13);
}

TEST(Ploc, OneWayNeighboursEndTheClustering) {
  // boxes along a line, each a little larger than the one before: every
  // cluster's nearest neighbour is the one before it, so a round merges
  // only a pair or two, quadratic time. PLOC hands such clusters to the SAH
  // pass after a round that merges fewer than 1/16 of them (without that:
  // 2 000 rounds here, 230 ms against 1).
  std::vector<Aabb> prims(4000);
  for (std::size_t i = 0; i < prims.size(); ++i)
    prims[i] = boxAround({float(i), 0.0f, 0.0f}, glm::vec3(0.3f + 1e-4f * float(i)));
  BvhBuildOptions options = optionsFor(BvhBuilder::Ploc, 1, 2);
  options.plocTopPrims = 0;
  const Bvh bvh = buildBvh(prims, options);
  ASSERT_TRUE(checkBvhInvariants(bvh, prims, 1));
  EXPECT_LE(bvh.stats.clusterRounds, 8);
  EXPECT_LE(bvh.stats.maxDepth, 30);
}

// ---- placed copies (BvhBuilder::Auto) --------------------------------------------

/// `copies` of a level-3 icosphere (1280 triangles), turned, scaled and moved
/// at random, after a soup of `soup` triangles (the primitives no copy holds).
Scene copiesScene(int copies, std::uint32_t soup, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), scale(0.03f, 0.12f);
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < copies; ++c) {
    glm::mat4 m(1.0f);
    m = glm::translate(m, glm::vec3(unit(rng), unit(rng), unit(rng)));
    m = glm::rotate(m, 3.0f * unit(rng), glm::normalize(glm::vec3(unit(rng), unit(rng), 1.5f)));
    m = glm::scale(m, glm::vec3(scale(rng), scale(rng), scale(rng)));
    transforms.push_back(m);
  }
  Scene scene = makeTriangleSoup(soup, seed, 0.05f);
  appendScene(scene, placeCopies(makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f))), transforms));
  return scene;
}

std::vector<BvhInstance> instancesOf(const Scene& scene) {
  std::vector<BvhInstance> out;
  for (const GeometryInstance& copy : scene.instances) out.push_back({copy.firstTriangle, copy.triangleCount, copy.geometry});
  return out;
}

TEST(AutoBuilder, CopiesKeepTheInvariants) {
  for (int leaf : {1, 4, 8})
    for (std::uint32_t soup : {0u, 3u, 5000u}) {
      const Scene scene = copiesScene(40, soup, 3 + soup);
      const std::vector<Aabb> prims = triangleBounds(scene);
      const Bvh bvh = buildBvh(prims, optionsFor(BvhBuilder::Auto, leaf), instancesOf(scene));
      EXPECT_TRUE(checkBvhInvariants(bvh, prims, leaf)) << "leaf " << leaf << ", soup " << soup;
    }
}

TEST(AutoBuilder, EveryCopyGetsTheGeometryTree) {
  // each copy's subtree has the shape of the SAH tree over the first copy
  // alone (the copies hold few primitives in all: kSahGeometryPrims)
  const Scene scene = copiesScene(12, 0, 8);
  const std::vector<Aabb> prims = triangleBounds(scene);
  const Bvh bvh = buildBvh(prims, optionsFor(BvhBuilder::Auto), instancesOf(scene));
  const std::uint32_t perCopy = scene.instances[0].triangleCount;
  const Bvh one = buildBvh(std::span(prims).subspan(0, perCopy), optionsFor(BvhBuilder::Sah));
  EXPECT_EQ(bvh.stats.leafCount, 12 * one.stats.leafCount);
  EXPECT_EQ(bvh.nodes.size(), 12 * one.nodes.size() + 11);
}

TEST(AutoBuilder, SmallPartsPairedIntoLeaves) {
  // copies of 64 primitives and a few others: the others' subtrees are
  // single primitives, which the top pass pairs below the leaf size; such a
  // pair must become one leaf, as every builder makes them
  for (std::uint32_t others : {5u, 40u, 300u}) {
    const std::vector<Aabb> prims = randomBoxes(64 * 6 + others, others);
    std::vector<BvhInstance> instances;
    for (std::uint32_t c = 0; c < 6; ++c) instances.push_back({others + c * 64, 64, 0});
    for (int leaf : {2, 4, 8}) {
      const Bvh bvh = buildBvh(prims, optionsFor(BvhBuilder::Auto, leaf), instances);
      EXPECT_TRUE(checkBvhInvariants(bvh, prims, leaf)) << others << " others, leaf " << leaf;
      EXPECT_EQ(bvh.stats.copiesPlaced, 6u);
    }
  }
}

TEST(AutoBuilder, CopiesOfFewPrimitivesAreBuiltWithTheRest) {
  // 3 000 copies of one or two boxes: a top pass over them would be a full
  // SAH build; below 64 primitives a copy is built with the others
  for (std::uint32_t size : {1u, 2u, 63u}) {
    const std::vector<Aabb> prims = randomBoxes(size * 3000, size);
    std::vector<BvhInstance> instances;
    for (std::uint32_t c = 0; c < 3000; ++c) instances.push_back({c * size, size, c % 7});
    const Bvh bvh = buildBvh(prims, optionsFor(BvhBuilder::Auto, 4), instances);
    EXPECT_TRUE(checkBvhInvariants(bvh, prims, 4)) << size << " per copy";
    EXPECT_EQ(bvh.stats.copiesPlaced, 0u) << size << " per copy";
  }
}

TEST(AutoBuilder, ThreadCountDoesNotChangeTheTree) {
  const Scene scene = copiesScene(30, 70000, 4);  // the others above the PLOC limit: the LBVH
  const std::vector<Aabb> prims = triangleBounds(scene);
  const Bvh one = buildBvh(prims, optionsFor(BvhBuilder::Auto, 4, 1), instancesOf(scene));
  const Bvh two = buildBvh(prims, optionsFor(BvhBuilder::Auto, 4, 2), instancesOf(scene));
  ASSERT_TRUE(checkBvhInvariants(one, prims));
  ASSERT_EQ(one.nodes.size(), two.nodes.size());
  EXPECT_EQ(std::memcmp(one.nodes.data(), two.nodes.data(), one.nodes.size() * sizeof(WtBvhNode)), 0);
  EXPECT_TRUE(std::equal(one.primIndices.begin(), one.primIndices.end(), two.primIndices.begin()));
}

TEST(AutoBuilder, BadInstancesAreRejected) {
  const std::vector<Aabb> prims = randomBoxes(400, 1);
  const auto build = [&](std::vector<BvhInstance> instances) {
    return buildBvh(prims, optionsFor(BvhBuilder::Auto), instances);
  };
  EXPECT_THROW(build({{0, 10, 0}, {395, 10, 0}}), std::invalid_argument);  // past the end
  EXPECT_THROW(build({{0, 10, 0}, {5, 10, 0}}), std::invalid_argument);    // overlapping
  EXPECT_THROW(build({{0, 10, 0}, {10, 9, 0}}), std::invalid_argument);    // one geometry, two sizes
  // two copies of 100 and one copy alone (built with the rest)
  const Bvh bvh = build({{0, 100, 0}, {100, 100, 0}, {250, 80, 1}});
  EXPECT_TRUE(checkBvhInvariants(bvh, prims));
  EXPECT_EQ(bvh.stats.copiesPlaced, 2u);
}

// ---- tree quality ----------------------------------------------------------------

// Fixed meshes made here, fixed builds. Each builder's binary costs were
// measured when it was written (2026-12-01), the 4-wide ones (the collapse's
// own objective, collapseCost) when the optimal collapse was (2026-12-02); a
// change that makes a tree worse by more than 2% fails, one that makes it
// better should lower the constant. Beside those, PLOC's tree must stay
// within kPlocVsSah of the SAH tree of the same mesh (measured: 1.005-1.110
// binary, 1.03-1.05 4-wide, worst on the bumpy grid; the LBVH is at
// 1.08-1.85 binary) and below the LBVH's cost.
constexpr double kSlack = 1.02;
constexpr double kPlocVsSah = 1.15;
// The LBVH's 4-wide tree on a height field, against the SAH tree's (BvhQuality.BumpyGrid).
constexpr double kFlatVsSah = 1.05;

struct Costs {
  double binary, bvh4;
};

Costs costOf(const std::vector<Aabb>& prims, BvhBuilder builder) {
  const Bvh binary = buildBvh(prims, optionsFor(builder));
  EXPECT_TRUE(checkBvhInvariants(binary, prims)) << bvhBuilderName(builder);
  Bvh4Options sameCosts;  // every tree at the same node cost, whatever its memory
  sameCosts.nodeBytesPerPrimitive = 0.0;
  return {binary.stats.sahCost, collapseToBvh4(binary, sameCosts).stats.collapseCost};
}

struct Measured {
  Costs sah, ploc;
};

struct AllCosts {
  Costs lbvh, ploc, sah;
};

/// The checks above; with plocBelowLbvh also that PLOC's tree costs less than
/// the LBVH's (not on a height field, whose regions the LBVH keys with their
/// height last while PLOC clusters in the plain Morton order).
AllCosts expectQuality(const char* mesh, const std::vector<Aabb>& prims, const Measured& measured,
                       bool plocBelowLbvh = true) {
  const Costs lbvh = costOf(prims, BvhBuilder::Lbvh), ploc = costOf(prims, BvhBuilder::Ploc),
              sah = costOf(prims, BvhBuilder::Sah);
  ::testing::Test::RecordProperty("lbvh_sah", std::to_string(lbvh.binary));
  ::testing::Test::RecordProperty("ploc_sah", std::to_string(ploc.binary));
  ::testing::Test::RecordProperty("sah_sah", std::to_string(sah.binary));
  SCOPED_TRACE(std::string(mesh) + ": binary SAH lbvh " + std::to_string(lbvh.binary) + ", ploc " +
               std::to_string(ploc.binary) + ", sah " + std::to_string(sah.binary) + "; 4-wide lbvh " +
               std::to_string(lbvh.bvh4) + ", ploc " + std::to_string(ploc.bvh4) + ", sah " + std::to_string(sah.bvh4));
  EXPECT_LE(sah.binary, measured.sah.binary * kSlack);
  EXPECT_LE(sah.bvh4, measured.sah.bvh4 * kSlack);
  EXPECT_LE(ploc.binary, measured.ploc.binary * kSlack);
  EXPECT_LE(ploc.bvh4, measured.ploc.bvh4 * kSlack);
  EXPECT_LE(ploc.binary, kPlocVsSah * sah.binary);
  EXPECT_LE(ploc.bvh4, kPlocVsSah * sah.bvh4);
  if (plocBelowLbvh) {
    EXPECT_LT(ploc.binary, lbvh.binary);
    EXPECT_LT(ploc.bvh4, lbvh.bvh4);
  }
  return {lbvh, ploc, sah};
}

TEST(BvhQuality, BumpyGrid) {
  const std::vector<Aabb> prims = triangleBounds(makeBumpyGrid(200000));
  const AllCosts costs = expectQuality("bumpy grid 200k", prims, {{44.95, 21.49}, {49.88, 22.65}}, false);
  // The LBVH keys the grid's regions with their height last (flat regions,
  // host/bvh/lbvh.cpp): measured 2026-12-04, binary / 4-wide, 48.24 / 21.93
  // (1.07 / 1.02 times the SAH tree's; PLOC 47.18 / 22.64); in the plain
  // Morton order 52.65 / 24.68, 1.15 times the SAH tree's 4-wide cost.
  EXPECT_LE(costs.lbvh.bvh4, kFlatVsSah * costs.sah.bvh4);
  EXPECT_LE(costs.lbvh.binary, kPlocVsSah * costs.sah.binary);
}

TEST(BvhQuality, Icosphere) {
  expectQuality("icosphere level 6",
                triangleBounds(makeIcosphere(6, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)))),
                {{42.68, 20.20}, {44.70, 20.83}});
}

TEST(BvhQuality, PlacedCopies) {
  // 200 turned and scaled icospheres and a soup: the auto tree (one SAH tree
  // for the icosphere, refitted per copy) must stay within kPlocVsSah of the
  // SAH tree over all of it and below the LBVH's. Measured when written
  // (2026-12-04), binary / 4-wide: auto 103.39 / 45.71 (104.87 / 46.07 with
  // a PLOC tree per geometry), lbvh 108.94 / 47.92, sah 94.58 / 42.11. The
  // copies overlap one another, which the top pass over whole copies cannot
  // split: the gap to the SAH tree is that.
  const Scene scene = copiesScene(200, 20000, 11);
  const std::vector<Aabb> prims = triangleBounds(scene);
  const Bvh binary = buildBvh(prims, optionsFor(BvhBuilder::Auto), instancesOf(scene));
  ASSERT_TRUE(checkBvhInvariants(binary, prims));
  Bvh4Options sameCosts;
  sameCosts.nodeBytesPerPrimitive = 0.0;
  const Costs autoCost{binary.stats.sahCost, collapseToBvh4(binary, sameCosts).stats.collapseCost};
  const Costs lbvh = costOf(prims, BvhBuilder::Lbvh), sah = costOf(prims, BvhBuilder::Sah);
  SCOPED_TRACE("binary SAH auto " + std::to_string(autoCost.binary) + ", lbvh " + std::to_string(lbvh.binary) +
               ", sah " + std::to_string(sah.binary) + "; 4-wide auto " + std::to_string(autoCost.bvh4) + ", lbvh " +
               std::to_string(lbvh.bvh4) + ", sah " + std::to_string(sah.bvh4));
  EXPECT_LE(autoCost.binary, kPlocVsSah * sah.binary);
  EXPECT_LE(autoCost.bvh4, kPlocVsSah * sah.bvh4);
  EXPECT_LT(autoCost.bvh4, lbvh.bvh4);
  EXPECT_LE(autoCost.binary, 103.39 * kSlack);
  EXPECT_LE(autoCost.bvh4, 45.71 * kSlack);
}

TEST(BvhQuality, TriangleSoup) {
  expectQuality("soup 100k", triangleBounds(makeTriangleSoup(100000, 9, 0.05f)), {{627.07, 236.25}, {630.12, 244.61}});
}

}  // namespace
}  // namespace wt
