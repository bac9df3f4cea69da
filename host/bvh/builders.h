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

/// The default. A geometry of 64 or more primitives placed at least twice
/// (instances) gets one tree, built over its first copy and refitted to
/// every copy: by the binned SAH builder while such geometries hold at most
/// 32 768 primitives in all (one copy of each), else by PLOC up to 65 536
/// primitives each and by the LBVH above. The other primitives, together,
/// get one tree: PLOC up to 65 536, the LBVH above. A binned SAH pass over
/// the copies and the others' subtrees builds the levels above. Throws
/// std::invalid_argument for instances out of range, overlapping, or of one
/// geometry with different counts.
Bvh buildAutoBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {},
                 std::span<const BvhInstance> instances = {});

/// The builder options.builder names. Only Auto reads `instances`; the
/// others build over all primitives alike.
Bvh buildBvh(std::span<const Aabb> primBounds, const BvhBuildOptions& options = {},
             std::span<const BvhInstance> instances = {});

const char* bvhBuilderName(BvhBuilder builder);  ///< "auto", "lbvh", "ploc", "sah"
std::optional<BvhBuilder> parseBvhBuilder(std::string_view name);

/// The name, for test output and logs.
inline std::ostream& operator<<(std::ostream& out, BvhBuilder builder) { return out << bvhBuilderName(builder); }

}  // namespace wt
