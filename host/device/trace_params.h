// The bench's and tests' ray-tracing kernels (kernels/trace.cl), declared
// once for KernelArgs: each must match its kernel's signature name for name.
#pragma once

#include "device/kernel_args.h"

namespace wt::trace {

/// trace_closest and trace_closest_packet: `hits` receives (t, b1, b2, prim).
inline constexpr auto kClosestParams =
    concatParams(params("count", "ray_o", "ray_d", "nodes", "node_count", "tri_verts", "hits", "skip", "instances"),
                 kGeometryParams, kAlphaParams);
/// trace_occluded and its packet and stream forms: `occluded` receives 0 or 1.
inline constexpr auto kOccludedParams =
    concatParams(params("count", "ray_o", "ray_d", "nodes", "node_count", "tri_verts", "occluded", "skip", "instances"),
                 kGeometryParams, kAlphaParams);

struct Closest {
  static constexpr std::string_view kName = "trace_closest";
  static constexpr auto kParams = kClosestParams;
};
struct ClosestPacket {
  static constexpr std::string_view kName = "trace_closest_packet";
  static constexpr auto kParams = kClosestParams;
};
struct Occluded {
  static constexpr std::string_view kName = "trace_occluded";
  static constexpr auto kParams = kOccludedParams;
};
struct OccludedPacket {
  static constexpr std::string_view kName = "trace_occluded_packet";
  static constexpr auto kParams = kOccludedParams;
};
struct OccludedStream {
  static constexpr std::string_view kName = "trace_occluded_stream";
  static constexpr auto kParams = kOccludedParams;
};

}  // namespace wt::trace
