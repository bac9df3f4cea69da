// The render stages' parameter lists, declared once: each must match its
// kernel's signature in kernels/*.cl, name for name and in order
// (KernelBinding checks the count at start-up, tests/contract/test_kernel_contract.cpp
// the names and the path-state element types).
#pragma once

#include "device/kernel_args.h"

namespace wt::stage {

struct Generate {
  static constexpr std::string_view kName = "generate";
  static constexpr auto kParams = params("frame", "camera", "camera_media", "ray_o", "ray_d", "throughput", "radiance", "queue",
                                         "counters", "bounce_counts", "ray_skip", "ray_cone", "media");
};

/// extend and extend_packet: the same parameters.
inline constexpr auto kExtendParams =
    concatParams(params("counters", "queue_slot", "queue", "ray_o", "ray_d", "nodes", "node_count", "tri_verts",
                        "hits", "ray_skip", "hit_instance", "aov_sample"),
                 kGeometryParams, kAlphaParams);
struct Extend {
  static constexpr std::string_view kName = "extend";
  static constexpr auto kParams = kExtendParams;
};
struct ExtendPacket {
  static constexpr std::string_view kName = "extend_packet";
  static constexpr auto kParams = kExtendParams;
};

struct Shade {
  static constexpr std::string_view kName = "shade";
  static constexpr auto kParams = concatParams(
      params("frame", "environment", "env_texels", "env_marginal_cdf", "env_conditional_cdf", "counters", "in_slot",
             "out_slot", "queue_in", "queue_out", "ray_o", "ray_d", "hits", "throughput", "radiance", "tri_info",
             "tri_verts", "normals", "materials", "lights", "alias", "emitter_pdf_area", "shadow_queue", "shadow_o",
             "shadow_d", "shadow_radiance", "pbr_table", "bounce_counts", "ray_skip", "shadow_skip", "light_tree",
             "emitter_leaf", "prev_normal", "hit_instance"),
      kGeometryParams, params("ray_cone", "aov_sample", "aov_ids", "media"), kSurfaceParams,
      paramsIf(ParamIf::ThinShadows, params("shadow_walls")), paramsIf(ParamIf::QuadLights, params("emitter_quad")));
};

/// connect, connect_packet and connect_stream: the same parameters.
inline constexpr auto kConnectParams =
    concatParams(params("counters", "shadow_queue", "shadow_o", "shadow_d", "shadow_radiance", "nodes", "node_count",
                        "tri_verts", "radiance", "shadow_skip", "hit_instance"),
                 kGeometryParams, kAlphaParams,
                 paramsIf(ParamIf::ThinShadows,
                          params("shadow_walls", "thin_materials", "thin_tri_info", "thin_normals", "thin_pbr_table",
                                 "thin_vertex_uv", "thin_vertex_color", "thin_vertex_tangent", "thin_material_textures",
                                 "thin_textures", "thin_texture_levels", "thin_texels")));
struct Connect {
  static constexpr std::string_view kName = "connect";
  static constexpr auto kParams = kConnectParams;
};
struct ConnectPacket {
  static constexpr std::string_view kName = "connect_packet";
  static constexpr auto kParams = kConnectParams;
};
struct ConnectStream {
  static constexpr std::string_view kName = "connect_stream";
  static constexpr auto kParams = kConnectParams;
};

struct Accumulate {
  static constexpr std::string_view kName = "accumulate";
  static constexpr auto kParams = params("frame", "radiance", "state", "sample_count", "counters", "aov_sample", "aov_accum");
};
struct Resolve {
  static constexpr std::string_view kName = "accumulate_resolve";
  static constexpr auto kParams = params("frame", "state", "mean", "m2");
};
struct Tonemap {
  static constexpr std::string_view kName = "tonemap";
  static constexpr auto kParams = params("frame", "tonemap", "exposure", "mean", "pixels");
};
/// Auto exposure (kernels/tonemap.cl): log-luminance partial sums, then the scale.
struct LogLuminance {
  static constexpr std::string_view kName = "tonemap_log_luminance";
  static constexpr auto kParams = params("frame", "mean", "partials");
};
struct TonemapExposure {
  static constexpr std::string_view kName = "tonemap_exposure";
  static constexpr auto kParams = params("frame", "partials", "exposure");
};

}  // namespace wt::stage
