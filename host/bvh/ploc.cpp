// PLOC (Meister and Bittner 2018, "Parallel locally-ordered clustering for
// bounding volume hierarchy construction") with a binned SAH pass on top.
// The primitives, sorted by Morton code as buildLbvh sorts them, are the
// first clusters. Each round every cluster finds the neighbour within
// plocRadius positions whose union with it has the smallest surface area;
// mutual nearest neighbours merge into a new node at the lower position, and
// the array is compacted. Clustering stops where the clusters average
// plocTopPrims primitives: PLOC's upper levels are where its tree is furthest
// from the SAH tree's (docs/lab/2026-12-01-performance-log.md, "What did not win"), so a binned
// SAH pass over the clusters, weighted by their primitive counts, builds the
// levels above. Subtrees of at most maxLeafSize primitives become leaves.
#include "bvh/build_tree.h"
#include "bvh/builders.h"
#include "bvh/parallel.h"
#include "core/log.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace wt {
namespace {

using namespace bvh_detail;

/// Cluster boxes by axis and bound, so the neighbour search reads them in lanes.
struct ClusterBoxes {
  std::vector<float> lx, ly, lz, hx, hy, hz;
  void resize(std::size_t n) {
    for (std::vector<float>* v : {&lx, &ly, &lz, &hx, &hy, &hz}) v->resize(n);
  }
  /// NaN bounds become infinite ones: std::min and std::max are not
  /// symmetric in NaN, and the search needs distance(i, j) == distance(j, i).
  void set(std::size_t i, const Aabb& box) {
    constexpr float inf = std::numeric_limits<float>::infinity();
    const auto lo = [](float v) { return v == v ? v : -inf; };
    const auto hi = [](float v) { return v == v ? v : inf; };
    lx[i] = lo(box.lo.x), ly[i] = lo(box.lo.y), lz[i] = lo(box.lo.z);
    hx[i] = hi(box.hi.x), hy[i] = hi(box.hi.y), hz[i] = hi(box.hi.z);
  }
};

Aabb unionBox(Aabb a, const Aabb& b) {
  a.extend(b);
  return a;
}

constexpr std::uint32_t kMaxRadius = 64;
/// PLOC stops when a round merges fewer than 1 / kMinMergeShare of its clusters.
constexpr std::uint64_t kMinMergeShare = 16;

/// Nearest neighbour of cluster i among [i - r, i + r]: the smallest union
/// area. Equal areas (duplicated or coincident primitives) go to the nearer
/// position, then to the pair whose lower position is even, then to the
/// lower pair: a strict order on pairs, so the globally smallest pair is
/// always mutual and every round merges at least one pair, and equal
/// clusters pair off two by two. (Ties to the lowest position in the window
/// merged one pair per window and round: 60 000 equal boxes took 63 s.)
std::uint32_t nearestNeighbour(const ClusterBoxes& c, std::uint32_t i, std::uint32_t count, std::uint32_t r) {
  const std::uint32_t lo = i > r ? i - r : 0, hi = std::min(count - 1, i + r);
  const float lx = c.lx[i], ly = c.ly[i], lz = c.lz[i], hx = c.hx[i], hy = c.hy[i], hz = c.hz[i];
  // the areas first, in a loop the compiler vectorises; i's own slot is skipped below
  float area[2 * kMaxRadius + 1];
  const std::uint32_t width = hi - lo + 1;
  for (std::uint32_t k = 0; k < width; ++k) {
    const std::uint32_t j = lo + k;
    const float ex = std::max(hx, c.hx[j]) - std::min(lx, c.lx[j]);
    const float ey = std::max(hy, c.hy[j]) - std::min(ly, c.ly[j]);
    const float ez = std::max(hz, c.hz[j]) - std::min(lz, c.lz[j]);
    area[k] = ex * ey + ey * ez + ez * ex;  // half the area: the order is the same
  }
  // the smallest area, ties to the lowest position (as fast as it was before
  // ties were ordered: this loop is most of the build); then, only where
  // another slot has the same area, the tie order among those slots
  float best = std::numeric_limits<float>::infinity();
  std::uint32_t bestK = lo == i ? 1 : 0;
  for (std::uint32_t k = 0; k < width; ++k) {
    // NaN (infinite bounds) ranks with +inf, last
    if (lo + k != i && area[k] < best) best = area[k], bestK = k;
  }
  std::uint32_t equal = 0;  // a loop the compiler vectorises; i's own slot may count
  for (std::uint32_t k = 0; k < width; ++k) equal += area[k] == best;
  std::uint32_t bestJ = lo + bestK;
  if (equal <= 1) return bestJ;
  const auto tieKey = [i](std::uint32_t j) {
    const std::uint32_t low = std::min(i, j), distance = i > j ? i - j : j - i;
    return std::uint64_t(distance) << 33 | std::uint64_t(low & 1u) << 32 | low;
  };
  std::uint64_t bestKey = ~std::uint64_t{0};
  for (std::uint32_t k = 0; k < width; ++k) {
    const std::uint32_t j = lo + k;
    if (j == i || area[k] != best) continue;
    const std::uint64_t key = tieKey(j);
    if (key < bestKey) bestKey = key, bestJ = j;
  }
  return bestJ;
}

/// A finished subtree that the top-down SAH pass treats as one primitive.
double boxArea(const Aabb& box) {
  const double ex = double(box.hi.x) - box.lo.x, ey = double(box.hi.y) - box.lo.y, ez = double(box.hi.z) - box.lo.z;
  if (!(ex >= 0.0 && ey >= 0.0 && ez >= 0.0)) return 0.0;
  return 2.0 * (ex * ey + ey * ez + ez * ex);
}

}  // namespace

namespace bvh_detail {

std::uint32_t buildTopSah(std::vector<TopCluster>& clusters, std::vector<BuildNode>& nodes, std::uint32_t first,
                          int threads) {
  constexpr int kBins = 32;
  constexpr std::uint32_t kSharedTask = 1024;  // clusters; smaller subtrees stay with one thread
  if (clusters.size() == 1) return clusters[0].node;
  struct Task {
    std::uint32_t begin, end;  ///< clusters
    std::uint32_t node;        ///< this subtree's root
    std::uint32_t free;        ///< first of the (end - begin - 2) slots of its descendants
  };
  const auto process = [&](const Task& task, std::array<Task, 2>& children) {
    Aabb bounds, centroids;
    for (std::uint32_t k = task.begin; k < task.end; ++k) {
      const Aabb& b = clusters[k].box;
      bounds = unionBox(bounds, b);
      const glm::vec3 c = 0.5f * b.lo + 0.5f * b.hi;
      for (int a = 0; a < 3; ++a)
        if (std::isfinite(c[a])) centroids.lo[a] = std::min(centroids.lo[a], c[a]), centroids.hi[a] = std::max(centroids.hi[a], c[a]);
    }
    nodes[task.node].box = bounds;
    const std::uint32_t count = task.end - task.begin;
    int bestAxis = -1, bestPlane = 0;
    double bestCost = std::numeric_limits<double>::infinity();
    float scale[3] = {0, 0, 0};
    const auto binOf = [&](const TopCluster& t, int a) {
      const float x = ((0.5f * t.box.lo[a] + 0.5f * t.box.hi[a]) - centroids.lo[a]) * scale[a];
      if (!(x > 0.0f)) return 0;
      return x >= float(kBins - 1) ? kBins - 1 : int(x);
    };
    for (int a = 0; a < 3 && count > 2; ++a) {
      const float extent = centroids.hi[a] - centroids.lo[a];
      if (!(extent > 0.0f) || !std::isfinite(extent)) continue;
      scale[a] = float(kBins) * (1.0f - 1e-6f) / extent;
      Aabb binBox[kBins];
      double binWeight[kBins] = {};
      std::uint32_t binCount[kBins] = {};
      for (std::uint32_t k = task.begin; k < task.end; ++k) {
        const int b = binOf(clusters[k], a);
        binBox[b] = unionBox(binBox[b], clusters[k].box);
        binWeight[b] += clusters[k].prims;
        ++binCount[b];
      }
      double rightCost[kBins] = {};
      Aabb right;
      double rightWeight = 0.0;
      for (int b = kBins - 1; b > 0; --b) {
        right = unionBox(right, binBox[b]);
        rightWeight += binWeight[b];
        rightCost[b] = boxArea(right) * rightWeight;
      }
      Aabb left;
      double leftWeight = 0.0;
      std::uint32_t leftCount = 0;
      for (int plane = 1; plane < kBins; ++plane) {
        left = unionBox(left, binBox[plane - 1]);
        leftWeight += binWeight[plane - 1];
        leftCount += binCount[plane - 1];
        if (leftCount == 0 || leftCount == count) continue;
        const double cost = boxArea(left) * leftWeight + rightCost[plane];
        if (cost < bestCost) bestCost = cost, bestAxis = a, bestPlane = plane;
      }
    }
    // no usable plane (or two clusters): split by position, which is Morton order
    std::uint32_t mid = task.begin + count / 2;
    if (bestAxis >= 0) {
      auto split = std::partition(clusters.begin() + task.begin, clusters.begin() + task.end,
                                  [&](const TopCluster& t) { return binOf(t, bestAxis) < bestPlane; });
      const std::uint32_t at = std::uint32_t(split - clusters.begin());
      if (at > task.begin && at < task.end) mid = at;
    }
    // the left subtree's slots first, then the right's
    const std::uint32_t leftSize = mid - task.begin, rightSize = task.end - mid;
    int spawned = 0;
    std::uint32_t child[2];
    if (leftSize == 1) {
      child[0] = clusters[task.begin].node;
    } else {
      child[0] = task.free;
      children[spawned++] = {task.begin, mid, task.free, task.free + 1};
    }
    const std::uint32_t rightFree = task.free + (leftSize - 1);
    if (rightSize == 1) {
      child[1] = clusters[mid].node;
    } else {
      child[1] = rightFree;
      children[spawned++] = {mid, task.end, rightFree, rightFree + 1};
    }
    nodes[task.node].left = child[0];
    nodes[task.node].right = child[1];
    nodes[task.node].count = 0;
    return spawned;
  };
  runTaskTree(threads, Task{0, std::uint32_t(clusters.size()), first, first + 1}, process,
              [](const Task& task) { return task.end - task.begin > kSharedTask; });
  return first;
}

}  // namespace bvh_detail

Bvh buildPlocBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  // One primitive per first cluster, in Morton order. Seeding with the LBVH's
  // leaves of up to maxLeafSize instead gave a worse 4-wide SAH
  // (docs/lab/2026-12-01-performance-log.md, "What did not win").
  const std::size_t n = primBounds.size();
  const std::uint32_t maxLeaf = std::uint32_t(std::max(options.maxLeafSize, 1));
  if (n <= std::max<std::size_t>(maxLeaf, 2)) return buildLbvh(primBounds, options);  // one leaf, or two
  if (n >= (std::size_t{1} << 31)) throw std::length_error("buildPlocBvh: too many primitives for 32-bit node indices");
  const int threads = builderThreads(options, n);
  const std::vector<std::uint32_t> order = mortonOrder(primBounds, threads);
  const double sortSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto plocStart = std::chrono::steady_clock::now();
  const std::uint32_t leaves = std::uint32_t(n);
  std::vector<BuildNode> nodes(2 * std::size_t(leaves) - 1);
  std::vector<std::uint32_t> cluster(leaves), next(leaves), nn(leaves);
  ClusterBoxes boxes, nextBoxes;
  boxes.resize(leaves);
  nextBoxes.resize(leaves);
  runTeam(threads, [&](int rank, int size, Barrier&) {
    const Range chunk = chunkOf(leaves, size, rank);
    for (std::size_t c = chunk.begin; c < chunk.end; ++c) {
      BuildNode& node = nodes[c];
      node.box = primBounds[order[c]];
      node.first = std::uint32_t(c);
      node.count = 1;
      boxes.set(c, node.box);
      cluster[c] = std::uint32_t(c);
    }
  });

  // rounds: neighbours, then merge and compact; each phase split over the team
  const std::uint32_t radius = std::uint32_t(std::clamp(options.plocRadius, 1, int(kMaxRadius)));
  std::vector<PerThread<std::uint32_t>> merges(threads), survivors(threads);
  std::uint32_t count = leaves, nextNode = leaves;
  // PLOC stops where the clusters average plocTopPrims primitives; SAH builds the rest
  const std::uint32_t stop =
      options.plocTopPrims > 0 ? std::max<std::uint32_t>(1, std::uint32_t(n / std::size_t(options.plocTopPrims))) : 1;
  int rounds = 0;
  bool stalled = false;
  runTeam(threads, [&](int rank, int size, Barrier& barrier) {
    while (count > stop && !stalled) {
      const Range chunk = chunkOf(count, size, rank);
      for (std::size_t i = chunk.begin; i < chunk.end; ++i)
        nn[i] = nearestNeighbour(boxes, std::uint32_t(i), count, radius);
      barrier.arriveAndWait();

      std::uint32_t merged = 0, kept = 0;
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        const bool mutual = nn[nn[i]] == i;
        merged += mutual && i < nn[i];
        kept += !(mutual && i > nn[i]);
      }
      merges[rank].value = merged;
      survivors[rank].value = kept;
      barrier.arriveAndWait();

      std::uint32_t node = nextNode, out = 0, total = 0;
      for (int r = 0; r < size; ++r) {
        if (r < rank) node += merges[r].value, out += survivors[r].value;
        total += survivors[r].value;
      }
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        const std::uint32_t j = nn[i];
        const bool mutual = nn[j] == i;
        if (mutual && i > j) continue;  // merged into j
        if (mutual) {
          BuildNode& parent = nodes[node];
          parent.left = cluster[i];
          parent.right = cluster[j];
          parent.box = unionBox(nodes[cluster[i]].box, nodes[cluster[j]].box);
          next[out] = node++;
          nextBoxes.set(out, parent.box);
        } else {
          next[out] = cluster[i];
          nextBoxes.lx[out] = boxes.lx[i], nextBoxes.ly[out] = boxes.ly[i], nextBoxes.lz[out] = boxes.lz[i];
          nextBoxes.hx[out] = boxes.hx[i], nextBoxes.hy[out] = boxes.hy[i], nextBoxes.hz[out] = boxes.hz[i];
        }
        ++out;
      }
      barrier.arriveAndWait();
      if (rank == 0) {
        std::uint32_t mergedTotal = 0;
        for (int r = 0; r < size; ++r) mergedTotal += merges[r].value;
        nextNode += mergedTotal;
        // The pair of smallest distance is always mutual, so every round merges.
        // A round that merges fewer than 1/16 of the clusters (the bench's
        // scenes merge far more a round) hands them to the SAH pass below: clusters
        // whose nearest neighbours run in one direction (sizes or gaps growing
        // along the order) merge one pair a round, quadratic time and a chain.
        if (mergedTotal == 0 || std::uint64_t(mergedTotal) * kMinMergeShare < count) stalled = true;
        count = total;
        std::swap(cluster, next);
        std::swap(boxes, nextBoxes);
        ++rounds;
      }
      barrier.arriveAndWait();
    }
  });

  const auto topStart = std::chrono::steady_clock::now();
  std::vector<TopCluster> top(count);
  for (std::uint32_t k = 0; k < count; ++k) top[k] = {nodes[cluster[k]].box, cluster[k], 0};
  {
    // primitive counts: children are numbered before their parents
    std::vector<std::uint32_t> prims(nextNode, 0);
    for (std::uint32_t b = 0; b < nextNode; ++b)
      prims[b] = nodes[b].count > 0 ? nodes[b].count : prims[nodes[b].left] + prims[nodes[b].right];
    for (TopCluster& t : top) t.prims = prims[t.node];
  }
  const std::uint32_t topClusters = count;
  const std::uint32_t root = buildTopSah(top, nodes, nextNode, threads);
  const double topSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - topStart).count();
  Bvh bvh = layoutTree(nodes, root, order, maxLeaf);
  const auto end = std::chrono::steady_clock::now();
  bvh.stats.buildSeconds = std::chrono::duration<double>(end - start).count();
  bvh.stats.clusterRounds = rounds;
  char line[256];
  std::snprintf(line, sizeof line,
                "bvh (ploc): %zu primitives, %zu nodes, depth %d, SAH %.2f, %.1f ms on %d threads "
                "(morton sort %.1f, %d rounds of radius %u, then SAH over %u clusters %.1f; all but the sort %.1f)",
                n, bvh.nodes.size(), bvh.stats.maxDepth, bvh.stats.sahCost,
                1e3 * bvh.stats.buildSeconds, threads, 1e3 * sortSeconds, rounds, radius, topClusters,
                1e3 * topSeconds, 1e3 * std::chrono::duration<double>(end - plocStart).count());
  log::debug(line);
  return bvh;
}

Bvh buildBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& given, std::span<const BvhInstance> instances) {
  BvhBuildOptions options = given;
  if (options.maxLeafSize <= 0) options.maxLeafSize = 4;
  switch (options.builder) {
    case BvhBuilder::Auto: return buildAutoBvh(primBounds, options, instances);
    case BvhBuilder::Ploc: return buildPlocBvh(primBounds, options);
    case BvhBuilder::Sah: return buildSahBvh(primBounds, options);
    case BvhBuilder::Lbvh: break;
  }
  return buildLbvh(primBounds, options);
}

const char* bvhBuilderName(BvhBuilder builder) {
  switch (builder) {
    case BvhBuilder::Auto: return "auto";
    case BvhBuilder::Ploc: return "ploc";
    case BvhBuilder::Sah: return "sah";
    case BvhBuilder::Lbvh: break;
  }
  return "lbvh";
}

std::optional<BvhBuilder> parseBvhBuilder(std::string_view name) {
  for (BvhBuilder b : {BvhBuilder::Auto, BvhBuilder::Lbvh, BvhBuilder::Ploc, BvhBuilder::Sah})
    if (name == bvhBuilderName(b)) return b;
  return std::nullopt;
}

}  // namespace wt
