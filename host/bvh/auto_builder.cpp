// The default builder (BvhBuilder::Auto): the tree quality of PLOC where it
// costs little, the LBVH's speed where the input is large, and one build per
// geometry that a scene places several times.
//
// - A geometry of at least kMinCopyPrims primitives placed at least twice
//   (BvhInstance) gets one tree, built over its first copy's boxes, and
//   every copy gets that tree's topology with its boxes refitted to its own
//   primitives. Its build cost is paid once, so it can afford the binned
//   SAH builder while such geometries hold at most kSahGeometryPrims
//   primitives in all, else PLOC up to kQualityBuildPrims each.
// - Everything else, taken together so that overlapping objects still share
//   one tree, is built by PLOC up to kQualityBuildPrims primitives and by the
//   LBVH above.
// - A binned SAH pass over the copies' roots and the rest's subtrees (cut at
//   about 1/kRestClusters of the rest) makes the levels above.
#include "bvh/build_tree.h"
#include "bvh/builders.h"
#include "bvh/parallel.h"
#include "core/log.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace wt {
namespace {

using namespace bvh_detail;

/// Up to this many primitives a part is built by PLOC, whose tree is close to
/// the SAH tree's, above it by the LBVH, whose build stays fast at any size
/// (docs/lab/2026-12-01-performance-log.md, "The auto builder").
constexpr std::size_t kQualityBuildPrims = 65536;
/// Repeated geometries of at most this many primitives in all (one copy of
/// each) are built by the binned SAH builder: built once, the best tree is
/// worth its build time (docs/lab/2026-12-01-performance-log.md, "The auto builder").
constexpr std::size_t kSahGeometryPrims = 32768;
/// Copies of fewer primitives are built with the rest: a million copies of
/// one triangle would make the top pass a full SAH build.
constexpr std::uint32_t kMinCopyPrims = 64;
/// The rest's tree is cut into about this many subtrees for the top pass.
constexpr std::size_t kRestClusters = 64;

Bvh buildPart(std::span<const Aabb> bounds, const BvhBuildOptions& options) {
  BvhBuildOptions part = options;
  part.builder = bounds.size() <= kQualityBuildPrims ? BvhBuilder::Ploc : BvhBuilder::Lbvh;
  return buildBvh(bounds, part);
}

/// Primitives and nodes below each node of a tree, itself included (children
/// come after their parents).
struct SubtreeSize {
  std::uint32_t prims = 0;
  std::uint32_t nodes = 1;
};

std::vector<SubtreeSize> subtreeSizes(const Bvh& bvh) {
  std::vector<SubtreeSize> sizes(bvh.nodes.size());
  for (std::size_t i = bvh.nodes.size(); i-- > 0;) {
    const WtBvhNode& node = bvh.nodes[i];
    if (node.count > 0) {
      sizes[i].prims = node.count;
      continue;
    }
    const SubtreeSize& left = sizes[node.first];
    const SubtreeSize& right = sizes[node.first + 1];
    sizes[i] = {left.prims + right.prims, 1 + left.nodes + right.nodes};
  }
  return sizes;
}

/// Where a top-pass cluster's subtree comes from: node `node` of `tree`, whose
/// primitive indices are offset by `primBase` (a copy of a geometry) or
/// looked up in `primMap` (the rest).
struct ClusterSource {
  const Bvh* tree;
  std::uint32_t node;
  std::uint32_t primBase;
  const std::vector<std::uint32_t>* primMap;  ///< null: primBase + index
};

void checkInstances(std::size_t n, std::span<const BvhInstance> instances) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;
  ranges.reserve(instances.size());
  std::unordered_map<std::uint32_t, std::uint32_t> counts;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const BvhInstance& instance = instances[i];
    if (std::size_t(instance.first) + instance.count > n)
      throw std::invalid_argument("buildBvh: instance " + std::to_string(i) + " runs past the " + std::to_string(n) +
                                  " primitives");
    auto [it, added] = counts.emplace(instance.geometry, instance.count);
    if (!added && it->second != instance.count)
      throw std::invalid_argument("buildBvh: instance " + std::to_string(i) + " of geometry " +
                                  std::to_string(instance.geometry) + " has " + std::to_string(instance.count) +
                                  " primitives, another copy " + std::to_string(it->second));
    if (instance.count > 0) ranges.emplace_back(instance.first, instance.first + instance.count);
  }
  std::sort(ranges.begin(), ranges.end());
  for (std::size_t i = 1; i < ranges.size(); ++i)
    if (ranges[i].first < ranges[i - 1].second)
      throw std::invalid_argument("buildBvh: instances overlap at primitive " + std::to_string(ranges[i].first));
}

}  // namespace

Bvh buildAutoBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options,
                 std::span<const BvhInstance> instances) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = primBounds.size();
  checkInstances(n, instances);
  const std::uint32_t maxLeaf = std::uint32_t(std::max(options.maxLeafSize, 1));

  // geometries placed at least twice, each with its copies
  std::unordered_map<std::uint32_t, std::vector<std::uint32_t>> copiesOf;
  for (std::uint32_t i = 0; i < instances.size(); ++i)
    if (instances[i].count > 0) copiesOf[instances[i].geometry].push_back(i);
  std::vector<std::vector<std::uint32_t>> repeated;
  for (auto& [geometry, copies] : copiesOf)
    if (copies.size() >= 2 && instances[copies[0]].count >= kMinCopyPrims) repeated.push_back(std::move(copies));
  if (repeated.empty()) {
    Bvh bvh = buildPart(primBounds, options);
    bvh.stats.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return bvh;
  }
  // in input order, so the result does not depend on the hash map's order
  std::sort(repeated.begin(), repeated.end(),
            [&](const auto& a, const auto& b) { return instances[a[0]].first < instances[b[0]].first; });

  // one tree per repeated geometry, over its first copy: by the binned SAH
  // builder while the geometries are small in all, else as any part
  std::size_t uniquePrims = 0;
  for (const std::vector<std::uint32_t>& copies : repeated) uniquePrims += instances[copies[0]].count;
  BvhBuildOptions sahOptions = options;
  sahOptions.builder = BvhBuilder::Sah;
  std::vector<Bvh> geometryTrees;
  geometryTrees.reserve(repeated.size());
  std::vector<char> placed(n, 0);
  std::size_t placedPrims = 0, copiesPlaced = 0;
  for (const std::vector<std::uint32_t>& copies : repeated) {
    const BvhInstance& first = instances[copies[0]];
    const std::span<const Aabb> bounds = primBounds.subspan(first.first, first.count);
    geometryTrees.push_back(uniquePrims <= kSahGeometryPrims ? buildBvh(bounds, sahOptions) : buildPart(bounds, options));
    for (std::uint32_t c : copies) {
      std::fill(placed.begin() + instances[c].first, placed.begin() + instances[c].first + instances[c].count, 1);
      placedPrims += instances[c].count;
      ++copiesPlaced;
    }
  }

  // the rest, in one tree
  std::vector<std::uint32_t> restIndex;
  restIndex.reserve(n - placedPrims);
  for (std::uint32_t i = 0; i < n; ++i)
    if (!placed[i]) restIndex.push_back(i);
  std::vector<Aabb> restBounds(restIndex.size());
  for (std::size_t i = 0; i < restIndex.size(); ++i) restBounds[i] = primBounds[restIndex[i]];
  const Bvh restTree = buildPart(restBounds, options);

  // the top pass's clusters: every copy's root, the rest's subtrees
  std::vector<ClusterSource> sources;
  std::vector<TopCluster> clusters;
  for (std::size_t g = 0; g < repeated.size(); ++g)
    for (std::uint32_t c : repeated[g]) {
      clusters.push_back({Aabb{}, std::uint32_t(sources.size()), instances[c].count});
      sources.push_back({&geometryTrees[g], 0, instances[c].first, nullptr});
    }
  runTeam(builderThreads(options, placedPrims), [&](int rank, int size, Barrier&) {
    const Range chunk = chunkOf(clusters.size(), size, rank);
    for (std::size_t c = chunk.begin; c < chunk.end; ++c) {
      Aabb box;
      const std::uint32_t first = sources[c].primBase;
      for (std::uint32_t k = first; k < first + clusters[c].prims; ++k) box.extend(primBounds[k]);
      clusters[c].box = box;
    }
  });
  const std::vector<SubtreeSize> restSizes = subtreeSizes(restTree);
  if (!restTree.nodes.empty()) {
    const std::uint32_t cut = std::uint32_t(std::max<std::size_t>(restIndex.size() / kRestClusters, 1));
    std::vector<std::uint32_t> stack{0};
    while (!stack.empty()) {
      const std::uint32_t node = stack.back();
      stack.pop_back();
      const WtBvhNode& rn = restTree.nodes[node];
      if (rn.count == 0 && restSizes[node].prims > cut) {
        stack.push_back(rn.first + 1);
        stack.push_back(rn.first);
        continue;
      }
      clusters.push_back({nodeBox(rn), std::uint32_t(sources.size()), restSizes[node].prims});
      sources.push_back({&restTree, node, 0, &restIndex});
    }
  }
  const std::uint32_t clusterCount = std::uint32_t(clusters.size());
  std::vector<BuildNode> top(2 * std::size_t(clusterCount) - 1);
  const std::uint32_t topRoot = buildTopSah(clusters, top, clusterCount, builderThreads(options, clusterCount));
  // primitives below each top slot (a slot's children come after it) and cluster
  std::vector<std::uint32_t> topPrims(top.size(), 0);
  for (const TopCluster& cluster : clusters) topPrims[cluster.node] = cluster.prims;
  for (std::size_t b = top.size(); b-- > clusterCount;) topPrims[b] = topPrims[top[b].left] + topPrims[top[b].right];

  // Lay the tree out: the top nodes first (one thread; small copies the top
  // pass paired below the leaf size become one leaf there), then every
  // cluster's subtree copied into a range of its own and refitted, the
  // clusters shared among the threads; last the top nodes' boxes.
  Bvh bvh;
  bvh.primIndices.reserve(n);
  const auto mapPrim = [&](const ClusterSource& s, std::uint32_t local) {
    return s.primMap ? (*s.primMap)[local] : s.primBase + local;
  };
  struct Job {
    std::uint32_t source;  ///< cluster
    std::uint32_t slot;    ///< the output node its root fills
    int depth;
    std::uint32_t nodeBase = 0, primBase = 0;  ///< where its other nodes and its primitives go
  };
  std::vector<Job> jobs;
  jobs.reserve(clusterCount);
  {
    struct Open {
      std::uint32_t node;  ///< top slot or cluster
      std::uint32_t out;
      int depth;
    };
    std::vector<Open> open{{topRoot, 0, 0}};
    std::vector<std::uint32_t> topGather, gather;
    bvh.nodes.emplace_back();
    while (!open.empty()) {
      const Open o = open.back();
      open.pop_back();
      if (o.node < clusterCount) {
        jobs.push_back({o.node, o.out, o.depth});
        continue;
      }
      bvh.stats.maxDepth = std::max(bvh.stats.maxDepth, o.depth);
      if (topPrims[o.node] <= maxLeaf) {
        bvh.nodes[o.out].first = std::uint32_t(bvh.primIndices.size());
        bvh.nodes[o.out].count = topPrims[o.node];
        topGather.assign(1, o.node);
        while (!topGather.empty()) {
          const std::uint32_t t = topGather.back();
          topGather.pop_back();
          if (t >= clusterCount) {
            topGather.push_back(top[t].right), topGather.push_back(top[t].left);
            continue;
          }
          const ClusterSource& s = sources[t];
          gather.assign(1, s.node);
          while (!gather.empty()) {
            const WtBvhNode& g = s.tree->nodes[gather.back()];
            gather.pop_back();
            if (g.count > 0) {
              for (std::uint32_t k = g.first; k < g.first + g.count; ++k)
                bvh.primIndices.push_back(mapPrim(s, s.tree->primIndices[k]));
            } else {
              gather.push_back(g.first + 1), gather.push_back(g.first);
            }
          }
        }
        ++bvh.stats.leafCount;
        continue;
      }
      const std::uint32_t pair = appendChildPair(bvh.nodes, o.out);
      open.push_back({top[o.node].right, pair + 1, o.depth + 1});
      open.push_back({top[o.node].left, pair, o.depth + 1});
    }
  }
  const std::size_t topNodes = bvh.nodes.size();
  std::size_t nodeCursor = topNodes, primCursor = bvh.primIndices.size();
  for (Job& job : jobs) {
    const ClusterSource& s = sources[job.source];
    job.nodeBase = std::uint32_t(nodeCursor);
    job.primBase = std::uint32_t(primCursor);
    nodeCursor += (s.primMap ? restSizes[s.node].nodes : std::uint32_t(s.tree->nodes.size())) - 1;
    primCursor += topPrims[job.source];  // a cluster's primitives
  }
  bvh.nodes.resize(nodeCursor);
  bvh.primIndices.resize(primCursor);

  const auto refit = [&](std::uint32_t i) {
    WtBvhNode& node = bvh.nodes[i];
    Aabb box;
    if (node.count > 0) {
      for (std::uint32_t k = node.first; k < node.first + node.count; ++k) box.extend(primBounds[bvh.primIndices[k]]);
    } else {
      box = nodeBox(bvh.nodes[node.first]);
      box.extend(nodeBox(bvh.nodes[node.first + 1]));
    }
    setBox(node, box);
  };
  std::atomic<std::size_t> nextJob{0};
  std::vector<PerThread<std::size_t>> leaves(kMaxBuildThreads);
  std::vector<PerThread<int>> depths(kMaxBuildThreads);
  runTeam(builderThreads(options, n), [&](int rank, int, Barrier&) {
    struct Open {
      std::uint32_t node, out;
      int depth;
    };
    std::vector<Open> open;
    std::size_t myLeaves = 0;
    int myDepth = 0;
    for (std::size_t j; (j = nextJob.fetch_add(1, std::memory_order_relaxed)) < jobs.size();) {
      const Job& job = jobs[j];
      const ClusterSource& s = sources[job.source];
      std::uint32_t nodeNext = job.nodeBase, primNext = job.primBase;
      open.assign(1, {s.node, job.slot, job.depth});
      while (!open.empty()) {
        const Open o = open.back();
        open.pop_back();
        myDepth = std::max(myDepth, o.depth);
        const WtBvhNode& in = s.tree->nodes[o.node];
        WtBvhNode& out = bvh.nodes[o.out];
        if (in.count > 0) {
          out.first = primNext;
          out.count = in.count;
          for (std::uint32_t k = in.first; k < in.first + in.count; ++k)
            bvh.primIndices[primNext++] = mapPrim(s, s.tree->primIndices[k]);
          ++myLeaves;
          continue;
        }
        const std::uint32_t pair = nodeNext;
        nodeNext += 2;
        out.first = pair;
        out.count = 0;
        open.push_back({in.first + 1, pair + 1, o.depth + 1});
        open.push_back({in.first, pair, o.depth + 1});
      }
      // children come after their parents: bottom up is backwards, the root last
      for (std::uint32_t i = nodeNext; i-- > job.nodeBase;) refit(i);
      refit(job.slot);
    }
    leaves[std::size_t(rank)].value = myLeaves;
    depths[std::size_t(rank)].value = myDepth;
  });
  for (std::size_t r = 0; r < leaves.size(); ++r) {
    bvh.stats.leafCount += leaves[r].value;
    bvh.stats.maxDepth = std::max(bvh.stats.maxDepth, depths[r].value);
  }
  // the top nodes' boxes, bottom up (the job roots among them are done)
  for (std::size_t i = topNodes; i-- > 0;) refit(std::uint32_t(i));
  bvh.stats.nodeCount = bvh.nodes.size();
  bvh.stats.sahCost = sahCost(bvh);
  bvh.stats.copiesPlaced = copiesPlaced;
  bvh.stats.flatRegions = restTree.stats.flatRegions;
  for (const Bvh& tree : geometryTrees) bvh.stats.flatRegions += tree.stats.flatRegions;
  bvh.stats.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  char line[256];
  std::snprintf(line, sizeof line,
                "bvh (auto): %zu primitives, %zu geometries placed %zu times, %zu others, %u top clusters, "
                "%zu nodes, SAH %.2f, %.1f ms",
                n, repeated.size(), copiesPlaced, restIndex.size(),
                clusterCount, bvh.nodes.size(), bvh.stats.sahCost, 1e3 * bvh.stats.buildSeconds);
  log::debug(line);
  return bvh;
}

}  // namespace wt
