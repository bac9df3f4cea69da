// Top-down binned SAH build (Wald 2007): at every node the centroids are
// binned along each axis, the best of the 3 x 31 bin planes by
// area(left) * count(left) + area(right) * count(right) splits the node's
// items in place, and subtrees are handed to the threads through a shared
// queue. It is the yardstick for the faster builders, not a default.
#include "bvh/build_tree.h"
#include "bvh/builders.h"
#include "bvh/parallel.h"
#include "core/log.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace wt {
namespace {

using namespace bvh_detail;

constexpr int kBins = 32;
// Subtrees of more items go through the shared queue; smaller ones stay with one thread.
constexpr std::uint32_t kLocalTask = 4096;

struct Item {
  Aabb box;
  std::uint32_t index;  ///< input primitive
};

double area(const Aabb& box) {
  if (!(box.lo.x <= box.hi.x && box.lo.y <= box.hi.y && box.lo.z <= box.hi.z)) return 0.0;
  const double ex = double(box.hi.x) - box.lo.x, ey = double(box.hi.y) - box.lo.y, ez = double(box.hi.z) - box.lo.z;
  return 2.0 * (ex * ey + ey * ez + ez * ex);
}

float centroid(const Item& item, int axis) { return 0.5f * item.box.lo[axis] + 0.5f * item.box.hi[axis]; }

struct Task {
  std::uint32_t node, begin, end;
};

class SahBuild {
 public:
  SahBuild(std::vector<Item>& items, std::uint32_t maxLeaf) : m_items(items), m_maxLeaf(maxLeaf) {
    m_nodes.resize(std::max<std::size_t>(2 * items.size(), 1));
  }

  /// Box the items of a task and make it a leaf or split it; returns the
  /// children's tasks (none for a leaf).
  int process(const Task& task, std::array<Task, 2>& children) {
    BuildNode& node = m_nodes[task.node];
    Aabb bounds, centroids;
    for (std::uint32_t k = task.begin; k < task.end; ++k) {
      const Item& item = m_items[k];
      bounds.extend(item.box);
      for (int a = 0; a < 3; ++a) {
        const float c = centroid(item, a);
        if (!std::isfinite(c)) continue;
        centroids.lo[a] = std::min(centroids.lo[a], c);
        centroids.hi[a] = std::max(centroids.hi[a], c);
      }
    }
    node.box = bounds;
    const std::uint32_t count = task.end - task.begin;
    if (count <= m_maxLeaf) {
      node.first = task.begin;
      node.count = count;
      return 0;
    }

    // bin along each axis of positive centroid extent
    struct Bin {
      Aabb box;
      std::uint32_t count = 0;
    };
    int bestAxis = -1, bestPlane = 0;
    double bestCost = std::numeric_limits<double>::infinity();
    float scale[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      const float extent = centroids.hi[a] - centroids.lo[a];
      if (!(extent > 0.0f) || !std::isfinite(extent)) continue;
      scale[a] = float(kBins) * (1.0f - 1e-6f) / extent;
      std::array<Bin, kBins> bins{};
      for (std::uint32_t k = task.begin; k < task.end; ++k) {
        const int b = binOf(m_items[k], a, centroids.lo[a], scale[a]);
        bins[b].box.extend(m_items[k].box);
        ++bins[b].count;
      }
      // areas and counts right of each plane, then sweep from the left
      std::array<double, kBins> rightCost{};
      Aabb right;
      std::uint32_t rightCount = 0;
      for (int b = kBins - 1; b > 0; --b) {
        right.extend(bins[b].box);
        rightCount += bins[b].count;
        rightCost[b] = area(right) * rightCount;
      }
      Aabb left;
      std::uint32_t leftCount = 0;
      for (int plane = 1; plane < kBins; ++plane) {
        left.extend(bins[plane - 1].box);
        leftCount += bins[plane - 1].count;
        if (leftCount == 0 || leftCount == count) continue;
        const double cost = area(left) * leftCount + rightCost[plane];
        if (cost < bestCost) bestCost = cost, bestAxis = a, bestPlane = plane;
      }
    }

    std::uint32_t mid = task.begin + count / 2;  // no usable plane: split by position
    if (bestAxis >= 0) {
      const float lo = centroids.lo[bestAxis], s = scale[bestAxis];
      auto split = std::partition(m_items.begin() + task.begin, m_items.begin() + task.end,
                                  [&](const Item& item) { return binOf(item, bestAxis, lo, s) < bestPlane; });
      const std::uint32_t at = std::uint32_t(split - m_items.begin());
      if (at > task.begin && at < task.end) mid = at;
    }
    const std::uint32_t pair = m_next.fetch_add(2, std::memory_order_relaxed);
    node.left = pair;
    node.right = pair + 1;
    node.count = 0;
    children[0] = {pair, task.begin, mid};
    children[1] = {pair + 1, mid, task.end};
    return 2;
  }

  std::uint32_t allocateRoot() { return m_next.fetch_add(1, std::memory_order_relaxed); }
  std::vector<BuildNode>& nodes() { return m_nodes; }

 private:
  static int binOf(const Item& item, int axis, float lo, float scale) {
    const float x = (centroid(item, axis) - lo) * scale;
    // NaN and infinite centroids go to the outer bins
    if (!(x > 0.0f)) return 0;
    return x >= float(kBins - 1) ? kBins - 1 : int(x);
  }

  std::vector<Item>& m_items;
  std::uint32_t m_maxLeaf;
  std::vector<BuildNode> m_nodes;
  std::atomic<std::uint32_t> m_next{0};
};

}  // namespace

Bvh buildSahBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::size_t n = primBounds.size();
  if (n == 0) return {};
  if (n >= (std::size_t{1} << 31)) throw std::length_error("buildSahBvh: too many primitives for 32-bit node indices");
  const std::uint32_t maxLeaf = std::uint32_t(std::max(options.maxLeafSize, 1));
  const int threads = builderThreads(options, n);

  std::vector<Item> items(n);
  for (std::size_t i = 0; i < n; ++i) items[i] = {primBounds[i], std::uint32_t(i)};
  SahBuild build(items, maxLeaf);
  const std::uint32_t root = build.allocateRoot();

  // big subtrees through a shared queue; small ones finished by the thread that made them
  runTaskTree(
      threads, Task{root, 0, std::uint32_t(n)},
      [&](const Task& task, std::array<Task, 2>& children) { return build.process(task, children); },
      [](const Task& task) { return task.end - task.begin > kLocalTask; });

  std::vector<std::uint32_t> prims(n);
  for (std::size_t i = 0; i < n; ++i) prims[i] = items[i].index;
  Bvh bvh = layoutTree(build.nodes(), root, prims, maxLeaf);
  bvh.stats.buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  char line[160];
  std::snprintf(line, sizeof line, "bvh (sah): %zu primitives, %zu nodes, depth %d, SAH %.2f, %.1f ms on %d threads", n,
                bvh.nodes.size(), bvh.stats.maxDepth, bvh.stats.sahCost, 1e3 * bvh.stats.buildSeconds, threads);
  log::debug(line);
  return bvh;
}

}  // namespace wt
