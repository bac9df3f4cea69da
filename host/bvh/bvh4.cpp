#include "bvh/bvh4.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

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

}  // namespace

Bvh4 collapseToBvh4(const Bvh& bvh) {
  auto start = std::chrono::steady_clock::now();
  Bvh4 out;
  const BvhNodes& in = bvh.nodes;
  if (in.empty()) return out;
  out.nodes.reserve(in.size() / 2 + 1);
  out.nodes.push_back(emptyNode());
  if (in[0].count > 0) {
    // the whole tree is one leaf
    setSlot(out.nodes[0], 0, in[0], in[0].first, in[0].count);
    out.stats.leafCount = 1;
  } else {
    // depth-first, so a node's children sit close behind it
    struct Task {
      std::uint32_t binary, node;
      int depth;
    };
    std::vector<Task> stack{{0, 0, 0}};
    while (!stack.empty()) {
      Task task = stack.back();
      stack.pop_back();
      out.stats.maxDepth = std::max(out.stats.maxDepth, task.depth);
      // open the largest inner child until there are four
      std::array<std::uint32_t, 4> kids{in[task.binary].first, in[task.binary].first + 1, 0, 0};
      int n = 2;
      while (n < 4) {
        int best = -1;
        double bestArea = -1.0;
        for (int k = 0; k < n; ++k)
          if (in[kids[k]].count == 0 && binaryArea(in[kids[k]]) > bestArea) best = k, bestArea = binaryArea(in[kids[k]]);
        if (best < 0) break;
        std::uint32_t opened = kids[best];
        kids[best] = in[opened].first;
        kids[n++] = in[opened].first + 1;
      }
      // inner children get their slots now (adjacent), their contents later
      std::array<Task, 4> pending;
      int pendingCount = 0;
      for (int k = 0; k < n; ++k) {
        const WtBvhNode& kid = in[kids[k]];
        if (kid.count > 0) {
          setSlot(out.nodes[task.node], k, kid, kid.first, kid.count);
          ++out.stats.leafCount;
        } else {
          std::uint32_t index = std::uint32_t(out.nodes.size());
          out.nodes.push_back(emptyNode());
          setSlot(out.nodes[task.node], k, kid, index, 0);
          pending[pendingCount++] = {kids[k], index, task.depth + 1};
        }
      }
      // the first child is laid out next
      for (int k = pendingCount - 1; k >= 0; --k) stack.push_back(pending[k]);
    }
  }
  out.stats.nodeCount = out.nodes.size();
  out.stats.sahCost = sahCost(out);
  out.stats.collapseSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

double sahCost(const Bvh4& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  // the root's box is the union of its children's
  const WtBvh4Node& root = bvh.nodes[0];
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (int k = 0; k < 4; ++k) {
    if (root.child[k] == WT_BVH4_EMPTY) continue;
    lo[0] = std::min(lo[0], root.lo_x[k]), lo[1] = std::min(lo[1], root.lo_y[k]), lo[2] = std::min(lo[2], root.lo_z[k]);
    hi[0] = std::max(hi[0], root.hi_x[k]), hi[1] = std::max(hi[1], root.hi_y[k]), hi[2] = std::max(hi[2], root.hi_z[k]);
  }
  const double rootArea = boxArea(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  double cost = 0.0, weight = 1.0;  // the root's test
  for (const WtBvh4Node& node : bvh.nodes)
    for (int k = 0; k < 4; ++k) {
      if (node.child[k] == WT_BVH4_EMPTY) continue;
      const double w = node.count[k] > 0 ? double(node.count[k]) : 1.0;
      cost += w * boxArea(node.lo_x[k], node.lo_y[k], node.lo_z[k], node.hi_x[k], node.hi_y[k], node.hi_z[k]);
      weight += w;
    }
  // degenerate roots (a point or a segment) give no ratio: count every test
  if (!(rootArea > 0.0) || !std::isfinite(rootArea) || !std::isfinite(cost)) return weight;
  return 1.0 + cost / rootArea;
}

int bvh4StackEntries(const Bvh4Stats& stats) { return 3 * (stats.maxDepth + 1); }

}  // namespace wt
