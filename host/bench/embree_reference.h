// Embree 3 as the bench's CPU reference: the same triangles and the same
// rays, traced on every host thread. The .cpp is compiled only when CMake
// finds Embree (WT_HAVE_EMBREE); this header has no Embree types.
#pragma once

#include "device/tracer.h"
#include "scene/scene.h"

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {

/// How a thread hands its chunk of rays to Embree. Which is fastest depends
/// on the rays and the machine (docs/lab/2026-11-23-performance-log.md,
/// "Embree settings"), so the bench times all four per ray set by default and
/// compares with the fastest (BenchOptions::embreeApi "fastest").
enum class EmbreeApi {
  kSingle,    ///< rtcIntersect1 / rtcOccluded1 per ray
  kPacket8,   ///< rtcIntersect8 / rtcOccluded8
  kPacket16,  ///< rtcIntersect16 / rtcOccluded16
  kStream,    ///< rtcIntersect1M / rtcOccluded1M over the chunk
};

inline const char* embreeApiName(EmbreeApi api) {
  switch (api) {
    case EmbreeApi::kSingle: return "single";
    case EmbreeApi::kPacket8: return "packet8";
    case EmbreeApi::kPacket16: return "packet16";
    case EmbreeApi::kStream: return "stream";
  }
  return "?";
}

/// "single", "packet8", "packet16", "stream"; throws std::invalid_argument otherwise.
inline EmbreeApi parseEmbreeApi(const std::string& name) {
  for (EmbreeApi api : {EmbreeApi::kSingle, EmbreeApi::kPacket8, EmbreeApi::kPacket16, EmbreeApi::kStream})
    if (name == embreeApiName(api)) return api;
  throw std::invalid_argument("--embree-api " + name + ": expected single, packet8, packet16 or stream");
}

/// Every API, in the order the bench times them.
constexpr EmbreeApi kEmbreeApis[] = {EmbreeApi::kSingle, EmbreeApi::kPacket8, EmbreeApi::kPacket16,
                                     EmbreeApi::kStream};

struct EmbreeOptions {
  EmbreeApi api = EmbreeApi::kPacket16;  ///< the API traces use until setApi
  bool fastestPerSet = false;            ///< only for description(): the caller picks the API per set
  int quality = 2;      ///< RTC_BUILD_QUALITY_: 0 low, 1 medium, 2 high
  bool robust = false;  ///< RTC_SCENE_FLAG_ROBUST
  int threads = 0;      ///< tracing threads; 0: std::thread::hardware_concurrency()
};

class EmbreeReference {
 public:
  /// Build the scene: one triangle geometry sharing the scene's arrays, which
  /// must outlive this object, one point-sphere geometry with the scene's
  /// spheres, and one round-linear-curve geometry with the curve segments
  /// wavetrace traces (gatherCurves). Throws std::runtime_error when Embree fails.
  EmbreeReference(const Scene& scene, const EmbreeOptions& options = {});
  ~EmbreeReference();
  EmbreeReference(const EmbreeReference&) = delete;
  EmbreeReference& operator=(const EmbreeReference&) = delete;

  /// Closest hit in [tmin, tmax]: RayHit::triangle and prim as wt::Tracer gives them.
  /// `coherent` sets RTC_INTERSECT_CONTEXT_FLAG_COHERENT (camera rays).
  std::vector<RayHit> traceClosest(std::span<const Ray> rays, bool coherent = false);
  /// 1 where something blocks [tmin, tmax].
  std::vector<std::uint8_t> traceOccluded(std::span<const Ray> rays, bool coherent = false);

  /// The API later traces use.
  void setApi(EmbreeApi api);
  /// Wall time of the last call's tracing alone, on every thread: without
  /// putting the rays in the API's layout before or reading the answers
  /// after (as wavetrace's kernel time leaves out its upload and read-back).
  double lastTraceSeconds() const;

  double buildSeconds() const { return m_buildSeconds; }
  /// "Embree 3.13.5, packet16 API, high quality, 2 threads" (with
  /// fastestPerSet: "the fastest API of each set" instead of "packet16 API").
  std::string description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  double m_buildSeconds = 0.0;
};

}  // namespace wt
