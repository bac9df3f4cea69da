// Linear BVH build: 63-bit Morton codes of the centroids, a parallel LSD
// radix sort, the Karras 2012 hierarchy (every internal node finds its own
// range and split), subtrees of at most maxLeafSize primitives collapsed into
// one leaf, then a depth-first flatten with bottom-up boxes, both in parallel
// over subtrees.
#include "bvh/lbvh.h"

#include "bvh/parallel.h"
#include "core/log.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <system_error>
#include <thread>

namespace wt {
namespace {

using namespace bvh_detail;

using Clock = std::chrono::steady_clock;

constexpr int kMortonBitsPerAxis = 21;
constexpr int kKeyBits = 3 * kMortonBitsPerAxis;
// 11-bit digits: at most six passes over 63-bit keys. On two threads this measured faster
// than eight 8-bit passes and than five 13-bit ones, whose scatter keeps too many lines open.
constexpr int kRadixBits = 11;
constexpr std::uint32_t kRadixBuckets = 1u << kRadixBits;
constexpr std::uint32_t kRadixMask = kRadixBuckets - 1;
constexpr int kMaxRadixPasses = (kKeyBits + kRadixBits - 1) / kRadixBits;
// Below this many primitives per thread, starting a thread costs more than it saves.
constexpr std::size_t kMinPrimsPerThread = 16384;
constexpr int kMaxThreads = 64;
// Node and primitive indices are 32-bit and a tree has up to 2n - 1 nodes.
constexpr std::size_t kMaxPrims = std::size_t{1} << 31;
// Leaf starts are also counted per block of sorted positions, to size big subtrees quickly.
constexpr std::size_t kStartBlock = 4096;
// The flatten hands out subtrees of at most n / kFlattenTasks primitives; many more tasks
// than threads balance the load, and a task's nodes stay in the core's cache for its boxes.
constexpr std::size_t kFlattenTasks = 64;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- Morton codes ------------------------------------------------------------------

/// Bit k of the index moved to bit 3k, for every byte.
constexpr std::array<std::uint64_t, 256> kSpreadByte = [] {
  std::array<std::uint64_t, 256> table{};
  for (std::uint64_t v = 0; v < 256; ++v)
    for (int bit = 0; bit < 8; ++bit) table[v] |= ((v >> bit) & 1u) << (3 * bit);
  return table;
}();

/// Spread the low 21 bits of v so that bit k moves to bit 3k (table lookups measured
/// faster than the shift-and-mask sequence).
std::uint64_t expandBits21(std::uint32_t v) {
  return kSpreadByte[v & 0xffu] | kSpreadByte[(v >> 8) & 0xffu] << 24 | kSpreadByte[(v >> 16) & 0x1fu] << 48;
}

struct Centroid {
  float x, y, z;
  bool finite;
};

Centroid centroidOf(const Aabb& box) {
  // Halve before adding so that boxes near the float limit do not overflow.
  Centroid c{0.5f * box.lo.x + 0.5f * box.hi.x, 0.5f * box.lo.y + 0.5f * box.hi.y,
             0.5f * box.lo.z + 0.5f * box.hi.z, false};
  c.finite = std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
  return c;
}

struct CentroidBounds {
  float lo[3] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity(),
                 std::numeric_limits<float>::infinity()};
  float hi[3] = {-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                 -std::numeric_limits<float>::infinity()};
};

/// Centroid quantisation: q = (c - origin) * scale, clamped to 21 bits.
struct MortonFrame {
  double origin[3];
  double scale[3];  ///< 0 on an axis where every centroid has the same coordinate
};

std::uint32_t quantise(float c, double origin, double scale) {
  constexpr double kMaxCell = double((1u << kMortonBitsPerAxis) - 1);
  const double q = std::min((double(c) - origin) * scale, kMaxCell);
  return q > 0.0 ? static_cast<std::uint32_t>(q) : 0u;
}

std::uint64_t mortonCode(const Aabb& box, const MortonFrame& frame) {
  const Centroid c = centroidOf(box);
  // Non-finite centroids (NaN or infinite bounds) all share code 0.
  if (!c.finite) return 0;
  return expandBits21(quantise(c.x, frame.origin[0], frame.scale[0])) |
         expandBits21(quantise(c.y, frame.origin[1], frame.scale[1])) << 1 |
         expandBits21(quantise(c.z, frame.origin[2], frame.scale[2])) << 2;
}

struct KeyBits {
  std::uint64_t orBits = 0;                   ///< OR of all keys
  std::uint64_t andBits = ~std::uint64_t{0};  ///< AND of all keys
};

struct MortonKeys {
  std::unique_ptr<std::uint64_t[]> keys;  ///< in input order
  KeyBits bits;
};

MortonKeys computeMortonKeys(std::span<const Aabb> primBounds, int threads) {
  const std::size_t n = primBounds.size();
  MortonKeys result;
  result.keys = std::make_unique_for_overwrite<std::uint64_t[]>(n);
  std::array<PerThread<CentroidBounds>, kMaxThreads> chunkBounds{};
  std::array<PerThread<KeyBits>, kMaxThreads> chunkBits{};
  runTeam(threads, [&](int rank, int size, Barrier& barrier) {
    const Range chunk = chunkOf(n, size, rank);
    // A local copy stays in registers; the shared slot might alias primBounds.
    CentroidBounds bounds;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const Centroid c = centroidOf(primBounds[i]);
      if (!c.finite) continue;
      bounds.lo[0] = std::min(bounds.lo[0], c.x), bounds.hi[0] = std::max(bounds.hi[0], c.x);
      bounds.lo[1] = std::min(bounds.lo[1], c.y), bounds.hi[1] = std::max(bounds.hi[1], c.y);
      bounds.lo[2] = std::min(bounds.lo[2], c.z), bounds.hi[2] = std::max(bounds.hi[2], c.z);
    }
    chunkBounds[static_cast<std::size_t>(rank)].value = bounds;
    barrier.arriveAndWait();

    // Every rank merges the same finite values, so all derive the same frame.
    MortonFrame frame{};
    for (int axis = 0; axis < 3; ++axis) {
      float lo = std::numeric_limits<float>::infinity();
      float hi = -std::numeric_limits<float>::infinity();
      for (int r = 0; r < size; ++r) {
        lo = std::min(lo, chunkBounds[static_cast<std::size_t>(r)].value.lo[axis]);
        hi = std::max(hi, chunkBounds[static_cast<std::size_t>(r)].value.hi[axis]);
      }
      // Zero extent (all centroids equal, collinear, planar) or no finite centroid: one cell.
      const double extent = double(hi) - double(lo);
      frame.origin[axis] = extent > 0.0 ? double(lo) : 0.0;
      frame.scale[axis] = extent > 0.0 ? double(1u << kMortonBitsPerAxis) / extent : 0.0;
    }

    KeyBits bits;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint64_t key = mortonCode(primBounds[i], frame);
      result.keys[i] = key;
      bits.orBits |= key;
      bits.andBits &= key;
    }
    chunkBits[static_cast<std::size_t>(rank)].value = bits;
  });
  // Ranks a short team never ran keep the neutral OR 0 and AND ~0.
  for (const PerThread<KeyBits>& chunk : chunkBits) {
    result.bits.orBits |= chunk.value.orBits;
    result.bits.andBits &= chunk.value.andBits;
  }
  return result;
}

// ---- sort --------------------------------------------------------------------------

/// Digit positions of the LSD passes: a digit that is the same in every key is skipped.
struct RadixPlan {
  std::array<int, kMaxRadixPasses> shifts{};
  int passes = 0;
};

// The radix passes sort 64-bit items, a key's top 32 bits over the input
// index, by those 32 bits (three 11-bit digits instead of six over the whole
// key and its index in two arrays: half the passes, two thirds of the bytes
// per pass); the full keys are then gathered in that order and a sequential
// pass orders each run of equal top bits by the full key (insertion sort:
// runs are short, most have one key). The result is the full sort's, key for
// key and index for index.
constexpr int kFixupBits = kKeyBits - 32;

RadixPlan planRadixSort(std::uint64_t keysOr, std::uint64_t keysAnd) {
  RadixPlan plan;
  const std::uint64_t differ = (keysOr ^ keysAnd) >> kFixupBits;  // the items' top 32 bits
  for (int shift = 0; shift < 32; shift += kRadixBits)
    if ((differ >> shift) & kRadixMask) plan.shifts[plan.passes++] = 32 + shift;
  return plan;
}

/// LSD radix passes over items by the digits at plan.shifts; stable. Pass p
/// reads set p % 2 and writes the other.
void radixSortItems(int threads, std::size_t n, const RadixPlan& plan, std::uint64_t* items0,
                    std::uint64_t* items1) {
  std::vector<std::uint32_t> histograms(static_cast<std::size_t>(threads) * kRadixBuckets);
  runTeam(threads, [&](int rank, int size, Barrier& barrier) {
    const Range chunk = chunkOf(n, size, rank);
    std::uint32_t* histogram = histograms.data() + static_cast<std::size_t>(rank) * kRadixBuckets;
    std::vector<std::uint32_t> offsets(kRadixBuckets);
    for (int pass = 0; pass < plan.passes; ++pass) {
      const std::uint64_t* src = pass % 2 == 0 ? items0 : items1;
      std::uint64_t* dst = pass % 2 == 0 ? items1 : items0;
      const int shift = plan.shifts[static_cast<std::size_t>(pass)];
      std::fill(histogram, histogram + kRadixBuckets, 0u);
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) ++histogram[(src[i] >> shift) & kRadixMask];
      barrier.arriveAndWait();
      // A digit's slots follow all smaller digits, then the same digit of lower ranks.
      std::uint32_t running = 0;
      for (std::uint32_t digit = 0; digit < kRadixBuckets; ++digit) {
        std::uint32_t mine = running;
        for (int r = 0; r < size; ++r) {
          const std::uint32_t count = histograms[static_cast<std::size_t>(r) * kRadixBuckets + digit];
          if (r < rank) mine += count;
          running += count;
        }
        offsets[digit] = mine;
      }
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        const std::uint64_t item = src[i];
        dst[offsets[(item >> shift) & kRadixMask]++] = item;
      }
      // The next pass reads what every rank wrote and rewrites the histograms.
      barrier.arriveAndWait();
    }
  });
}

/// Orders every run of keys equal above the low kFixupBits by the full key,
/// keeping equal keys in index order (a stable insertion sort).
void sortRunsByLowBits(std::size_t n, std::uint64_t* keys, std::uint32_t* vals) {
  std::size_t i = 0;
  while (i < n) {
    const std::uint64_t top = keys[i] >> kFixupBits;
    std::size_t end = i + 1;
    while (end < n && (keys[end] >> kFixupBits) == top) ++end;
    if (end - i > 32) {
      // a long run (primitives crowded into one cell of the top bits): sort
      // (key, index) pairs, which within a run are in index order already
      std::vector<std::pair<std::uint64_t, std::uint32_t>> run(end - i);
      for (std::size_t j = i; j < end; ++j) run[j - i] = {keys[j], vals[j]};
      std::sort(run.begin(), run.end());
      for (std::size_t j = i; j < end; ++j) keys[j] = run[j - i].first, vals[j] = run[j - i].second;
      i = end;
      continue;
    }
    for (std::size_t j = i + 1; j < end; ++j) {
      const std::uint64_t key = keys[j];
      const std::uint32_t val = vals[j];
      std::size_t k = j;
      for (; k > i && keys[k - 1] > key; --k) {
        keys[k] = keys[k - 1];
        vals[k] = vals[k - 1];
      }
      keys[k] = key;
      vals[k] = val;
    }
    i = end;
  }
}

// ---- hierarchy ---------------------------------------------------------------------

/// Karras's delta: length of the common prefix of the keys augmented with their index,
/// or -1 when j is outside [0, n). Sorted keys are at most 63 bits, so any two distinct
/// keys give less than 64 and equal keys give 64 plus the common prefix of the indices.
int commonPrefix(const std::uint64_t* keys, std::int64_t n, std::int64_t i, std::int64_t j) {
  if (static_cast<std::uint64_t>(j) >= static_cast<std::uint64_t>(n)) return -1;
  const std::uint64_t diff = keys[i] ^ keys[j];
  if (diff != 0) return std::countl_zero(diff);
  return 64 + std::countl_zero(static_cast<std::uint32_t>(i ^ j));
}

/// The Karras tree reduced to what the flatten opens. Internal node i covers the sorted
/// range [min(i, j), max(i, j)] for some j; a left child is the internal node numbered by
/// the last position of its range, a right child the one numbered by its first.
struct Hierarchy {
  /// Last position of the left child of node i; written only where i covers more than
  /// maxLeaf primitives, the only nodes the collapsed tree keeps as internal nodes.
  std::unique_ptr<std::uint32_t[]> split;
  /// 1 where a leaf of the collapsed tree begins: position 0 and split + 1 of every kept node.
  std::unique_ptr<std::uint8_t[]> leafStart;
  std::vector<std::uint32_t> blockStarts;  ///< leafStart summed over blocks of kStartBlock positions
  std::size_t leafCount = 0;

  /// Leaves of the collapsed subtree of a kept node covering [first, last]. Its first
  /// position is marked: it is 0 or follows the split of a kept ancestor.
  std::size_t leavesIn(std::size_t first, std::size_t last) const {
    std::size_t count = 0;
    std::size_t k = first;
    const std::size_t end = last + 1;
    while (k < end && k % kStartBlock != 0) count += leafStart[k++];
    while (k + kStartBlock <= end) {
      count += blockStarts[k / kStartBlock];
      k += kStartBlock;
    }
    while (k < end) count += leafStart[k++];
    return count;
  }
};

Hierarchy buildHierarchy(const std::uint64_t* keys, std::size_t n, std::uint32_t maxLeaf, int threads) {
  Hierarchy tree;
  tree.split = std::make_unique_for_overwrite<std::uint32_t[]>(n - 1);
  tree.leafStart = std::make_unique_for_overwrite<std::uint8_t[]>(n);
  tree.blockStarts.resize((n + kStartBlock - 1) / kStartBlock);
  std::array<PerThread<std::size_t>, kMaxThreads> chunkKept{};
  const std::int64_t count = static_cast<std::int64_t>(n);
  runTeam(threads, [&](int rank, int size, Barrier& barrier) {
    const Range marks = chunkOf(n, size, rank);
    std::memset(tree.leafStart.get() + marks.begin, 0, marks.end - marks.begin);
    if (rank == 0) tree.leafStart[0] = 1;
    // Any rank may mark any position below.
    barrier.arriveAndWait();

    // Local copies: the byte stores below could alias anything reached through a reference.
    std::uint32_t* const split = tree.split.get();
    std::uint8_t* const leafStart = tree.leafStart.get();
    const std::uint64_t* const sorted = keys;
    const Range chunk = chunkOf(n - 1, size, rank);
    std::size_t kept = 0;
    for (std::int64_t i = static_cast<std::int64_t>(chunk.begin); i < static_cast<std::int64_t>(chunk.end); ++i) {
      // The range grows towards the neighbour sharing the longer prefix.
      const int prefixNext = commonPrefix(sorted, count, i, i + 1);
      const int prefixPrev = commonPrefix(sorted, count, i, i - 1);
      const std::int64_t dir = prefixNext > prefixPrev ? 1 : -1;
      const int prefixMin = std::min(prefixNext, prefixPrev);
      // Positions sharing more than prefixMin with i are exactly the range; a node of at most
      // maxLeaf primitives lies inside a leaf and needs neither its length nor its split.
      if (commonPrefix(sorted, count, i, i + static_cast<std::int64_t>(maxLeaf) * dir) <= prefixMin) continue;
      std::int64_t lengthMax = 2 * static_cast<std::int64_t>(maxLeaf);
      while (commonPrefix(sorted, count, i, i + lengthMax * dir) > prefixMin) lengthMax *= 2;
      std::int64_t length = 0;
      for (std::int64_t step = lengthMax / 2; step >= 1; step /= 2)
        if (commonPrefix(sorted, count, i, i + (length + step) * dir) > prefixMin) length += step;

      // Split where the prefix shared with i first shortens below the node's prefix.
      const std::int64_t j = i + length * dir;
      const int prefixNode = commonPrefix(sorted, count, i, j);
      std::int64_t offset = 0;
      std::int64_t step = length;
      do {
        step = (step + 1) / 2;
        if (commonPrefix(sorted, count, i, i + (offset + step) * dir) > prefixNode) offset += step;
      } while (step > 1);
      const std::int64_t gamma = i + offset * dir + std::min<std::int64_t>(dir, 0);
      split[i] = static_cast<std::uint32_t>(gamma);
      // Each boundary between sorted positions is split by exactly one node: no two ranks write one mark.
      leafStart[gamma + 1] = 1;
      ++kept;
    }
    chunkKept[static_cast<std::size_t>(rank)].value = kept;
    barrier.arriveAndWait();

    const Range blocks = chunkOf(tree.blockStarts.size(), size, rank);
    for (std::size_t b = blocks.begin; b < blocks.end; ++b) {
      const std::size_t end = std::min(n, (b + 1) * kStartBlock);
      std::uint32_t starts = 0;
      for (std::size_t k = b * kStartBlock; k < end; ++k) starts += tree.leafStart[k];
      tree.blockStarts[b] = starts;
    }
  });
  // A binary tree with k internal nodes has k + 1 leaves.
  tree.leafCount = 1;
  for (const PerThread<std::size_t>& kept : chunkKept) tree.leafCount += kept.value;
  return tree;
}

// ---- flatten and boxes -------------------------------------------------------------

void setBox(WtBvhNode& node, const Aabb& box) {
  node.lo_x = box.lo.x, node.lo_y = box.lo.y, node.lo_z = box.lo.z;
  node.hi_x = box.hi.x, node.hi_y = box.hi.y, node.hi_z = box.hi.z;
}

/// Union of boxes[0 .. leaf.count).
void setLeafBox(WtBvhNode& leaf, const Aabb* boxes) {
  setBox(leaf, boxes[0]);
  for (std::uint32_t k = 1; k < leaf.count; ++k) {
    const Aabb& box = boxes[k];
    leaf.lo_x = std::min(leaf.lo_x, box.lo.x), leaf.lo_y = std::min(leaf.lo_y, box.lo.y);
    leaf.lo_z = std::min(leaf.lo_z, box.lo.z);
    leaf.hi_x = std::max(leaf.hi_x, box.hi.x), leaf.hi_y = std::max(leaf.hi_y, box.hi.y);
    leaf.hi_z = std::max(leaf.hi_z, box.hi.z);
  }
}

void setUnionBox(WtBvhNode& node, const WtBvhNode& a, const WtBvhNode& b) {
  node.lo_x = std::min(a.lo_x, b.lo_x), node.lo_y = std::min(a.lo_y, b.lo_y), node.lo_z = std::min(a.lo_z, b.lo_z);
  node.hi_x = std::max(a.hi_x, b.hi_x), node.hi_y = std::max(a.hi_y, b.hi_y), node.hi_z = std::max(a.hi_z, b.hi_z);
}

double nodeArea(const WtBvhNode& node) {
  const double ex = double(node.hi_x) - double(node.lo_x);
  const double ey = double(node.hi_y) - double(node.lo_y);
  const double ez = double(node.hi_z) - double(node.lo_z);
  if (ex < 0.0 || ey < 0.0 || ez < 0.0) return 0.0;
  return 2.0 * (ex * ey + ey * ez + ez * ex);
}

/// Running sums for sahCost, so that partial trees can be summed apart and combined.
struct SahSums {
  double area = 0.0;       ///< sum of area * weight over nodes of finite area
  double nonFinite = 0.0;  ///< sum of weights of nodes whose area is infinite or NaN
  double weight = 0.0;     ///< sum of all weights (1 per internal node, count per leaf)

  void add(const WtBvhNode& node) {
    const double w = node.count > 0 ? double(node.count) : 1.0;
    const double a = nodeArea(node);
    if (std::isfinite(a))
      area += a * w;
    else
      nonFinite += w;
    weight += w;
  }
  void add(const SahSums& other) {
    area += other.area;
    nonFinite += other.nonFinite;
    weight += other.weight;
  }
  double cost(double rootArea) const {
    // A root of zero, infinite or NaN area (all primitives at a point or on a line) gives
    // no meaningful ratio; count every node as if its area were the root's.
    if (!(rootArea > 0.0) || !std::isfinite(rootArea)) return weight;
    return area / rootArea + nonFinite;
  }
};

/// A subtree the flatten hands to one thread whole.
struct SubtreeTask {
  std::uint32_t node;      ///< output index of its root, an internal node
  std::uint32_t first;     ///< sorted range of the root
  std::uint32_t last;
  std::uint32_t karras;    ///< Karras internal node of the root
  std::uint32_t children;  ///< output index of the root's child pair; descendants fill [children, end)
  std::uint32_t end;
  int depth;  ///< depth of the root
};

struct SubtreeResult {
  SahSums sah;
  int maxDepth = 0;
};

/// A node opened by the depth-first walk; the walk appends its children as a pair.
struct Pending {
  std::uint32_t node;
  std::uint32_t first;
  std::uint32_t last;
  std::uint32_t karras;
  int depth;
};

/// Give the opened node its child pair at `next`; hand leaf children to leaf() once
/// written, and internal ones to queue() (right first, so the left subtree is laid out next).
template <class Leaf, class Queue>
void openNode(const Pending& open, std::uint32_t next, const Hierarchy& tree, std::uint32_t maxLeaf,
              std::vector<WtBvhNode>& nodes, Leaf&& leaf, Queue&& queue) {
  const std::uint32_t gamma = tree.split[open.karras];
  const std::uint32_t leftSize = gamma - open.first + 1;
  const std::uint32_t rightSize = open.last - gamma;
  nodes[open.node].first = next;
  WtBvhNode& left = nodes[next];
  WtBvhNode& right = nodes[next + 1];
  if (leftSize <= maxLeaf) {
    left.first = open.first, left.count = leftSize;
    leaf(left);
  }
  if (rightSize <= maxLeaf) {
    right.first = gamma + 1, right.count = rightSize;
    leaf(right);
  }
  if (rightSize > maxLeaf) queue(Pending{next + 1, gamma + 1, open.last, gamma + 1, open.depth + 1});
  if (leftSize > maxLeaf) queue(Pending{next, open.first, gamma, gamma, open.depth + 1});
}

/// Copy the boxes of sorted positions [first, last] into `sorted`. The source order is the
/// input's, often random, so prefetching well ahead keeps many cache misses in flight.
void gatherBoxes(std::span<const Aabb> primBounds, const std::uint32_t* primIndices, std::uint32_t first,
                 std::uint32_t last, std::vector<Aabb>& sorted) {
  constexpr std::uint32_t kPrefetchDistance = 32;
  const std::uint32_t count = last - first + 1;
  sorted.resize(count);
  const std::uint32_t* indices = primIndices + first;
  for (std::uint32_t k = 0; k < count; ++k) {
    if (k + kPrefetchDistance < count) __builtin_prefetch(&primBounds[indices[k + kPrefetchDistance]]);
    sorted[k] = primBounds[indices[k]];
  }
}

/// Per-thread buffers of the flatten, reused across subtrees.
struct FlattenScratch {
  std::vector<Pending> stack;
  std::vector<std::uint32_t> opened;  ///< internal nodes in opening order
  std::vector<Aabb> sorted;           ///< primitive boxes of the subtree in sorted order
};

/// Lay out the subtree of `task` depth first from task.children, boxing leaves as they are
/// written; then box internal nodes in reverse opening order, which sees children first.
SubtreeResult flattenSubtree(const SubtreeTask& task, const Hierarchy& tree, std::uint32_t maxLeaf,
                             std::span<const Aabb> primBounds, const std::uint32_t* primIndices,
                             std::vector<WtBvhNode>& nodes, FlattenScratch& scratch) {
  SubtreeResult result;
  result.maxDepth = task.depth;
  gatherBoxes(primBounds, primIndices, task.first, task.last, scratch.sorted);
  const auto boxLeaf = [&](WtBvhNode& leaf) {
    setLeafBox(leaf, scratch.sorted.data() + (leaf.first - task.first));
    result.sah.add(leaf);
  };
  std::vector<Pending>& stack = scratch.stack;
  std::vector<std::uint32_t>& opened = scratch.opened;
  stack.clear();
  opened.clear();
  stack.push_back({task.node, task.first, task.last, task.karras, task.depth});
  std::uint32_t next = task.children;
  while (!stack.empty()) {
    const Pending open = stack.back();
    stack.pop_back();
    opened.push_back(open.node);
    openNode(open, next, tree, maxLeaf, nodes, boxLeaf, [&](const Pending& child) { stack.push_back(child); });
    next += 2;
    result.maxDepth = std::max(result.maxDepth, open.depth + 1);
  }
  assert(next == task.end && "subtree size disagrees with its leaf starts");
  for (auto it = opened.rbegin(); it != opened.rend(); ++it) {
    WtBvhNode& node = nodes[*it];
    setUnionBox(node, nodes[node.first], nodes[node.first + 1]);
    result.sah.add(node);
  }
  return result;
}

struct FlatTree {
  int maxDepth = 0;
  double sahCost = 0.0;
};

/// Depth-first layout: a node's children are appended as a pair when it is opened and the
/// left subtree is laid out next. The top of the tree is walked here; subtrees of at most
/// taskPrims primitives go to the threads, each given the slots the sequential walk would
/// reach them at: the subtree of a node with L leaves has 2L - 1 nodes.
FlatTree flattenTree(const Hierarchy& tree, std::size_t n, std::uint32_t maxLeaf, std::span<const Aabb> primBounds,
                     const std::uint32_t* primIndices, int threads, std::vector<WtBvhNode>& nodes) {
  FlatTree flat;
  nodes.resize(2 * tree.leafCount - 1);
  const std::size_t taskPrims = std::max<std::size_t>(n / kFlattenTasks, kMinPrimsPerThread / 4);

  // Walk the top; its sums come last, so the total does not depend on the thread count.
  SahSums topSah;
  std::vector<Aabb> leafBoxes;
  const auto boxLeaf = [&](WtBvhNode& leaf) {
    gatherBoxes(primBounds, primIndices, leaf.first, leaf.first + leaf.count - 1, leafBoxes);
    setLeafBox(leaf, leafBoxes.data());
    topSah.add(leaf);
  };
  std::vector<SubtreeTask> tasks;
  std::vector<std::uint32_t> opened;
  std::vector<Pending> stack{{0, 0, static_cast<std::uint32_t>(n - 1), 0, 0}};
  std::uint32_t next = 1;
  while (!stack.empty()) {
    const Pending open = stack.back();
    stack.pop_back();
    if (open.last - open.first + 1 <= taskPrims) {
      const std::uint32_t end = next + static_cast<std::uint32_t>(2 * tree.leavesIn(open.first, open.last) - 2);
      tasks.push_back({open.node, open.first, open.last, open.karras, next, end, open.depth});
      next = end;
      continue;
    }
    opened.push_back(open.node);
    openNode(open, next, tree, maxLeaf, nodes, boxLeaf, [&](const Pending& child) { stack.push_back(child); });
    next += 2;
    flat.maxDepth = std::max(flat.maxDepth, open.depth + 1);
  }
  assert(next == nodes.size() && "tree size disagrees with its leaf count");

  std::vector<SubtreeResult> results(tasks.size());
  std::atomic<std::size_t> nextTask{0};
  runTeam(threads, [&](int, int, Barrier&) {
    FlattenScratch scratch;
    for (std::size_t t = nextTask++; t < tasks.size(); t = nextTask++)
      results[t] = flattenSubtree(tasks[t], tree, maxLeaf, primBounds, primIndices, nodes, scratch);
  });

  SahSums sah;
  for (const SubtreeResult& result : results) {
    sah.add(result.sah);
    flat.maxDepth = std::max(flat.maxDepth, result.maxDepth);
  }
  // Children of a top node are leaves, subtree roots or top nodes opened after it.
  for (auto it = opened.rbegin(); it != opened.rend(); ++it) {
    WtBvhNode& node = nodes[*it];
    setUnionBox(node, nodes[node.first], nodes[node.first + 1]);
    topSah.add(node);
  }
  sah.add(topSah);
  flat.sahCost = sah.cost(nodeArea(nodes[0]));
  return flat;
}

/// Wall times of the phases of one build, for the log line.
struct PhaseTimes {
  double morton = 0, sort = 0, hierarchy = 0, flatten = 0;
};

/// Morton keys of the centroids sorted ascending, with primIndices[k] the input
/// index of the k-th; equal keys keep index order.
void sortKeysWithPlan(int threads, std::size_t n, const RadixPlan& plan, std::unique_ptr<std::uint64_t[]>& keys,
                      std::vector<std::uint32_t>& primIndices) {
  primIndices.resize(n);
  auto items0 = std::make_unique_for_overwrite<std::uint64_t[]>(n);
  auto items1 = std::make_unique_for_overwrite<std::uint64_t[]>(plan.passes > 0 ? n : 1);
  auto sorted = std::make_unique_for_overwrite<std::uint64_t[]>(n);
  std::uint64_t* result = plan.passes % 2 == 1 ? items1.get() : items0.get();
  runTeam(threads, [&](int rank, int size, Barrier&) {
    const Range chunk = chunkOf(n, size, rank);
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) items0[i] = (keys[i] >> kFixupBits) << 32 | i;
  });
  radixSortItems(threads, n, plan, items0.get(), items1.get());
  runTeam(threads, [&](int rank, int size, Barrier&) {
    const Range chunk = chunkOf(n, size, rank);
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint32_t index = static_cast<std::uint32_t>(result[i]);
      primIndices[i] = index;
      sorted[i] = keys[index];
    }
  });
  keys = std::move(sorted);
  // the runs, split between the threads at run boundaries
  const std::uint64_t* k = keys.get();
  runTeam(threads, [&](int rank, int size, Barrier&) {
    auto boundary = [&](std::size_t i) {
      while (i > 0 && i < n && (k[i] >> kFixupBits) == (k[i - 1] >> kFixupBits)) ++i;
      return std::min(i, n);
    };
    const Range chunk = chunkOf(n, size, rank);
    const std::size_t begin = boundary(chunk.begin), end = boundary(chunk.end);
    if (begin < end) sortRunsByLowBits(end - begin, keys.get() + begin, primIndices.data() + begin);
  });
}

std::unique_ptr<std::uint64_t[]> sortByMorton(std::span<const Aabb> primBounds, int threads,
                                             std::vector<std::uint32_t>& primIndices, PhaseTimes& times) {
  const std::size_t n = primBounds.size();
  Clock::time_point phase = Clock::now();
  MortonKeys morton = computeMortonKeys(primBounds, threads);
  times.morton = secondsSince(phase);

  // The pass count decides which buffers end up sorted; make that one primIndices.
  phase = Clock::now();
  const RadixPlan plan = planRadixSort(morton.bits.orBits, morton.bits.andBits);
  std::unique_ptr<std::uint64_t[]> keys = std::move(morton.keys);
  sortKeysWithPlan(threads, n, plan, keys, primIndices);
  times.sort = secondsSince(phase);
  return keys;
}

}  // namespace

namespace bvh_detail {

void sortKeysWithIndices(int threads, std::size_t n, std::unique_ptr<std::uint64_t[]>& keys,
                         std::vector<std::uint32_t>& primIndices) {
  std::uint64_t orBits = 0, andBits = ~std::uint64_t{0};
  for (std::size_t i = 0; i < n; ++i) orBits |= keys[i], andBits &= keys[i];
  sortKeysWithPlan(std::clamp(threads, 1, kMaxThreads), n, planRadixSort(orBits, andBits), keys, primIndices);
}

}  // namespace bvh_detail


namespace bvh_detail {

std::vector<std::uint32_t> mortonOrder(std::span<const Aabb> primBounds, int threads) {
  std::vector<std::uint32_t> order;
  PhaseTimes times;
  if (!primBounds.empty()) sortByMorton(primBounds, std::clamp(threads, 1, kMaxThreads), order, times);
  return order;
}

}  // namespace bvh_detail

Bvh buildLbvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options) {
  const Clock::time_point start = Clock::now();
  Bvh bvh;
  const std::size_t n = primBounds.size();
  if (n == 0) {
    bvh.stats.buildSeconds = secondsSince(start);
    return bvh;
  }
  if (n >= kMaxPrims) throw std::length_error("buildLbvh: too many primitives for 32-bit node indices");

  const std::uint32_t maxLeaf =
      static_cast<std::uint32_t>(std::clamp(options.maxLeafSize, 1, std::numeric_limits<int>::max()));
  int threads = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  threads = std::clamp(threads, 1, kMaxThreads);
  threads = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(threads), n / kMinPrimsPerThread + 1));
  PhaseTimes times;

  std::unique_ptr<std::uint64_t[]> keys = sortByMorton(primBounds, threads, bvh.primIndices, times);

  int maxDepth = 0;
  if (n <= maxLeaf) {
    WtBvhNode& root = bvh.nodes.emplace_back();
    root.first = 0;
    root.count = static_cast<std::uint32_t>(n);
    std::vector<Aabb> boxes;
    gatherBoxes(primBounds, bvh.primIndices.data(), 0, root.count - 1, boxes);
    setLeafBox(root, boxes.data());
    bvh.stats.leafCount = 1;
    bvh.stats.sahCost = sahCost(bvh);
  } else {
    Clock::time_point phase = Clock::now();
    const Hierarchy tree = buildHierarchy(keys.get(), n, maxLeaf, threads);
    keys.reset();
    times.hierarchy = secondsSince(phase);

    phase = Clock::now();
    const FlatTree flat = flattenTree(tree, n, maxLeaf, primBounds, bvh.primIndices.data(), threads, bvh.nodes);
    times.flatten = secondsSince(phase);
    maxDepth = flat.maxDepth;
    bvh.stats.leafCount = tree.leafCount;
    bvh.stats.sahCost = flat.sahCost;
  }
  bvh.stats.nodeCount = bvh.nodes.size();
  bvh.stats.maxDepth = maxDepth;
  bvh.stats.buildSeconds = secondsSince(start);

  char line[256];
  std::snprintf(line, sizeof line,
                "bvh: %zu primitives, %zu nodes, depth %d, SAH %.2f, %.1f ms on %d threads "
                "(morton %.1f, sort %.1f, hierarchy %.1f, flatten+bounds %.1f)",
                n, bvh.nodes.size(), maxDepth, bvh.stats.sahCost, 1e3 * bvh.stats.buildSeconds, threads,
                1e3 * times.morton, 1e3 * times.sort, 1e3 * times.hierarchy, 1e3 * times.flatten);
  log::debug(line);
  return bvh;
}

double sahCost(const Bvh& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  SahSums sah;
  for (const WtBvhNode& node : bvh.nodes) sah.add(node);
  return sah.cost(nodeArea(bvh.nodes[0]));
}

}  // namespace wt
