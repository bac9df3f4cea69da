#include "bvh/bvh4.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <ranges>
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

class Collapse {
 public:
  Collapse(const Bvh& bvh, const Bvh4Options& options) : m_in(bvh.nodes), m_options(options) {}

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

    // children before parents: a flatten that lays children out after their
    // parent (every builder here) is walked backwards, any other in post-order
    bool childrenAfter = true;
    for (std::uint32_t i = 0; i < n && childrenAfter; ++i) childrenAfter = m_in[i].count > 0 || m_in[i].first > i;
    if (childrenAfter) {
      for (std::size_t i = n; i-- > 0;) evaluate(std::uint32_t(i));
    } else {
      for (std::uint32_t i : preorder() | std::views::reverse) evaluate(i);
    }

    out.nodes.reserve(n / 4 + 1);
    out.nodes.push_back(emptyNode());
    if (m_rootIsLeaf) {
      setSlot(out.nodes[0], 0, m_in[0], m_firstPrim[0], m_prims[0]);
      out.stats.leafCount = 1;
    } else {
      emit(out);
    }
    out.stats.nodeCount = out.nodes.size();
    return out;
  }

 private:
  struct Slot {
    std::uint32_t binary;
    bool leaf;
  };

  std::vector<std::uint32_t> preorder() const {
    std::vector<std::uint32_t> order, stack{0};
    order.reserve(m_in.size());
    while (!stack.empty()) {
      std::uint32_t i = stack.back();
      stack.pop_back();
      order.push_back(i);
      if (m_in[i].count == 0) stack.push_back(m_in[i].first + 1), stack.push_back(m_in[i].first);
    }
    return order;
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
      m_rootIsLeaf = true;  // read only for i = 0
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
    m_rootIsLeaf = asLeaf <= split[4];
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

  /// Lay the 4-wide nodes out depth first, so a node's first child sits right behind it.
  void emit(Bvh4& out) const {
    struct Task {
      std::uint32_t binary, node;
      int depth;
    };
    std::vector<Task> stack{{0, 0, 0}};
    std::vector<Slot> slots;
    while (!stack.empty()) {
      const Task task = stack.back();
      stack.pop_back();
      out.stats.maxDepth = std::max(out.stats.maxDepth, task.depth);
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
          setSlot(out.nodes[task.node], int(k), m_in[b], m_firstPrim[b], m_prims[b]);
          ++out.stats.leafCount;
        } else {
          const std::uint32_t index = std::uint32_t(out.nodes.size());
          out.nodes.push_back(emptyNode());
          setSlot(out.nodes[task.node], int(k), m_in[b], index, 0);
          pending[std::size_t(pendingCount++)] = {b, index, task.depth + 1};
        }
      }
      for (int k = pendingCount - 1; k >= 0; --k) stack.push_back(pending[std::size_t(k)]);
    }
  }

  const BvhNodes& m_in;
  Bvh4Options m_options;
  bool m_unitAreas = false;
  bool m_rootIsLeaf = false;
  float m_nodeCost = 0.0f;
  std::uint32_t m_maxLeaf = 1;
  std::vector<SubtreeCost, UninitialisedAllocator<SubtreeCost>> m_cost;
  std::vector<Decision> m_decision;
  std::vector<std::uint32_t, UninitialisedAllocator<std::uint32_t>> m_prims, m_firstPrim;
};

}  // namespace

Bvh4 collapseToBvh4(const Bvh& bvh, const Bvh4Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Bvh4 out = Collapse(bvh, options).run();
  // over the memory budget: nodes made dearer until the tree fits
  const double prims = double(bvh.primIndices.size());
  Bvh4Options dearer = options;
  for (int round = 0; round < Bvh4Options::kBudgetRounds && options.nodeBytesPerPrimitive > 0.0 &&
                      double(out.nodes.size() * sizeof(WtBvh4Node)) > options.nodeBytesPerPrimitive * prims;
       ++round) {
    dearer.nodeCost = std::max(2.0 * dearer.nodeCost, 1e-6);
    out = Collapse(bvh, dearer).run();
  }
  out.stats.sahCost = sahCost(out);
  out.stats.nodeCost = dearer.nodeCost;
  out.stats.collapseCost = collapseCost(out, dearer);
  out.stats.collapseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

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

}  // namespace

double collapseCost(const Bvh4& bvh, const Bvh4Options& options) {
  if (bvh.nodes.empty()) return 0.0;
  const double area = rootArea(bvh.nodes[0]);
  const bool unit = !(area > 0.0) || !std::isfinite(area);
  double cost = 1.0 + options.nodeCost;  // the root's test
  for (const WtBvh4Node& node : bvh.nodes)
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) continue;
      const double a = unit ? 1.0 : slotArea(node, k) / area;
      cost += node.count[k] > 0 ? a * options.leafCost * double((node.count[k] + 3) / 4) : a + options.nodeCost;
    }
  return cost;
}

double sahCost(const Bvh4& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  const double area = rootArea(bvh.nodes[0]);
  double cost = 0.0, weight = 1.0;  // the root's test
  for (const WtBvh4Node& node : bvh.nodes)
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) continue;
      const double w = node.count[k] > 0 ? double(node.count[k]) : 1.0;
      cost += w * slotArea(node, k);
      weight += w;
    }
  // degenerate roots (a point or a segment) give no ratio: count every test
  if (!(area > 0.0) || !std::isfinite(area) || !std::isfinite(cost)) return weight;
  return 1.0 + cost / area;
}

int bvh4StackEntries(const Bvh4Stats& stats) { return 3 * (stats.maxDepth + 1); }

}  // namespace wt
