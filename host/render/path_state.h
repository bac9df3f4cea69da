// The per-pixel buffers of the wavefront (the path state, the queues, the
// shadow rays and the accumulation), listed once with their element type
// and the stages that need them: the list allocates them and binds them by
// name to every stage that declares a parameter of that name.
#pragma once

#include "device/kernel_args.h"

#include <CL/opencl.hpp>

#include <array>
#include <cstddef>
#include <string_view>

namespace wt {

/// What a buffer exists for; one whose need is absent holds a single
/// element (the kernels still take it, and never touch it).
enum class PathNeed : std::uint8_t {
  Always,
  Shadows,    ///< the connect stage runs (some light can be sampled)
  Instances,  ///< the scene has instances (hit_instance)
  Textures,   ///< textures are read at the path's footprint (ray_cone)
  Aovs,       ///< the render records AOVs (RenderSettings::aovs, kernels/aov.cl)
  Media,      ///< the kernels refract (WT_HAS_TRANSMISSION): the nested-dielectric stack
  ThinShadows,  ///< shadow rays cross smooth thin walls (WT_HAS_THIN_SHADOWS): how many each may cross
};

struct PathNeeds {
  bool shadows = true;
  bool instances = false;
  bool textures = false;
  bool aovs = false;
  bool media = false;
  bool thinShadows = false;
  bool has(PathNeed n) const {
    return n == PathNeed::Always || (n == PathNeed::Shadows && shadows) ||
           (n == PathNeed::Instances && instances) || (n == PathNeed::Textures && textures) ||
           (n == PathNeed::Aovs && aovs) || (n == PathNeed::Media && media) ||
           (n == PathNeed::ThinShadows && thinShadows && shadows);
  }
};

struct PathState;

struct PathBufferDesc {
  std::string_view name;        ///< the kernels' parameter name
  std::string_view deviceType;  ///< the kernels' element type (tests compare CL_KERNEL_ARG_TYPE_NAME)
  std::size_t elementBytes;     ///< bytes per pixel
  cl::Buffer PathState::*member;
  PathNeed need;
};

struct PathState {
  cl::Buffer rayO, rayD;      ///< float4: origin and tmin; direction and tmax
  cl::Buffer hits;            ///< float4: t, b1, b2, prim (extend)
  cl::Buffer throughput;      ///< float4: xyz throughput, w the last BSDF pdf
  cl::Buffer radiance;        ///< float4: this sample's radiance so far
  cl::Buffer bounceCounts;    ///< ushort4: diffuse, specular, transmission bounces
  cl::Buffer raySkip;         ///< uint: the triangle the next ray leaves (never hit)
  cl::Buffer prevNormal;      ///< float4: the last vertex's normal for the light tree's pmf
  /// uint: the instance of the last hit (WT_NO_HIT: none), written by
  /// extend; the path's next rays leave (ray_skip or shadow_skip.x, this instance)
  cl::Buffer hitInstance;
  cl::Buffer rayCone;         ///< float2: footprint spread so far, cone angle of the ray (materials/textured.cl)
  cl::Buffer queueA, queueB;  ///< uint: the paths of a bounce, in and out by turns
  cl::Buffer shadowQueue;     ///< uint: the shadow rays of a bounce
  cl::Buffer shadowO, shadowD, shadowRadiance;  ///< float4: the shadow ray and what it carries if unblocked
  cl::Buffer shadowSkip;      ///< uint2: the triangle it leaves, the emitter it aims at (neither hit)
  cl::Buffer shadowWalls;     ///< uint: the thin walls the shadow ray may cross (kernels/connect.cl)
  cl::Buffer state;           ///< float4[4]: accumulation state (accumulate.cl)
  cl::Buffer mean, m2;        ///< float4: resolved mean and second moment
  cl::Buffer sampleCount;     ///< uint: samples folded in
  cl::Buffer pixels;          ///< uchar4: tone-mapped sRGB
  cl::Buffer aovSample;       ///< float4[4]: this sample's AOVs (kernels/aov.cl)
  cl::Buffer aovAccum;        ///< float4[4]: the AOVs summed over samples
  cl::Buffer aovIds;          ///< uint4: the first sample's material, instance, primitive at the camera hit
  cl::Buffer media;           ///< uint4: the volumes the path is inside (kernels/shared/media.h)

  /// Every buffer above, once.
  static const std::array<PathBufferDesc, 27> kBuffers;

  /// Allocate every buffer for `pixels` pixels (one element where `needs`
  /// lacks its need). With `host` (a CPU device's), the buffers are that
  /// memory (CL_MEM_USE_HOST_PTR), hostBytes() of it, which must outlive
  /// them and every command that uses them; else the device allocates.
  void allocate(const cl::Context& context, std::size_t pixels, const PathNeeds& needs, std::byte* host = nullptr);
  /// Bytes allocate() takes from `host`: each buffer starts on a kHostAlignment boundary.
  static std::size_t hostBytes(std::size_t pixels, const PathNeeds& needs);
  /// A page: more than any device's CL_DEVICE_MEM_BASE_ADDR_ALIGN asks of a host pointer.
  static constexpr std::size_t kHostAlignment = 4096;
  /// Bytes allocated by allocate().
  std::size_t bytes = 0;

  /// Set every parameter of `args` that names a buffer of the list.
  template <class Decl>
  void bind(KernelArgs<Decl>& args) const {
    for (const PathBufferDesc& b : kBuffers) args.setIfDeclared(b.name, this->*b.member);
  }
};

inline const std::array<PathBufferDesc, 27> PathState::kBuffers{{
    {"ray_o", "float4", 16, &PathState::rayO, PathNeed::Always},
    {"ray_d", "float4", 16, &PathState::rayD, PathNeed::Always},
    {"hits", "float4", 16, &PathState::hits, PathNeed::Always},
    {"throughput", "float4", 16, &PathState::throughput, PathNeed::Always},
    {"radiance", "float4", 16, &PathState::radiance, PathNeed::Always},
    {"bounce_counts", "ushort4", 8, &PathState::bounceCounts, PathNeed::Always},
    {"ray_skip", "uint", 4, &PathState::raySkip, PathNeed::Always},
    {"prev_normal", "float4", 16, &PathState::prevNormal, PathNeed::Always},
    {"hit_instance", "uint", 4, &PathState::hitInstance, PathNeed::Instances},
    {"ray_cone", "float2", 8, &PathState::rayCone, PathNeed::Textures},
    // the queues change places every bounce: bound per launch, never by name
    {"queue_a", "uint", 4, &PathState::queueA, PathNeed::Always},
    {"queue_b", "uint", 4, &PathState::queueB, PathNeed::Always},
    {"shadow_queue", "uint", 4, &PathState::shadowQueue, PathNeed::Shadows},
    {"shadow_o", "float4", 16, &PathState::shadowO, PathNeed::Shadows},
    {"shadow_d", "float4", 16, &PathState::shadowD, PathNeed::Shadows},
    {"shadow_radiance", "float4", 16, &PathState::shadowRadiance, PathNeed::Shadows},
    {"shadow_skip", "uint2", 8, &PathState::shadowSkip, PathNeed::Shadows},
    {"shadow_walls", "uint", 4, &PathState::shadowWalls, PathNeed::ThinShadows},
    {"state", "float4", 64, &PathState::state, PathNeed::Always},
    {"mean", "float4", 16, &PathState::mean, PathNeed::Always},
    {"m2", "float4", 16, &PathState::m2, PathNeed::Always},
    {"sample_count", "uint", 4, &PathState::sampleCount, PathNeed::Always},
    {"pixels", "uchar4", 4, &PathState::pixels, PathNeed::Always},
    {"aov_sample", "float4", 64, &PathState::aovSample, PathNeed::Aovs},
    {"aov_accum", "float4", 64, &PathState::aovAccum, PathNeed::Aovs},
    {"aov_ids", "uint4", 16, &PathState::aovIds, PathNeed::Aovs},
    {"media", "uint4", 16, &PathState::media, PathNeed::Media},
}};

inline std::size_t PathState::hostBytes(std::size_t pixelCount, const PathNeeds& needs) {
  std::size_t total = 0;
  for (const PathBufferDesc& b : kBuffers) {
    const std::size_t size = b.elementBytes * (needs.has(b.need) ? pixelCount : 1);
    total += (size + kHostAlignment - 1) / kHostAlignment * kHostAlignment;
  }
  return total;
}

inline void PathState::allocate(const cl::Context& context, std::size_t pixelCount, const PathNeeds& needs,
                                std::byte* host) {
  bytes = 0;
  std::size_t offset = 0;
  for (const PathBufferDesc& b : kBuffers) {
    const std::size_t size = b.elementBytes * (needs.has(b.need) ? pixelCount : 1);
    if (host) {
      this->*b.member = cl::Buffer(context, CL_MEM_READ_WRITE | CL_MEM_USE_HOST_PTR, size, host + offset);
      offset += (size + kHostAlignment - 1) / kHostAlignment * kHostAlignment;
    } else {
      this->*b.member = cl::Buffer(context, CL_MEM_READ_WRITE, size);
    }
    bytes += size;
  }
}

}  // namespace wt
