#include "bvh/bvh4.h"

#include "bvh/parallel.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <ranges>
#include <stdexcept>
#include <vector>

namespace wt {
namespace {

double boxArea(float lx, float ly, float lz, float hx, float hy, float hz) {
  const double ex = double(hx) - lx, ey = double(hy) - ly, ez = double(hz) - lz;
  if (!(ex >= 0.0 && ey >= 0.0 && ez >= 0.0)) return 0.0;
  return 2.0 * (ex * ey + ey * ez + ez * ex);
}

double binaryArea(const WtBvhNode& n) { return boxArea(n.lo_x, n.lo_y, n.lo_z, n.hi_x, n.hi_y, n.hi_z); }

void setSlot(WtBvh4Node& node, int k, const WtBvhNode& box, std::uint32_t child, std::uint32_t count) {
  node.lo_x[k] = box.lo_x, node.lo_y[k] = box.lo_y, node.lo_z[k] = box.lo_z;
  node.hi_x[k] = box.hi_x, node.hi_y[k] = box.hi_y, node.hi_z[k] = box.hi_z;
  node.child[k] = child;
  node.count[k] = count;
}

WtBvh4Node emptyNode() {
  WtBvh4Node node;
  const float inf = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 4; ++k) {
    node.lo_x[k] = node.lo_y[k] = node.lo_z[k] = inf;
    node.hi_x[k] = node.hi_y[k] = node.hi_z[k] = -inf;
    node.child[k] = WT_BVH4_EMPTY;
    node.count[k] = 0;
  }
  return node;
}

/// What the collapse knows of one binary subtree: the least cost of hanging
/// it under a 4-wide node in at most 1, 2, 3 or 4 slots (cost[j - 1]), in
/// units of area; more slots never cost more.
struct SubtreeCost {
  float cost[4];
};

/// How one binary subtree fills the slots it is given, packed in a byte:
/// bit 0: as one slot, a leaf (else a 4-wide node of its own); for 2, 3 and
/// 4 slots (bit 1, bits 2-3, bits 4-5): 0 when one slot fewer does as well,
/// else how many of them the left child takes; bits 6-7: the left child's
/// share of the four slots when the subtree is a 4-wide node.
struct Decision {
  std::uint8_t bits = 0;
  static int shift(int slots) { return slots == 2 ? 1 : 2 * slots - 4; }
  bool leaf() const { return bits & 1u; }
  int left(int slots) const { return (bits >> shift(slots)) & (slots == 2 ? 1 : 3); }  ///< slots = 2, 3, 4
  int nodeLeft() const { return bits >> 6; }
};

using bvh_detail::Barrier;
using bvh_detail::runTeam;

/// The threads a collapse of `bvh` runs on: options.threads (0: all the
/// host has) for a tree collapsed in parts, else one.
int collapseThreads(const Bvh& bvh, const Bvh4Options& options) {
  if (bvh.primIndices.size() < options.partsFromPrimitives) return 1;
  return bvh_detail::resolveThreads(options.threads);
}

class Collapse {
 public:
  Collapse(const Bvh& bvh, const Bvh4Options& options) : m_in(bvh.nodes), m_options(options) {
    // in parts on one thread as on many, so that the layout never depends on the count
    m_parts = bvh.primIndices.size() >= options.partsFromPrimitives;
    m_threads = collapseThreads(bvh, options);
    m_partPrims = std::uint32_t(std::max<std::size_t>(bvh.primIndices.size() / kParts, 1));
  }

  Bvh4 run() {
    Bvh4 out;
    if (m_in.empty()) return out;
    const std::size_t n = m_in.size();
    m_cost.resize(n);
    m_decision.resize(n);
    m_prims.resize(n);
    m_firstPrim.resize(n);
    const double rootArea = binaryArea(m_in[0]);
    // a point or a segment has no area ratios: weigh every test alike
    m_unitAreas = !(rootArea > 0.0) || !std::isfinite(rootArea);
    m_nodeCost = float(m_options.nodeCost * (m_unitAreas ? 1.0 : rootArea));
    m_maxLeaf = std::uint32_t(std::max(m_options.maxLeafSize, 1));

    if (m_parts) {
      evaluateInParts();
    } else {
      // children before parents: a flatten that lays children out after their
      // parent (every builder here) is walked backwards, any other in post-order
      bool childrenAfter = true;
      for (std::uint32_t i = 0; i < n && childrenAfter; ++i) childrenAfter = m_in[i].count > 0 || m_in[i].first > i;
      if (childrenAfter) {
        for (std::size_t i = n; i-- > 0;) evaluate(std::uint32_t(i));
      } else {
        std::vector<std::uint32_t> order;
        preorder(0, order);
        for (std::uint32_t i : order | std::views::reverse) evaluate(i);
      }
    }

    out.nodes.reserve(n / 4 + 1);
    out.nodes.push_back(emptyNode());
    if (m_rootIsLeaf) {
      setSlot(out.nodes[0], 0, m_in[0], m_firstPrim[0], m_prims[0]);
      out.stats.leafCount = 1;
    } else if (m_parts) {
      emitInParts(out);
    } else {
      EmitStats stats;
      emit({0, 0, 0}, out.nodes, nullptr, stats);
      out.stats.leafCount = stats.leafCount;
      out.stats.maxDepth = stats.maxDepth;
    }
    out.stats.nodeCount = out.nodes.size();
    return out;
  }

 private:
  /// A large tree is evaluated as the binary subtrees from depth kSplitDepth,
  /// then the nodes above them, and laid out as the 4-wide nodes over binary
  /// subtrees of more than 1/kParts of the primitives, then the parts below
  /// them one after another.
  static constexpr int kSplitDepth = 8;
  static constexpr std::size_t kParts = 256;

  struct Slot {
    std::uint32_t binary;
    bool leaf;
  };

  /// A 4-wide node to fill: from the children of binary node `binary`.
  struct Task {
    std::uint32_t binary, node;
    int depth;
  };

  struct EmitStats {
    std::size_t leafCount = 0;
    int maxDepth = 0;
  };

  /// Subtree `root` in pre-order (parents before children), appended to order.
  void preorder(std::uint32_t root, std::vector<std::uint32_t>& order) const {
    std::vector<std::uint32_t> stack{root};
    while (!stack.empty()) {
      std::uint32_t i = stack.back();
      stack.pop_back();
      order.push_back(i);
      if (m_in[i].count == 0) stack.push_back(m_in[i].first + 1), stack.push_back(m_in[i].first);
    }
  }

  void evaluateInParts() {
    // the nodes above kSplitDepth in pre-order; the subtrees hanging from them
    std::vector<std::uint32_t> top, roots;
    std::vector<std::pair<std::uint32_t, int>> stack{{0u, 0}};
    while (!stack.empty()) {
      const auto [i, depth] = stack.back();
      stack.pop_back();
      if (depth == kSplitDepth) {
        roots.push_back(i);
        continue;
      }
      top.push_back(i);
      if (m_in[i].count == 0) stack.push_back({m_in[i].first + 1, depth + 1}), stack.push_back({m_in[i].first, depth + 1});
    }
    std::atomic<std::size_t> next{0};
    runTeam(std::min<int>(m_threads, int(roots.size()) + 1), [&](int, int, Barrier&) {
      std::vector<std::uint32_t> order;
      for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < roots.size();) {
        order.clear();
        preorder(roots[k], order);
        for (std::uint32_t i : order | std::views::reverse) evaluate(i);
      }
    });
    for (std::uint32_t i : top | std::views::reverse) evaluate(i);
  }

  /// Node i's costs and decision, from its children's.
  void evaluate(std::uint32_t i) {
    const WtBvhNode& node = m_in[i];
    const float area = m_unitAreas ? 1.0f : float(binaryArea(node));
    const float inf = std::numeric_limits<float>::infinity();
    SubtreeCost& s = m_cost[i];
    Decision& d = m_decision[i];
    if (node.count > 0) {
      m_prims[i] = node.count;
      m_firstPrim[i] = node.first;
      s.cost[0] = s.cost[1] = s.cost[2] = s.cost[3] = leafTestCost(area, node.count);
      d.bits = 1;
      if (i == 0) m_rootIsLeaf = true;
      return;
    }
    const std::uint32_t l = node.first, r = l + 1;
    m_prims[i] = m_prims[l] + m_prims[r];
    m_firstPrim[i] = m_firstPrim[l];
    // j slots shared between the two children, j = 2..4
    float split[5];
    int left[5];
    for (int j = 2; j <= 4; ++j) {
      split[j] = inf;
      left[j] = 1;
      for (int k = 1; k < j; ++k) {
        const float cost = m_cost[l].cost[k - 1] + m_cost[r].cost[j - k - 1];
        if (cost < split[j]) split[j] = cost, left[j] = k;
      }
    }
    const bool contiguous = m_firstPrim[r] == m_firstPrim[l] + m_prims[l];
    const float asLeaf = m_prims[i] <= m_maxLeaf && contiguous ? leafTestCost(area, m_prims[i]) : inf;
    const float asNode = area + m_nodeCost + split[4];
    std::uint32_t bits = asLeaf <= asNode ? 1u : 0u;
    s.cost[0] = std::min(asLeaf, asNode);
    for (int j = 2; j <= 4; ++j) {
      if (s.cost[j - 2] <= split[j]) {
        s.cost[j - 1] = s.cost[j - 2];
      } else {
        s.cost[j - 1] = split[j];
        bits |= std::uint32_t(left[j]) << Decision::shift(j);
      }
    }
    d.bits = std::uint8_t(bits | std::uint32_t(left[4]) << 6);
    // the root is a 4-wide node in any case: it is one leaf only when that beats its four slots
    if (i == 0) m_rootIsLeaf = asLeaf <= split[4];
  }

  float leafTestCost(float area, std::uint32_t prims) const {
    return area * float(m_options.leafCost) * float((prims + 3) / 4);
  }

  /// The slots subtree i fills when it may take up to j of them, left to right.
  void gather(std::uint32_t i, int j, std::vector<Slot>& slots) const {
    struct Item {
      std::uint32_t binary;
      int slots;
    };
    Item stack[8];
    int sp = 0;
    stack[sp++] = {i, j};
    while (sp > 0) {
      const Item item = stack[--sp];
      const Decision d = m_decision[item.binary];
      const int left = item.slots > 1 && m_in[item.binary].count == 0 ? d.left(item.slots) : -1;
      if (left < 0) {
        slots.push_back({item.binary, d.leaf()});
      } else if (left == 0) {
        stack[sp++] = {item.binary, item.slots - 1};  // one slot fewer does as well
      } else {
        stack[sp++] = {m_in[item.binary].first + 1, item.slots - left};
        stack[sp++] = {m_in[item.binary].first, left};
      }
    }
  }

  /// Fill nodes[root.node] from root.binary's children and lay the 4-wide
  /// nodes below it out depth first, so that a node's first child sits right
  /// behind it. With `deferred`, a node over a binary subtree of at most
  /// m_partPrims primitives is left empty and its task appended there.
  void emit(const Task& root, std::vector<WtBvh4Node>& nodes, std::vector<Task>* deferred, EmitStats& stats) const {
    std::vector<Task> stack{root};
    std::vector<Slot> slots;
    while (!stack.empty()) {
      const Task task = stack.back();
      stack.pop_back();
      if (deferred && task.node != root.node && m_prims[task.binary] <= m_partPrims) {
        deferred->push_back(task);
        continue;
      }
      stats.maxDepth = std::max(stats.maxDepth, task.depth);
      const std::uint32_t l = m_in[task.binary].first;
      const int left = m_decision[task.binary].nodeLeft();
      slots.clear();
      gather(l, left, slots);
      gather(l + 1, 4 - left, slots);
      std::array<Task, 4> pending;
      int pendingCount = 0;
      for (std::size_t k = 0; k < slots.size(); ++k) {
        const std::uint32_t b = slots[k].binary;
        if (slots[k].leaf) {
          setSlot(nodes[task.node], int(k), m_in[b], m_firstPrim[b], m_prims[b]);
          ++stats.leafCount;
        } else {
          const std::uint32_t index = std::uint32_t(nodes.size());
          nodes.push_back(emptyNode());
          setSlot(nodes[task.node], int(k), m_in[b], index, 0);
          pending[std::size_t(pendingCount++)] = {b, index, task.depth + 1};
        }
      }
      for (int k = pendingCount - 1; k >= 0; --k) stack.push_back(pending[std::size_t(k)]);
    }
  }

  /// The nodes over the large subtrees first, then each part's nodes (its
  /// root in the slot the top left for it, the rest in one block), parts in
  /// the order the top met them.
  void emitInParts(Bvh4& out) const {
    std::vector<Task> deferred;
    EmitStats topStats;
    emit({0, 0, 0}, out.nodes, &deferred, topStats);
    std::vector<std::vector<WtBvh4Node>> parts(deferred.size());
    std::vector<EmitStats> partStats(deferred.size());
    std::atomic<std::size_t> next{0};
    const int team = std::min<int>(m_threads, int(deferred.size()) + 1);
    runTeam(team, [&](int, int, Barrier&) {
      for (std::size_t k; (k = next.fetch_add(1, std::memory_order_relaxed)) < deferred.size();) {
        // built in locals: neighbouring parts' vectors and counts share cache lines
        std::vector<WtBvh4Node> nodes;
        nodes.reserve(m_prims[deferred[k].binary] / 8 + 16);
        nodes.push_back(emptyNode());
        EmitStats stats;
        emit({deferred[k].binary, 0, deferred[k].depth}, nodes, nullptr, stats);
        parts[k] = std::move(nodes);
        partStats[k] = stats;
      }
    });
    // part k's node j > 0 goes to base[k] + j - 1
    std::vector<std::size_t> base(deferred.size());
    std::size_t total = out.nodes.size();
    out.stats.leafCount = topStats.leafCount;
    out.stats.maxDepth = topStats.maxDepth;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      base[k] = total;
      total += parts[k].size() - 1;
      out.stats.leafCount += partStats[k].leafCount;
      out.stats.maxDepth = std::max(out.stats.maxDepth, partStats[k].maxDepth);
    }
    out.nodes.reserve(total);
    for (const std::vector<WtBvh4Node>& part : parts) out.nodes.insert(out.nodes.end(), part.begin() + 1, part.end());
    runTeam(team, [&](int rank, int size, Barrier&) {
      const bvh_detail::Range range = bvh_detail::chunkOf(parts.size(), size, rank);
      for (std::size_t k = range.begin; k < range.end; ++k) {
        const std::uint32_t offset = std::uint32_t(base[k] - 1);
        const auto relocate = [offset](WtBvh4Node& node) {
          for (int c = 0; c < 4; ++c)
            if (node.count[c] == 0 && node.child[c] != WT_BVH4_EMPTY) node.child[c] += offset;
        };
        out.nodes[deferred[k].node] = parts[k][0];
        relocate(out.nodes[deferred[k].node]);
        for (std::size_t j = base[k]; j < base[k] + parts[k].size() - 1; ++j) relocate(out.nodes[j]);
      }
    });
  }

  const BvhNodes& m_in;
  Bvh4Options m_options;
  bool m_unitAreas = false;
  bool m_rootIsLeaf = false;
  float m_nodeCost = 0.0f;
  std::uint32_t m_maxLeaf = 1;
  bool m_parts = false;
  int m_threads = 1;
  std::uint32_t m_partPrims = 1;
  std::vector<SubtreeCost, UninitialisedAllocator<SubtreeCost>> m_cost;
  std::vector<Decision> m_decision;
  std::vector<std::uint32_t, UninitialisedAllocator<std::uint32_t>> m_prims, m_firstPrim;
};

}  // namespace

namespace {

/// The root's box: the union of its children's.
double rootArea(const WtBvh4Node& root) {
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int k = 0; k < 4; ++k) {
    if (root.child[k] == WT_BVH4_EMPTY) continue;
    lo[0] = std::min(lo[0], root.lo_x[k]), lo[1] = std::min(lo[1], root.lo_y[k]), lo[2] = std::min(lo[2], root.lo_z[k]);
    hi[0] = std::max(hi[0], root.hi_x[k]), hi[1] = std::max(hi[1], root.hi_y[k]), hi[2] = std::max(hi[2], root.hi_z[k]);
  }
  return boxArea(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
}

double slotArea(const WtBvh4Node& node, int k) {
  return boxArea(node.lo_x[k], node.lo_y[k], node.lo_z[k], node.hi_x[k], node.hi_y[k], node.hi_z[k]);
}

struct TreeCosts {
  double sah = 0.0, collapse = 0.0;
};

/// sahCost and collapseCost in one pass, over fixed chunks of nodes summed
/// in order: the same figures on any number of threads.
TreeCosts treeCosts(const Bvh4& bvh, const Bvh4Options& options, int threads) {
  TreeCosts costs;
  if (bvh.nodes.empty()) return costs;
  const double area = rootArea(bvh.nodes[0]);
  const bool unit = !(area > 0.0) || !std::isfinite(area);
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (bvh.nodes.size() + kChunk - 1) / kChunk;
  struct Sums {
    double sahArea = 0.0, sahWeight = 0.0, collapse = 0.0;
  };
  std::vector<Sums> sums(chunks);
  const auto sumChunk = [&](std::size_t c) {
    Sums s;
    const std::size_t end = std::min(bvh.nodes.size(), (c + 1) * kChunk);
    for (std::size_t i = c * kChunk; i < end; ++i) {
      const WtBvh4Node& node = bvh.nodes[i];
      for (int k = 0; k < 4; ++k) {
        if (node.child[k] == WT_BVH4_EMPTY) continue;
        const double slot = slotArea(node, k);
        const bool leaf = node.count[k] > 0;
        const double w = leaf ? double(node.count[k]) : 1.0;
        s.sahArea += w * slot;
        s.sahWeight += w;
        const double a = unit ? 1.0 : slot / area;
        s.collapse += leaf ? a * options.leafCost * double((node.count[k] + 3) / 4) : a + options.nodeCost;
      }
    }
    sums[c] = s;
  };
  if (threads > 1 && chunks > 1) {
    std::atomic<std::size_t> next{0};
    runTeam(std::min<int>(threads, int(chunks)), [&](int, int, Barrier&) {
      for (std::size_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks;) sumChunk(c);
    });
  } else {
    for (std::size_t c = 0; c < chunks; ++c) sumChunk(c);
  }
  Sums total;
  total.sahWeight = 1.0;  // the root's test
  for (const Sums& s : sums) total.sahArea += s.sahArea, total.sahWeight += s.sahWeight, total.collapse += s.collapse;
  // degenerate roots (a point or a segment) give no ratio: count every test
  costs.sah = unit || !std::isfinite(total.sahArea) ? total.sahWeight : 1.0 + total.sahArea / area;
  costs.collapse = 1.0 + options.nodeCost + total.collapse;  // the root's test and node
  return costs;
}

}  // namespace

Bvh4 collapseToBvh4(const Bvh& bvh, const Bvh4Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Bvh4 out = Collapse(bvh, options).run();
  // over the memory budget: nodes made dearer until the tree fits
  const double prims = double(bvh.primIndices.size());
  Bvh4Options dearer = options;
  for (int round = 0; round < Bvh4Options::kBudgetRounds && options.nodeBytesPerPrimitive > 0.0 &&
                      out.nodes.size() > 1 &&  // one node is the fewest a tree can have
                      double(out.nodes.size() * sizeof(WtBvh4Node)) > options.nodeBytesPerPrimitive * prims;
       ++round) {
    dearer.nodeCost = std::max(2.0 * dearer.nodeCost, 1e-6);
    out = Collapse(bvh, dearer).run();
  }
  const TreeCosts costs = treeCosts(out, dearer, collapseThreads(bvh, options));
  out.stats.sahCost = costs.sah;
  out.stats.nodeCost = dearer.nodeCost;
  out.stats.collapseCost = costs.collapse;
  out.stats.collapseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

double collapseCost(const Bvh4& bvh, const Bvh4Options& options) { return treeCosts(bvh, options, 1).collapse; }

double sahCost(const Bvh4& bvh) { return treeCosts(bvh, Bvh4Options{}, 1).sah; }

int bvh4StackEntries(const Bvh4Stats& stats) { return 3 * (stats.maxDepth + 1) + 1; }

LeafPacking packLeavesIntoBlocks(Bvh4& bvh, std::size_t primitives, std::size_t window) {
  constexpr std::uint32_t kB = kTriangleBlock;
  constexpr std::uint32_t kNone = 0xffffffffu;
  struct Leaf {
    std::uint32_t first = 0, count = 0, node = 0, slot = 0;
  };
  // The leaves in the order of their first primitive (the stream they are
  // packed from): the collapse keeps the binary tree's order in its slots,
  // so reading the slots depth first in order gives it; sorted otherwise.
  std::vector<Leaf> stream;
  stream.reserve(bvh.stats.leafCount);
  bool sorted = true;
  if (!bvh.nodes.empty()) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> slots{{0u, 0u}};  // (node, next slot)
    while (!slots.empty()) {
      auto& [n, k] = slots.back();
      if (k == 4) {
        slots.pop_back();
        continue;
      }
      const std::uint32_t node = n, slot = k++;
      const WtBvh4Node& w = bvh.nodes[node];
      if (w.count[slot] > 0) {
        sorted = sorted && (stream.empty() || stream.back().first < w.child[slot]);
        stream.push_back({w.child[slot], w.count[slot], node, slot});
      } else if (w.child[slot] != WT_BVH4_EMPTY) {
        slots.push_back({w.child[slot], 0u});
      }
    }
  }
  if (!sorted) std::sort(stream.begin(), stream.end(), [](const Leaf& a, const Leaf& b) { return a.first < b.first; });
  // each class (count % kB) as a queue of stream positions
  std::array<std::vector<std::uint32_t>, kB> queue;
  for (std::uint32_t i = 0; i < stream.size(); ++i) queue[stream[i].count % kB].push_back(i);
  std::array<std::size_t, kB> head{};
  std::vector<char> placed(stream.size(), 0);
  std::size_t front = 0;  // the first stream position not laid out yet

  LeafPacking packing;
  packing.order.resize(primitives);
  std::uint32_t* out = packing.order.data();
  std::size_t placedPrims = 0;
  // A leaf of `count` starting `offset` lanes into a block touches no more
  // blocks than its size needs.
  auto fits = [](std::uint32_t count, std::size_t offset) {
    return offset == 0 || (count % kB != 0 && offset + count % kB <= kB);
  };
  // the oldest leaf of class c not laid out, if it is at most `window`
  // positions behind the stream's front
  auto candidate = [&](std::uint32_t c) -> std::uint32_t {
    if (head[c] == queue[c].size() || queue[c][head[c]] > front + window) return kNone;
    return queue[c][head[c]];
  };
  auto emit = [&](std::uint32_t position) {
    const Leaf& leaf = stream[position];
    const std::uint32_t c = leaf.count % kB;
    // the class queue's head is the oldest of its class, which this is
    ++head[c];
    placed[position] = 1;
    while (front < stream.size() && placed[front]) ++front;
    if (leaf.count > primitives - placedPrims) throw std::logic_error("packLeavesIntoBlocks: leaves cover more than the primitives");
    if (!fits(leaf.count, placedPrims % kB)) ++packing.misfits;
    bvh.nodes[leaf.node].child[leaf.slot] = std::uint32_t(placedPrims);
    for (std::uint32_t i = 0; i < leaf.count; ++i) out[placedPrims + i] = leaf.first + i;
    placedPrims += leaf.count;
  };
  while (front < stream.size()) {
    const std::size_t offset = placedPrims % kB;
    if (offset == 0) {
      emit(std::uint32_t(front));  // a block starts with the oldest leaf left
      continue;
    }
    // the largest class that still fits the block (the exact one fills it)
    std::uint32_t pick = kNone;
    for (std::uint32_t c = std::uint32_t(kB - offset); c >= 1 && pick == kNone; --c) pick = candidate(c);
    if (pick == kNone) {
      // No leaf near enough fits: one goes that ends where a leaf near
      // enough can fill the block after it (at its start if possible).
      int best = 4;
      for (std::uint32_t c = 0; c < kB; ++c) {
        const std::uint32_t p = candidate(c);
        if (p == kNone) continue;
        const std::size_t end = (offset + c) % kB;
        const int score = end == 0 ? 0 : candidate(std::uint32_t(kB - end)) != kNone ? 1 : 2;
        if (score < best || (score == best && p < pick)) best = score, pick = p;
      }
    }
    emit(pick);
  }
  if (placedPrims != primitives) throw std::logic_error("packLeavesIntoBlocks: leaves cover fewer than the primitives");
  return packing;
}

void orderChildSlots(Bvh4& bvh) {
  for (WtBvh4Node& node : bvh.nodes) {
    // leaves rank above every area, empty slots below (stable: leaves keep their order)
    float rank[4];
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) {
        rank[k] = -1.0f;
      } else if (node.count[k] > 0) {
        rank[k] = std::numeric_limits<float>::infinity();
      } else {
        const float ex = node.hi_x[k] - node.lo_x[k], ey = node.hi_y[k] - node.lo_y[k], ez = node.hi_z[k] - node.lo_z[k];
        const float area = ex * ey + ey * ez + ez * ex;
        rank[k] = area == area ? std::min(area, std::numeric_limits<float>::max()) : 0.0f;  // NaN: after the others
      }
    }
    // a stable insertion sort, by rank descending (std::stable_sort spent its time
    // in buffer handling for four items)
    int slot[4] = {0, 1, 2, 3};
    for (int k = 1; k < 4; ++k)
      for (int j = k; j > 0 && rank[slot[j]] > rank[slot[j - 1]]; --j) std::swap(slot[j], slot[j - 1]);
    const WtBvh4Node old = node;
    for (int k = 0; k < 4; ++k) {
      const int j = slot[k];
      node.lo_x[k] = old.lo_x[j], node.hi_x[k] = old.hi_x[j];
      node.lo_y[k] = old.lo_y[j], node.hi_y[k] = old.hi_y[j];
      node.lo_z[k] = old.lo_z[j], node.hi_z[k] = old.hi_z[j];
      node.child[k] = old.child[j], node.count[k] = old.count[j];
    }
  }
}

}  // namespace wt
