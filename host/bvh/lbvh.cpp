// Linear BVH build: 63-bit Morton codes of the centroids in cubic cells
// (per-axis cells too for small inputs, the lower SAH kept; in large inputs,
// regions that form one sheet keyed with their thin axis last), a parallel radix
// sort (one MSD pass, then buckets sorted alone in cache), the Karras 2012
// radix tree found top down (each node kept in the collapsed tree searches
// its split; subtrees of at most maxLeafSize primitives become one leaf
// unsplit), then a depth-first flatten with bottom-up boxes, both in
// parallel over subtrees.
#include "bvh/lbvh.h"

#include "bvh/build_tree.h"
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
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace wt {
namespace {

using namespace bvh_detail;

using Clock = std::chrono::steady_clock;

constexpr int kMortonBitsPerAxis = 21;
constexpr int kKeyBits = 3 * kMortonBitsPerAxis;
// 11-bit digits: 2048 buckets, whose scatter keeps few enough lines open (LSD passes over
// whole arrays measured faster with 11-bit digits than with 8 or 13 bits).
constexpr int kRadixBits = 11;
constexpr std::uint32_t kRadixBuckets = 1u << kRadixBits;
constexpr std::uint32_t kRadixMask = kRadixBuckets - 1;
constexpr std::size_t kMinPrimsPerThread = kMinItemsPerThread;
constexpr int kMaxThreads = kMaxBuildThreads;
// Up to this many primitives the LBVH is built with both cell shapes (Cells) and the
// tree of lower SAH kept.
constexpr std::size_t kBothCellsBelow = 65536;
// Node and primitive indices are 32-bit and a tree has up to 2n - 1 nodes.
constexpr std::size_t kMaxPrims = std::size_t{1} << 31;
// The flatten hands out subtrees of at most n / kFlattenTasks primitives (subtreePrims).
constexpr std::size_t kFlattenTasks = 64;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// ---- Morton codes ------------------------------------------------------------------

/// Bit k of the index moved to bit spacing * k, for every byte.
template <class T, int kSpacing>
constexpr std::array<T, 256> spreadByteTable() {
  std::array<T, 256> table{};
  for (T v = 0; v < 256; ++v)
    for (int bit = 0; bit < 8; ++bit) table[v] |= ((v >> bit) & 1u) << (kSpacing * bit);
  return table;
}

constexpr std::array<std::uint64_t, 256> kSpreadByte = spreadByteTable<std::uint64_t, 3>();

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

/// The Morton code of the box's centroid, its cells in q.
std::uint64_t mortonCells(const Aabb& box, const MortonFrame& frame, std::uint32_t q[3]) {
  const Centroid c = centroidOf(box);
  // Non-finite centroids (NaN or infinite bounds) all share cell 0 and code 0.
  if (!c.finite) {
    q[0] = q[1] = q[2] = 0;
    return 0;
  }
  q[0] = quantise(c.x, frame.origin[0], frame.scale[0]);
  q[1] = quantise(c.y, frame.origin[1], frame.scale[1]);
  q[2] = quantise(c.z, frame.origin[2], frame.scale[2]);
  return expandBits21(q[0]) | expandBits21(q[1]) << 1 | expandBits21(q[2]) << 2;
}

struct KeyBits {
  std::uint64_t orBits = 0;                   ///< OR of all keys
  std::uint64_t andBits = ~std::uint64_t{0};  ///< AND of all keys
};

struct MortonKeys {
  std::unique_ptr<std::uint64_t[]> keys;  ///< in input order
  KeyBits bits;
  std::size_t flatRegions = 0;  ///< regions keyed with an axis last (flat patches, below)
  std::size_t flatTested = 0;   ///< sample subtrees tried for that
  /// The candidate regions' key ranges [first, last], re-keyed or kept in Morton order.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> acceptedRanges, rejectedRanges;
};

// ---- flat patches ------------------------------------------------------------------
//
// The Morton order splits the three axes in turn. Where the primitives form one
// sheet over two axes (a terrain, a height field, a patch of a large smooth surface),
// a split across the third cuts the sheet along a contour line: a ridge's crest goes
// to one child and both its flanks to the other, whose box then holds the first's.
// A SAH build never splits so, and such splits are what the LBVH lost to the binned
// SAH tree on the bumpy grid (docs/lab/2026-12-01-performance-log.md, "Flat regions").
// So the key of a region whose primitives form
// such a sheet puts the bits of the region's shortest axis below the other two
// axes' bits: the region's subtree splits only the sheet's two axes, down to the
// primitives that share a cell in them.
//
// Which regions: a sample of the primitives, sorted by key, is cut into subtrees of
// at most kFlatRegionSamples; each is built both ways over its sampled boxes, and
// where the reordered tree is no dearer it becomes a candidate region (the range of
// keys sharing the subtree's prefix). A sample is too sparse to show what the
// reordering costs at the finest levels, where a closed object's front and back,
// now sorted together, would share every node (MetalRoughSpheres' rows of spheres
// pass the sample and are far dearer reordered), so the
// key pass keeps every primitive of one column of each candidate aside (all of it
// along the shortest axis, about kFlatWindowPrims primitives), and both trees are
// built again over that column at full density. Regions whose column tree costs
// kFlatCostRatio of the Morton one or less keep their reordered keys; the key pass
// wrote a candidate's keys reordered, and a second pass puts a rejected one's back
// (re-keying the accepted ones in a second pass instead was dearer:
// docs/lab/2026-12-04-performance-log.md, "Build, 2026-12-04 evening"). A region's keys keep its prefix, so the
// order of regions and of everything around them stays the Morton order.

// About this many primitives are sampled (every n / kFlatSamples-th, in input order).
constexpr std::size_t kFlatSamples = 16384;
// A region holds at most this many samples: 1/16 of the scene, the size of the subtrees
// where the bumpy grid's first splits across its height fall.
constexpr std::size_t kFlatRegionSamples = 1024;
// Sample subtrees smaller than this (the ends of an uneven split) are not tested.
constexpr std::size_t kFlatMinSamples = 64;
// A candidate's sampled tree, reordered, costs at most this much of the Morton one.
constexpr double kFlatSampleRatio = 1.0;
// A column holds about this many primitives, and is thinned to at most kFlatWindowMax.
constexpr std::size_t kFlatWindowPrims = 1024;
constexpr std::size_t kFlatWindowMax = 8192;
// A column of fewer primitives says too little: the region stays in Morton order.
constexpr std::size_t kFlatMinWindow = 64;
// A region is re-keyed when its column's reordered tree costs at most this much of its
// Morton tree: below it lie height fields' columns, above it closed objects' and
// random soups' (docs/lab/2026-12-01-performance-log.md, "Flat regions").
constexpr double kFlatCostRatio = 0.97;

/// A range of keys (those sharing the bits from lowBits up) whose low lowBits bits
/// are reordered: the other two axes' bits first, still interleaved in their order,
/// then `axis`'s bits; and the column of it whose primitives test that order.
struct FlatRegion {
  std::uint64_t first;
  std::uint64_t last;
  int axis;
  int low;                    ///< the lower of the other two axes (its bits come first in a level)
  int high;                   ///< the higher one
  int pairShift;              ///< where the other two axes' bits go: above axis's bits
  std::uint32_t cellMask[3];  ///< each axis's cell bits below lowBits
  // The column: the cells of `low` and `high` shifted right by columnShift[0] and [1]
  // are columnCell[0] and [1].
  int columnShift[2] = {0, 0};
  std::uint32_t columnCell[2] = {0, 0};
};

FlatRegion makeFlatRegion(std::uint64_t key, int lowBits, int axis) {
  FlatRegion region;
  const std::uint64_t lowMask = (std::uint64_t{1} << lowBits) - 1;
  region.first = key & ~lowMask;
  region.last = region.first | lowMask;
  region.axis = axis;
  region.low = axis == 0 ? 1 : 0;
  region.high = axis == 2 ? 1 : 2;
  // Axis k holds key bits 3i + k, so below lowBits it has (lowBits - k + 2) / 3 of them
  // (of the other two, the lower axis never has fewer).
  for (int k = 0; k < 3; ++k) region.cellMask[k] = (std::uint32_t{1} << (std::max(0, lowBits - k + 2) / 3)) - 1;
  region.pairShift = std::popcount(region.cellMask[axis]);
  return region;
}

constexpr std::array<std::uint32_t, 256> kSpreadByte2 = spreadByteTable<std::uint32_t, 2>();

/// The low 21 bits of v spread so that bit k moves to bit 2k.
std::uint64_t expandBits2(std::uint32_t v) {
  return std::uint64_t{kSpreadByte2[v & 0xffu]} | std::uint64_t{kSpreadByte2[(v >> 8) & 0xffu]} << 16 |
         std::uint64_t{kSpreadByte2[(v >> 16) & 0x1fu]} << 32;
}

/// The key of cells q[0..2] in the region, reordered (the prefix is the region's).
std::uint64_t keyWithAxisLast(const std::uint32_t q[3], const FlatRegion& region) {
  const std::uint64_t pair = expandBits2(q[region.low] & region.cellMask[region.low]) |
                             expandBits2(q[region.high] & region.cellMask[region.high]) << 1;
  return region.first | pair << region.pairShift | (q[region.axis] & region.cellMask[region.axis]);
}

bool inColumn(const std::uint32_t q[3], const FlatRegion& region) {
  return ((q[region.low] & region.cellMask[region.low]) >> region.columnShift[0]) == region.columnCell[0] &&
         ((q[region.high] & region.cellMask[region.high]) >> region.columnShift[1]) == region.columnCell[1];
}

/// The region (sorted, disjoint) holding `key`, or none; `last` is tried first.
const FlatRegion* regionOf(std::uint64_t key, std::span<const FlatRegion> regions, const FlatRegion*& last) {
  if (key >= last->first && key <= last->last) return last;
  const auto after = std::upper_bound(regions.begin(), regions.end(), key,
                                      [](std::uint64_t k, const FlatRegion& region) { return k < region.first; });
  if (after == regions.begin() || key > (after - 1)->last) return nullptr;
  last = &*(after - 1);
  return last;
}

/// SAH cost (in area units, not divided by the root's) of the radix tree over `count`
/// sorted keys with their boxes in the same order, one primitive to a leaf (the middle
/// splits a run of equal keys).
double radixTreeCost(const std::uint64_t* keys, const Aabb* boxes, std::size_t count, Aabb& box) {
  if (count == 1) {
    box = boxes[0];
    return double(box.surfaceArea());
  }
  const std::uint64_t diff = keys[0] ^ keys[count - 1];
  std::size_t half = count / 2;
  if (diff != 0) {
    const std::uint64_t bit = std::uint64_t{1} << (63 - std::countl_zero(diff));
    half = static_cast<std::size_t>(
        std::partition_point(keys, keys + count, [bit](std::uint64_t key) { return (key & bit) == 0; }) - keys);
  }
  Aabb right;
  const double cost =
      radixTreeCost(keys, boxes, half, box) + radixTreeCost(keys + half, boxes + half, count - half, right);
  box.extend(right);
  return cost + double(box.surfaceArea());
}

/// A primitive of a test: its Morton key, its key reordered, its cells, its box and,
/// in a column, the candidate region's index.
struct FlatPrim {
  std::uint64_t key;
  std::uint64_t reordered;
  std::uint32_t q[3];
  Aabb box;
  std::uint32_t region = 0;
};

/// The reordered tree's cost over the Morton tree's, for prims in Morton order
/// (their reordered keys set).
double reorderedCostRatio(std::span<const FlatPrim> prims) {
  const std::size_t count = prims.size();
  std::vector<std::uint64_t> keys(count);
  std::vector<Aabb> boxes(count);
  for (std::size_t i = 0; i < count; ++i) keys[i] = prims[i].key, boxes[i] = prims[i].box;
  Aabb box;
  const double mortonCost = radixTreeCost(keys.data(), boxes.data(), count, box);
  std::vector<std::uint32_t> order(count);
  for (std::uint32_t i = 0; i < count; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return prims[a].reordered < prims[b].reordered; });
  for (std::size_t i = 0; i < count; ++i) keys[i] = prims[order[i]].reordered, boxes[i] = prims[order[i]].box;
  return radixTreeCost(keys.data(), boxes.data(), count, box) / mortonCost;
}

/// The candidate for samples (sorted by key, a subtree sharing the key bits from
/// lowBits up, their reordered keys unset) that would be keyed with their shortest
/// axis last, or none; `regionPrims` is about how many primitives its range holds.
std::optional<FlatRegion> candidateRegion(std::span<FlatPrim> samples, int lowBits, std::size_t regionPrims) {
  std::uint32_t lo[3], hi[3];
  for (int axis = 0; axis < 3; ++axis) lo[axis] = std::numeric_limits<std::uint32_t>::max(), hi[axis] = 0;
  for (const FlatPrim& sample : samples)
    for (int axis = 0; axis < 3; ++axis)
      lo[axis] = std::min(lo[axis], sample.q[axis]), hi[axis] = std::max(hi[axis], sample.q[axis]);
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] < hi[axis] - lo[axis]) axis = k;

  FlatRegion region = makeFlatRegion(samples[0].key, lowBits, axis);
  for (FlatPrim& sample : samples) sample.reordered = keyWithAxisLast(sample.q, region);
  if (!(reorderedCostRatio(samples) <= kFlatSampleRatio)) return std::nullopt;

  // The column: 4^levels columns of the two other axes' cells hold about
  // kFlatWindowPrims each; the one of the middle sample in the reordered order.
  const int lowCells = std::popcount(region.cellMask[region.low]);
  const int highCells = std::popcount(region.cellMask[region.high]);
  int levels = 0;
  while (levels < highCells && (regionPrims >> (2 * levels)) > 2 * kFlatWindowPrims) ++levels;
  region.columnShift[0] = lowCells - levels;
  region.columnShift[1] = highCells - levels;
  std::vector<std::uint64_t> reordered(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) reordered[i] = samples[i].reordered;
  std::nth_element(reordered.begin(), reordered.begin() + static_cast<std::ptrdiff_t>(reordered.size() / 2),
                   reordered.end());
  const std::uint64_t middle = reordered[reordered.size() / 2];
  for (const FlatPrim& sample : samples)
    if (sample.reordered == middle) {
      region.columnCell[0] = (sample.q[region.low] & region.cellMask[region.low]) >> region.columnShift[0];
      region.columnCell[1] = (sample.q[region.high] & region.cellMask[region.high]) >> region.columnShift[1];
      break;
    }
  return region;
}

/// The candidate regions (sorted by key), from a sample of the primitives; `tested`
/// gets how many sample subtrees were tried.
std::vector<FlatRegion> findCandidateRegions(std::span<const Aabb> primBounds, const MortonFrame& frame,
                                             std::size_t& tested) {
  const std::size_t stride = std::max<std::size_t>(1, primBounds.size() / kFlatSamples);
  std::vector<FlatPrim> samples;
  samples.reserve(primBounds.size() / stride + 1);
  for (std::size_t i = 0; i < primBounds.size(); i += stride) {
    FlatPrim sample;
    sample.key = mortonCells(primBounds[i], frame, sample.q);
    sample.box = primBounds[i];
    // Boxes with a non-finite corner would make every cost infinite.
    if (std::isfinite(sample.box.surfaceArea())) samples.push_back(sample);
  }
  std::stable_sort(samples.begin(), samples.end(),
                   [](const FlatPrim& a, const FlatPrim& b) { return a.key < b.key; });

  std::vector<FlatRegion> regions;
  tested = 0;
  std::vector<Range> stack{{0, samples.size()}};
  while (!stack.empty()) {
    const Range range = stack.back();
    stack.pop_back();
    const std::size_t count = range.end - range.begin;
    if (count < kFlatMinSamples) continue;
    const std::uint64_t diff = samples[range.begin].key ^ samples[range.end - 1].key;
    if (diff == 0) continue;
    const int lowBits = 64 - std::countl_zero(diff);
    if (count <= kFlatRegionSamples) {
      ++tested;
      if (const auto region = candidateRegion(std::span(samples).subspan(range.begin, count), lowBits, count * stride))
        regions.push_back(*region);
      continue;
    }
    const std::uint64_t bit = std::uint64_t{1} << (lowBits - 1);
    const std::size_t split = static_cast<std::size_t>(
        std::partition_point(samples.begin() + static_cast<std::ptrdiff_t>(range.begin),
                             samples.begin() + static_cast<std::ptrdiff_t>(range.end),
                             [bit](const FlatPrim& s) { return (s.key & bit) == 0; }) -
        samples.begin());
    // Right first, so that the left subtree is tried next and the regions come out sorted.
    stack.push_back({split, range.end});
    stack.push_back({range.begin, split});
  }
  return regions;
}

/// Whether a candidate's column (its primitives in input order, as gathered) is
/// cheaper reordered.
bool columnIsFlat(std::vector<FlatPrim>& column) {
  if (column.size() > kFlatWindowMax) {
    // thinned by input position, so that the test does not depend on the thread count
    const std::size_t stride = (column.size() + kFlatWindowMax - 1) / kFlatWindowMax;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < column.size(); i += stride) column[kept++] = column[i];
    column.resize(kept);
  }
  if (column.size() < kFlatMinWindow) return false;
  std::stable_sort(column.begin(), column.end(), [](const FlatPrim& a, const FlatPrim& b) { return a.key < b.key; });
  return reorderedCostRatio(column) <= kFlatCostRatio;
}

/// How centroids are quantised: cells of one size on every axis (that of the longest
/// extent), or every axis scaled to its own extent.
enum class Cells { Cubic, PerAxis };

/// The keys in input order; with findFlat, those of flat patches reordered (above).
MortonKeys computeMortonKeys(std::span<const Aabb> primBounds, int threads, Cells cells, bool findFlat) {
  const std::size_t n = primBounds.size();
  MortonKeys result;
  result.keys = std::make_unique_for_overwrite<std::uint64_t[]>(n);
  std::array<PerThread<CentroidBounds>, kMaxThreads> chunkBounds{};
  std::array<PerThread<KeyBits>, kMaxThreads> chunkBits{};
  // the flat patches' candidate regions, their columns, and which are re-keyed
  std::vector<FlatRegion> candidates;
  std::array<PerThread<std::vector<FlatPrim>>, kMaxThreads> rankColumns{};
  // each rank's key bits in each candidate region, in Morton order and reordered
  struct RegionBits {
    std::vector<KeyBits> morton, reordered;
  };
  std::array<PerThread<RegionBits>, kMaxThreads> rankRegionBits{};
  std::vector<std::vector<FlatPrim>> columns;
  std::vector<char> accepted;
  std::atomic<std::size_t> nextColumn{0};
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
    double extent[3];
    for (int axis = 0; axis < 3; ++axis) {
      float lo = std::numeric_limits<float>::infinity();
      float hi = -std::numeric_limits<float>::infinity();
      for (int r = 0; r < size; ++r) {
        lo = std::min(lo, chunkBounds[static_cast<std::size_t>(r)].value.lo[axis]);
        hi = std::max(hi, chunkBounds[static_cast<std::size_t>(r)].value.hi[axis]);
      }
      // Zero extent (all centroids equal, collinear, planar) or no finite centroid: one cell.
      extent[axis] = double(hi) - double(lo);
      frame.origin[axis] = extent[axis] > 0.0 ? double(lo) : 0.0;
    }
    // Cubic cells: one scale for all axes, that of the longest. A short axis then
    // has only low bits that vary, so the radix tree splits it only once the cells
    // are as small as its extent (scaling every axis to 21 bits cut a flat mesh
    // across its thin axis near the root: docs/lab/2026-12-02-performance-log.md, "Build, 2026-12-02").
    const double longest = std::max({extent[0], extent[1], extent[2]});
    for (int axis = 0; axis < 3; ++axis)
      frame.scale[axis] = extent[axis] > 0.0
                              ? double(1u << kMortonBitsPerAxis) / (cells == Cells::Cubic ? longest : extent[axis])
                              : 0.0;

    if (findFlat) {
      if (rank == 0) {
        candidates = findCandidateRegions(primBounds, frame, result.flatTested);
        if (!candidates.empty()) {
          columns.resize(candidates.size());
          accepted.assign(candidates.size(), 0);
        }
      }
      barrier.arriveAndWait();
    }

    KeyBits bits;
    std::uint32_t q[3];
    if (candidates.empty()) {
      for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
        const std::uint64_t key = mortonCells(primBounds[i], frame, q);
        result.keys[i] = key;
        bits.orBits |= key;
        bits.andBits &= key;
      }
      chunkBits[static_cast<std::size_t>(rank)].value = bits;
      return;
    }

    // Keys, the reordered ones in every candidate region (most are accepted), and the
    // primitives of every candidate's column set aside with both keys (in input order:
    // the ranks' chunks are in order). The key bits are summed apart for each region,
    // both ways, so that only a rejected region's keys need a second pass. Neighbours
    // in input order are mostly neighbours in space: the last region is tried first.
    std::vector<FlatPrim>& mine = rankColumns[static_cast<std::size_t>(rank)].value;
    const std::span<const FlatRegion> regions(candidates);
    std::vector<KeyBits>& mortonBits = rankRegionBits[static_cast<std::size_t>(rank)].value.morton;
    std::vector<KeyBits>& reorderedBits = rankRegionBits[static_cast<std::size_t>(rank)].value.reordered;
    mortonBits.assign(regions.size(), KeyBits{});
    reorderedBits.assign(regions.size(), KeyBits{});
    std::uint64_t* const keys = result.keys.get();
    const FlatRegion* last = regions.data();
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint64_t key = mortonCells(primBounds[i], frame, q);
      const FlatRegion* region = regionOf(key, regions, last);
      if (!region) {
        keys[i] = key;
        bits.orBits |= key;
        bits.andBits &= key;
        continue;
      }
      const std::size_t r = static_cast<std::size_t>(region - regions.data());
      const std::uint64_t reordered = keyWithAxisLast(q, *region);
      if (inColumn(q, *region) && std::isfinite(primBounds[i].surfaceArea()))
        mine.push_back({key, reordered, {q[0], q[1], q[2]}, primBounds[i], static_cast<std::uint32_t>(r)});
      mortonBits[r].orBits |= key, mortonBits[r].andBits &= key;
      reorderedBits[r].orBits |= reordered, reorderedBits[r].andBits &= reordered;
      keys[i] = reordered;
    }
    barrier.arriveAndWait();
    if (rank == 0)
      for (int r = 0; r < size; ++r)
        for (const FlatPrim& prim : rankColumns[static_cast<std::size_t>(r)].value) columns[prim.region].push_back(prim);
    barrier.arriveAndWait();
    for (std::size_t c = nextColumn++; c < columns.size(); c = nextColumn++) accepted[c] = columnIsFlat(columns[c]);
    barrier.arriveAndWait();

    // This rank's key bits, each region's as it is keyed in the end.
    for (std::size_t r = 0; r < regions.size(); ++r) {
      const KeyBits& regionBits = accepted[r] ? reorderedBits[r] : mortonBits[r];
      bits.orBits |= regionBits.orBits;
      bits.andBits &= regionBits.andBits;
    }
    chunkBits[static_cast<std::size_t>(rank)].value = bits;
    // The rejected regions' keys back in Morton order. A reordered key keeps its
    // region's prefix, so it still finds its region.
    if (std::count(accepted.begin(), accepted.end(), 0) == 0) return;
    last = regions.data();
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const FlatRegion* region = regionOf(keys[i], regions, last);
      if (region && !accepted[static_cast<std::size_t>(region - regions.data())])
        keys[i] = mortonCells(primBounds[i], frame, q);
    }
  });
  result.flatRegions = static_cast<std::size_t>(std::count(accepted.begin(), accepted.end(), 1));
  for (std::size_t r = 0; r < candidates.size(); ++r)
    (accepted[r] ? result.acceptedRanges : result.rejectedRanges).emplace_back(candidates[r].first, candidates[r].last);
  // Ranks a short team never ran keep the neutral OR 0 and AND ~0.
  for (const PerThread<KeyBits>& chunk : chunkBits) {
    result.bits.orBits |= chunk.value.orBits;
    result.bits.andBits &= chunk.value.andBits;
  }
  return result;
}

// ---- sort --------------------------------------------------------------------------

// The sort orders 64-bit items, a key's top 32 bits over its input index, by
// value, which is the stable sort of the keys by their top 32 bits: one
// parallel MSD pass scatters the items into buckets by the most significant
// 11-bit digit that varies, then each bucket, which fits in a core's cache,
// is sorted alone (LSD passes over the digits below, insertion sort when
// small) and its full keys gathered in that order; a pass over the bucket
// then orders each run of equal top bits by the full key (insertion sort:
// runs are short, most have one key). The result is the full sort's, key for
// key and index for index.
constexpr int kFixupBits = kKeyBits - 32;
// Buckets of at most this many items are insertion-sorted instead of radix passes.
constexpr std::size_t kInsertionSortItems = 64;
// Buckets of more than this many items (or a quarter of one thread's share) are split
// again by the whole team before they are shared out (sortKeysWithPlan).
constexpr std::size_t kBigBucket = 65536;

/// The digits of the item sort, as bit positions within the items' top 32 bits.
struct RadixPlan {
  int msdShift = 0;  ///< the bucket digit: the highest 11-bit window holding a differing bit
  // below a bucket digit at bit 21 at most: two digits, of 11 and 10 bits
  std::array<int, 2> shifts{};  ///< the LSD digits below it that differ, lowest first
  std::array<int, 2> widths{};
  int passes = 0;
};

RadixPlan planRadixSort(std::uint64_t keysOr, std::uint64_t keysAnd) {
  RadixPlan plan;
  const std::uint32_t differ = static_cast<std::uint32_t>((keysOr ^ keysAnd) >> kFixupBits);
  const int topBit = differ != 0 ? 31 - std::countl_zero(differ) : 0;
  plan.msdShift = std::max(0, topBit + 1 - kRadixBits);
  for (int shift = 0; shift < plan.msdShift; shift += kRadixBits) {
    const int width = std::min(kRadixBits, plan.msdShift - shift);
    if ((differ >> shift) & ((1u << width) - 1)) {
      plan.shifts[static_cast<std::size_t>(plan.passes)] = shift;
      plan.widths[static_cast<std::size_t>(plan.passes++)] = width;
    }
  }
  return plan;
}

/// Sort the items of one bucket by value, which needs only the plan's lowest `passes`
/// digits (the bucket's items agree above them); returns where they ended, `items` or
/// `scratch`.
std::uint64_t* sortBucket(const RadixPlan& plan, int passes, std::uint64_t* items, std::uint64_t* scratch,
                          std::size_t count) {
  if (count <= kInsertionSortItems) {
    for (std::size_t j = 1; j < count; ++j) {
      const std::uint64_t item = items[j];
      std::size_t k = j;
      for (; k > 0 && items[k - 1] > item; --k) items[k] = items[k - 1];
      items[k] = item;
    }
    return items;
  }
  // Within a bucket the items are in index order (the bucket pass is stable), so stable
  // passes over the lower digits order them by value.
  std::array<std::uint32_t, kRadixBuckets> offsets;
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = 32 + plan.shifts[static_cast<std::size_t>(pass)];
    const std::uint32_t digits = 1u << plan.widths[static_cast<std::size_t>(pass)];
    const std::uint32_t mask = digits - 1;
    std::fill(offsets.begin(), offsets.begin() + digits, 0u);
    for (std::size_t i = 0; i < count; ++i) ++offsets[(items[i] >> shift) & mask];
    std::uint32_t running = 0;
    for (std::uint32_t d = 0; d < digits; ++d) running += std::exchange(offsets[d], running);
    for (std::size_t i = 0; i < count; ++i) scratch[offsets[(items[i] >> shift) & mask]++] = items[i];
    std::swap(items, scratch);
  }
  return items;
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

/// The split of the internal node covering sorted positions [first, last], first < last:
/// the last position of its left child, the last one sharing more than the node's prefix
/// with `first` (Karras's split search, from the node's first position).
std::uint32_t findSplit(const std::uint64_t* keys, std::int64_t n, std::int64_t first, std::int64_t last) {
  const int prefixNode = commonPrefix(keys, n, first, last);
  std::int64_t offset = 0;
  std::int64_t step = last - first;
  do {
    step = (step + 1) / 2;
    if (commonPrefix(keys, n, first, first + offset + step) > prefixNode) offset += step;
  } while (step > 1);
  return static_cast<std::uint32_t>(first + offset);
}

/// Below this many primitives the flatten hands a subtree to one thread whole; many more
/// subtrees than threads balance the load, and a subtree's nodes stay in the core's cache.
std::size_t subtreePrims(std::size_t n) { return std::max<std::size_t>(n / kFlattenTasks, kMinPrimsPerThread / 4); }

/// A subtree of at most subtreePrims primitives, and how many leaves the collapsed tree has there.
struct Subtree {
  std::uint32_t first;
  std::uint32_t last;
  std::uint32_t leaves;
};

/// The binary radix tree over the sorted keys (Karras 2012), reduced to what the flatten
/// opens: only nodes covering more than maxLeaf primitives, the internal nodes of the
/// collapsed tree, are split. Internal node ids follow Karras: the root is 0, a left child
/// is numbered by the last position of its range, a right child by its first.
struct Hierarchy {
  /// Last position of the left child of internal node id; written for kept nodes only.
  std::unique_ptr<std::uint32_t[]> split;
  /// The subtrees the flatten gives to threads, in its depth-first order (left first).
  std::vector<Subtree> subtrees;
  std::size_t leafCount = 0;
};

/// A node of the radix tree: its sorted range and its id.
struct RadixNode {
  std::uint32_t first;
  std::uint32_t last;
  std::uint32_t id;
};

/// Split `node` and hand each child to leaf() (at most maxLeaf primitives) or inner(),
/// right first, so that a stack opens the left subtree next.
template <class Leaf, class Inner>
void splitNode(const RadixNode& node, const std::uint64_t* keys, std::int64_t n, std::uint32_t maxLeaf,
               std::uint32_t* split, Leaf&& leaf, Inner&& inner) {
  const std::uint32_t gamma = findSplit(keys, n, node.first, node.last);
  split[node.id] = gamma;
  if (node.last - gamma > maxLeaf)
    inner(RadixNode{gamma + 1, node.last, gamma + 1});
  else
    leaf();
  if (gamma - node.first + 1 > maxLeaf)
    inner(RadixNode{node.first, gamma, gamma});
  else
    leaf();
}

// Top down from the root, so only the kept nodes are searched (about one position in
// four to eight with leaves of four to eight): the top sequentially down to subtrees of
// at most subtreePrims primitives, the subtrees in parallel. The tree is the one every
// internal node would find bottom up by its own range search.
Hierarchy buildHierarchy(const std::uint64_t* keys, std::size_t n, std::uint32_t maxLeaf, int threads) {
  Hierarchy tree;
  tree.split = std::make_unique_for_overwrite<std::uint32_t[]>(n - 1);
  const std::int64_t count = static_cast<std::int64_t>(n);
  const std::size_t taskPrims = subtreePrims(n);
  std::uint32_t* const split = tree.split.get();

  std::size_t topLeaves = 0;
  std::vector<RadixNode> stack{{0, static_cast<std::uint32_t>(n - 1), 0}};
  std::vector<RadixNode> roots;
  while (!stack.empty()) {
    const RadixNode node = stack.back();
    stack.pop_back();
    if (node.last - node.first + 1 <= taskPrims) {
      roots.push_back(node);
      continue;
    }
    splitNode(node, keys, count, maxLeaf, split, [&] { ++topLeaves; },
              [&](const RadixNode& child) { stack.push_back(child); });
  }

  tree.subtrees.resize(roots.size());
  std::atomic<std::size_t> nextRoot{0};
  runTeam(threads, [&](int, int, Barrier&) {
    std::vector<RadixNode> pending;
    for (std::size_t r = nextRoot++; r < roots.size(); r = nextRoot++) {
      std::uint32_t leaves = 0;
      pending.assign(1, roots[r]);
      while (!pending.empty()) {
        const RadixNode node = pending.back();
        pending.pop_back();
        splitNode(node, keys, count, maxLeaf, split, [&] { ++leaves; },
                  [&](const RadixNode& child) { pending.push_back(child); });
      }
      tree.subtrees[r] = {roots[r].first, roots[r].last, leaves};
    }
  });
  tree.leafCount = topLeaves;
  for (const Subtree& subtree : tree.subtrees) tree.leafCount += subtree.leaves;
  return tree;
}

// ---- flatten and boxes -------------------------------------------------------------

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
              BvhNodes& nodes, Leaf&& leaf, Queue&& queue) {
  const std::uint32_t gamma = tree.split[open.karras];
  const std::uint32_t leftSize = gamma - open.first + 1;
  const std::uint32_t rightSize = open.last - gamma;
  nodes[open.node].first = next;
  nodes[open.node].count = 0;  // the nodes array is not zeroed (UninitialisedAllocator)
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
                             BvhNodes& nodes, FlattenScratch& scratch) {
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
                     const std::uint32_t* primIndices, int threads, BvhNodes& nodes) {
  FlatTree flat;
  nodes.resize(2 * tree.leafCount - 1);
  const std::size_t taskPrims = subtreePrims(n);

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
      // the same depth-first order as buildHierarchy's walk, so its subtrees come in turn
      const Subtree& subtree = tree.subtrees[tasks.size()];
      assert(subtree.first == open.first && subtree.last == open.last);
      const std::uint32_t end = next + 2 * subtree.leaves - 2;
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

/// Wall times of the phases of one build, and the flat patches found, for the log line.
struct PhaseTimes {
  double morton = 0, sort = 0, hierarchy = 0, flatten = 0;
  std::size_t flatRegions = 0, flatTested = 0;
};

/// The slots of a stable team-wide counting pass: offsets[d] is where this rank's
/// first item of digit d goes (after all smaller digits, then the same digit of lower
/// ranks); rank 0 also writes each digit's first slot to starts[d] and the total to
/// starts[digits].
void teamOffsets(const std::vector<std::uint32_t>& histograms, int rank, int size, std::uint32_t digits,
                 std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& starts) {
  std::uint32_t running = 0;
  for (std::uint32_t digit = 0; digit < digits; ++digit) {
    if (rank == 0) starts[digit] = running;
    std::uint32_t mine = running;
    for (int r = 0; r < size; ++r) {
      const std::uint32_t count = histograms[static_cast<std::size_t>(r) * kRadixBuckets + digit];
      if (r < rank) mine += count;
      running += count;
    }
    offsets[digit] = mine;
  }
  if (rank == 0) starts[digits] = running;
}

/// A range of items that agree above the plan's lowest `passes` digits.
struct Bucket {
  std::uint32_t begin;
  std::uint32_t count;
  int passes;
};

/// Morton keys of the centroids sorted ascending, with primIndices[k] the input
/// index of the k-th (n entries); equal keys keep index order.
void sortKeysWithPlan(int threads, std::size_t n, const RadixPlan& plan, std::unique_ptr<std::uint64_t[]>& keys,
                      std::uint32_t* primIndices) {
  // The keys' low kFixupBits bits, which the items leave out: the keys' array then
  // holds the items, each written where its key was read, and is the sort's scratch
  // (a third array would cost more, mostly in faulting the fresh memory in).
  auto lowBits = std::make_unique_for_overwrite<std::uint32_t[]>(n);
  constexpr std::uint64_t kLowMask = (std::uint64_t{1} << kFixupBits) - 1;
  std::uint64_t* const items0 = keys.get();
  // items1 ends up holding the sorted full keys
  auto items1 = std::make_unique_for_overwrite<std::uint64_t[]>(n);
  std::vector<std::uint32_t> histograms(static_cast<std::size_t>(threads) * kRadixBuckets);
  std::vector<std::uint32_t> starts(kRadixBuckets + 1);
  std::vector<Bucket> buckets;
  std::atomic<std::size_t> nextBucket{0};
  // A bucket bigger than this is split again by the team before the buckets are shared
  // out: one core sorting a cluster that holds most of the scene (a far outlier
  // shrinks the rest into one cell of the first digit) would leave the other cores idle.
  const std::size_t bigBucket = std::max(kBigBucket, n / (4 * static_cast<std::size_t>(threads)));
  const int msdShift = 32 + plan.msdShift;
  runTeam(threads, [&](int rank, int size, Barrier& barrier) {
    const Range chunk = chunkOf(n, size, rank);
    std::uint32_t* histogram = histograms.data() + static_cast<std::size_t>(rank) * kRadixBuckets;
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint64_t key = keys[i];
      lowBits[i] = static_cast<std::uint32_t>(key & kLowMask);
      const std::uint64_t item = (key >> kFixupBits) << 32 | i;
      items0[i] = item;
      ++histogram[(item >> msdShift) & kRadixMask];
    }
    barrier.arriveAndWait();
    std::vector<std::uint32_t> offsets(kRadixBuckets);
    teamOffsets(histograms, rank, size, kRadixBuckets, offsets, starts);
    for (std::size_t i = chunk.begin; i < chunk.end; ++i) {
      const std::uint64_t item = items0[i];
      items1[offsets[(item >> msdShift) & kRadixMask]++] = item;
    }
    // The buckets hold what every rank scattered.
    barrier.arriveAndWait();
    if (rank == 0)
      for (std::uint32_t d = 0; d < kRadixBuckets; ++d)
        if (starts[d + 1] > starts[d]) buckets.push_back({starts[d], starts[d + 1] - starts[d], plan.passes});
    barrier.arriveAndWait();

    // Big buckets, split by the team on their highest digit left. Every rank walks the
    // same list: rank 0 changes it only while the others wait at the last barrier.
    for (std::size_t k = 0; k < buckets.size(); ++k) {
      const Bucket big = buckets[k];
      if (big.count <= bigBucket || big.passes == 0) continue;
      const std::size_t pass = static_cast<std::size_t>(big.passes - 1);
      const int shift = 32 + plan.shifts[pass];
      const std::uint32_t digits = 1u << plan.widths[pass], mask = digits - 1;
      std::uint64_t* items = items1.get() + big.begin;
      std::uint64_t* scratch = items0 + big.begin;
      const Range part = chunkOf(big.count, size, rank);
      std::fill(histogram, histogram + digits, 0u);
      for (std::size_t i = part.begin; i < part.end; ++i) ++histogram[(items[i] >> shift) & mask];
      barrier.arriveAndWait();
      teamOffsets(histograms, rank, size, digits, offsets, starts);
      for (std::size_t i = part.begin; i < part.end; ++i) scratch[offsets[(items[i] >> shift) & mask]++] = items[i];
      barrier.arriveAndWait();
      std::copy(scratch + part.begin, scratch + part.end, items + part.begin);
      if (rank == 0) {
        buckets[k].count = 0;
        for (std::uint32_t d = 0; d < digits; ++d)
          if (starts[d + 1] > starts[d])
            buckets.push_back({big.begin + starts[d], starts[d + 1] - starts[d], big.passes - 1});
      }
      barrier.arriveAndWait();
    }

    for (std::size_t b = nextBucket++; b < buckets.size(); b = nextBucket++) {
      const Bucket bucket = buckets[b];
      if (bucket.count == 0) continue;
      const std::size_t begin = bucket.begin, count = bucket.count;
      const std::uint64_t* items =
          sortBucket(plan, bucket.passes, items1.get() + begin, items0 + begin, count);
      // Each item's full key replaces it in items1 (in place when the items ended there).
      std::uint64_t* sorted = items1.get() + begin;
      for (std::size_t k = 0; k < count; ++k) {
        const std::uint64_t item = items[k];
        const std::uint32_t index = static_cast<std::uint32_t>(item);
        primIndices[begin + k] = index;
        sorted[k] = (item >> 32) << kFixupBits | lowBits[index];
      }
      // Runs of equal top bits never cross buckets.
      sortRunsByLowBits(count, sorted, primIndices + begin);
    }
  });
  keys = std::move(items1);
}

template <class Indices>
std::unique_ptr<std::uint64_t[]> sortByMorton(std::span<const Aabb> primBounds, int threads, Cells cells,
                                             bool findFlat, Indices& primIndices, PhaseTimes& times) {
  const std::size_t n = primBounds.size();
  Clock::time_point phase = Clock::now();
  MortonKeys morton = computeMortonKeys(primBounds, threads, cells, findFlat);
  times.morton = secondsSince(phase);
  times.flatRegions = morton.flatRegions;
  times.flatTested = morton.flatTested;

  phase = Clock::now();
  const RadixPlan plan = planRadixSort(morton.bits.orBits, morton.bits.andBits);
  std::unique_ptr<std::uint64_t[]> keys = std::move(morton.keys);
  primIndices.resize(n);
  sortKeysWithPlan(threads, n, plan, keys, primIndices.data());
  times.sort = secondsSince(phase);
  return keys;
}

}  // namespace

namespace bvh_detail {

void sortKeysWithIndices(int threads, std::size_t n, std::unique_ptr<std::uint64_t[]>& keys,
                         std::vector<std::uint32_t>& primIndices) {
  std::uint64_t orBits = 0, andBits = ~std::uint64_t{0};
  for (std::size_t i = 0; i < n; ++i) orBits |= keys[i], andBits &= keys[i];
  primIndices.resize(n);
  sortKeysWithPlan(std::clamp(threads, 1, kMaxThreads), n, planRadixSort(orBits, andBits), keys, primIndices.data());
}

}  // namespace bvh_detail


namespace bvh_detail {

FlatPatchKeys flatPatchKeys(std::span<const Aabb> primBounds, int threads) {
  const std::size_t n = primBounds.size();
  threads = std::clamp(threads, 1, kMaxThreads);
  FlatPatchKeys result;
  const MortonKeys plain = computeMortonKeys(primBounds, threads, Cells::Cubic, false);
  MortonKeys flat = computeMortonKeys(primBounds, threads, Cells::Cubic, true);
  result.morton.assign(plain.keys.get(), plain.keys.get() + n);
  result.keys.assign(flat.keys.get(), flat.keys.get() + n);
  result.accepted = std::move(flat.acceptedRanges);
  result.rejected = std::move(flat.rejectedRanges);
  return result;
}

std::vector<std::uint32_t> mortonOrder(std::span<const Aabb> primBounds, int threads) {
  std::vector<std::uint32_t> order;
  PhaseTimes times;
  if (!primBounds.empty()) sortByMorton(primBounds, std::clamp(threads, 1, kMaxThreads), Cells::Cubic, false, order, times);
  return order;
}

}  // namespace bvh_detail

namespace {

/// The LBVH over primBounds (1 to kMaxPrims - 1 of them) with centroids quantised in `cells`.
Bvh buildWithCells(std::span<const Aabb> primBounds, const BvhBuildOptions& options, Cells cells) {
  const Clock::time_point start = Clock::now();
  Bvh bvh;
  const std::size_t n = primBounds.size();

  const std::uint32_t maxLeaf =
      static_cast<std::uint32_t>(std::clamp(options.maxLeafSize, 1, std::numeric_limits<int>::max()));
  const int threads = teamThreads(options.threads, n);
  PhaseTimes times;

  // Large inputs are built one way only, so flat patches are looked for there.
  const bool findFlat = cells == Cells::Cubic && n > kBothCellsBelow;
  std::unique_ptr<std::uint64_t[]> keys = sortByMorton(primBounds, threads, cells, findFlat, bvh.primIndices, times);

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
  bvh.stats.flatRegions = times.flatRegions;
  bvh.stats.buildSeconds = secondsSince(start);

  char line[320];
  std::snprintf(line, sizeof line,
                "bvh: %zu primitives, %zu nodes, depth %d, SAH %.2f, %.1f ms on %d threads, %s cells, "
                "%zu of %zu sampled regions flat (morton %.1f, sort %.1f, hierarchy %.1f, flatten+bounds %.1f)",
                n, bvh.nodes.size(), maxDepth, bvh.stats.sahCost, 1e3 * bvh.stats.buildSeconds, threads,
                cells == Cells::Cubic ? "cubic" : "per-axis", times.flatRegions, times.flatTested,
                1e3 * times.morton, 1e3 * times.sort, 1e3 * times.hierarchy, 1e3 * times.flatten);
  log::debug(line);
  return bvh;
}

}  // namespace

Bvh buildLbvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options) {
  const Clock::time_point start = Clock::now();
  const std::size_t n = primBounds.size();
  if (n == 0) return Bvh{};
  if (n >= kMaxPrims) throw std::length_error("buildLbvh: too many primitives for 32-bit node indices");
  Bvh bvh = buildWithCells(primBounds, options, Cells::Cubic);
  // Cubic cells give the lower 4-wide SAH on most scenes but not all (the Cornell
  // box among them: docs/lab/2026-12-02-performance-log.md, "Build, 2026-12-02");
  // small trees are cheap enough to build both ways and keep the better.
  if (n <= kBothCellsBelow) {
    Bvh perAxis = buildWithCells(primBounds, options, Cells::PerAxis);
    if (perAxis.stats.sahCost < bvh.stats.sahCost) bvh = std::move(perAxis);
  }
  bvh.stats.buildSeconds = secondsSince(start);
  return bvh;
}

double sahCost(const Bvh& bvh) {
  if (bvh.nodes.empty()) return 0.0;
  SahSums sah;
  for (const WtBvhNode& node : bvh.nodes) sah.add(node);
  return sah.cost(nodeArea(bvh.nodes[0]));
}

}  // namespace wt
