// The BVH builders beside buildLbvh, all giving the same Bvh layout (so the
// 4-wide collapse and the kernels take any of them), and the dispatch on
// BvhBuildOptions::builder.
#pragma once

#include "bvh/lbvh.h"

#include <optional>
#include <ostream>
#include <span>
#include <string_view>

namespace wt {

/// Top-down binned SAH (32 bins per axis, all three axes, one unit per node
/// visit and per primitive test); a node becomes a leaf at maxLeafSize
/// primitives or fewer, as in buildLbvh. Slow; the quality yardstick.
Bvh buildSahBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {});

/// PLOC (Meister and Bittner 2018) from the primitives in Morton order (the
/// LBVH's sort): clusters merge bottom up with their nearest neighbour
/// (smallest union surface area) within plocRadius positions until they
/// average plocTopPrims primitives; a binned SAH pass over those clusters
/// builds the levels above. Subtrees of at most maxLeafSize primitives become
/// leaves, as in buildLbvh. Several times slower than buildLbvh.
Bvh buildPlocBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {});

/// The builder options.builder names.
Bvh buildBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {});

const char* bvhBuilderName(BvhBuilder builder);  ///< "lbvh", "ploc", "sah"
std::optional<BvhBuilder> parseBvhBuilder(std::string_view name);

/// The name, for test output and logs.
inline std::ostream& operator<<(std::ostream& out, BvhBuilder builder) { return out << bvhBuilderName(builder); }

}  // namespace wt
