#include "bench/embree_reference.h"

#include "bvh/parallel.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

namespace wt {
namespace {

// Rays per work unit handed to a thread: large enough that the atomic counter
// costs nothing, small enough that two threads finish together.
constexpr std::size_t kChunk = 4096;

void setRay(const Ray& r, RTCRay& ray) {
  ray.org_x = r.origin.x, ray.org_y = r.origin.y, ray.org_z = r.origin.z;
  ray.dir_x = r.direction.x, ray.dir_y = r.direction.y, ray.dir_z = r.direction.z;
  ray.tnear = r.tmin;
  ray.tfar = r.tmax;
  ray.time = 0.0f;
  ray.mask = 0xffffffffu;
  ray.id = 0;
  ray.flags = 0;
}

RayHit toHit(const RTCRayHit& rh) {
  RayHit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.t = rh.ray.tfar;
  hit.b1 = rh.hit.u;
  hit.b2 = rh.hit.v;
  hit.triangle = rh.hit.primID;
  return hit;
}

/// Fill packet lanes [0, n) of a RTCRayN-style SoA struct from rays.
template <typename Packet>
void setPacket(const Ray* rays, int n, int lanes, Packet& p, int* valid) {
  for (int k = 0; k < lanes; ++k) {
    const Ray& r = rays[std::min(k, n - 1)];  // idle lanes repeat the last ray, masked off
    valid[k] = k < n ? -1 : 0;
    p.org_x[k] = r.origin.x, p.org_y[k] = r.origin.y, p.org_z[k] = r.origin.z;
    p.dir_x[k] = r.direction.x, p.dir_y[k] = r.direction.y, p.dir_z[k] = r.direction.z;
    p.tnear[k] = r.tmin;
    p.tfar[k] = r.tmax;
    p.time[k] = 0.0f;
    p.mask[k] = 0xffffffffu;
    p.id[k] = 0;
    p.flags[k] = 0;
  }
}

}  // namespace

struct EmbreeReference::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  EmbreeOptions options;
  int threads = 1;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  /// Run fn(begin, end) over chunks of [0, count) on every thread.
  template <typename Fn>
  void parallelChunks(std::size_t count, Fn&& fn) {
    std::atomic<std::size_t> next{0};
    auto worker = [&] {
      for (;;) {
        std::size_t begin = next.fetch_add(kChunk, std::memory_order_relaxed);
        if (begin >= count) return;
        fn(begin, std::min(count, begin + kChunk));
      }
    };
    std::vector<std::thread> team;
    for (int t = 1; t < threads; ++t) team.emplace_back(worker);
    worker();
    for (std::thread& t : team) t.join();
  }
};

EmbreeReference::EmbreeReference(const Scene& scene, const EmbreeOptions& options)
    : m_impl(std::make_unique<Impl>()) {
  Impl& im = *m_impl;
  im.options = options;
  im.threads = bvh_detail::resolveThreads(options.threads, std::numeric_limits<int>::max());
  im.device = rtcNewDevice(nullptr);
  if (!im.device) throw std::runtime_error("Embree: rtcNewDevice failed");

  auto start = std::chrono::steady_clock::now();
  im.scene = rtcNewScene(im.device);
  RTCBuildQuality quality = options.quality <= 0   ? RTC_BUILD_QUALITY_LOW
                            : options.quality == 1 ? RTC_BUILD_QUALITY_MEDIUM
                                                   : RTC_BUILD_QUALITY_HIGH;
  rtcSetSceneBuildQuality(im.scene, quality);
  rtcSetSceneFlags(im.scene, options.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  if (!scene.triangles.empty()) {
    RTCGeometry geometry = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, quality);
    // Shared, not copied: WtVec4 is a float3 with padding and WtTriangle a
    // uint3 with the material index, so both strides are 16 bytes (Embree
    // reads 16 bytes per vertex, which the padding covers).
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, scene.positions.data(), 0,
                               sizeof(WtVec4), scene.positions.size());
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, scene.triangles.data(), 0,
                               sizeof(WtTriangle), scene.triangles.size());
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(im.scene, geometry);
    rtcReleaseGeometry(geometry);
  }
  rtcCommitScene(im.scene);
  m_buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (rtcGetDeviceError(im.device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: scene build failed");
}

EmbreeReference::~EmbreeReference() = default;

std::string EmbreeReference::description() const {
  const Impl& im = *m_impl;
  static const char* kQuality[] = {"low", "medium", "high"};
  return "Embree " + std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
         std::to_string(RTC_VERSION_PATCH) + ", " +
         (im.options.fastestPerSet ? std::string("the fastest API of each set")
                                   : embreeApiName(im.options.api) + std::string(" API")) +
         ", " +
         kQuality[std::clamp(im.options.quality, 0, 2)] + " quality" + (im.options.robust ? ", robust" : "") +
         ", " + std::to_string(im.threads) + " threads";
}

void EmbreeReference::setApi(EmbreeApi api) { m_impl->options.api = api; }

std::vector<RayHit> EmbreeReference::traceClosest(std::span<const Ray> rays, bool coherent) {
  Impl& im = *m_impl;
  std::vector<RayHit> hits(rays.size());
  im.parallelChunks(rays.size(), [&](std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    switch (im.options.api) {
      case EmbreeApi::kSingle:
        for (std::size_t i = begin; i < end; ++i) {
          RTCRayHit rh;
          setRay(rays[i], rh.ray);
          rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(im.scene, &context, &rh);
          hits[i] = toHit(rh);
        }
        break;
      case EmbreeApi::kPacket8:
      case EmbreeApi::kPacket16: {
        const int lanes = im.options.api == EmbreeApi::kPacket8 ? 8 : 16;
        alignas(64) RTCRayHit16 p16;
        alignas(32) RTCRayHit8 p8;
        alignas(64) int valid[16];
        for (std::size_t i = begin; i < end; i += lanes) {
          int n = int(std::min<std::size_t>(lanes, end - i));
          if (lanes == 8) {
            setPacket(&rays[i], n, 8, p8.ray, valid);
            std::fill(p8.hit.geomID, p8.hit.geomID + 8, RTC_INVALID_GEOMETRY_ID);
            rtcIntersect8(valid, im.scene, &context, &p8);
          } else {
            setPacket(&rays[i], n, 16, p16.ray, valid);
            std::fill(p16.hit.geomID, p16.hit.geomID + 16, RTC_INVALID_GEOMETRY_ID);
            rtcIntersect16(valid, im.scene, &context, &p16);
          }
          for (int k = 0; k < n; ++k) {
            RayHit& h = hits[i + k];
            unsigned geom = lanes == 8 ? p8.hit.geomID[k] : p16.hit.geomID[k];
            if (geom == RTC_INVALID_GEOMETRY_ID) continue;
            h.t = lanes == 8 ? p8.ray.tfar[k] : p16.ray.tfar[k];
            h.b1 = lanes == 8 ? p8.hit.u[k] : p16.hit.u[k];
            h.b2 = lanes == 8 ? p8.hit.v[k] : p16.hit.v[k];
            h.triangle = lanes == 8 ? p8.hit.primID[k] : p16.hit.primID[k];
          }
        }
        break;
      }
      case EmbreeApi::kStream: {
        std::vector<RTCRayHit> stream(end - begin);
        for (std::size_t i = begin; i < end; ++i) {
          RTCRayHit& rh = stream[i - begin];
          setRay(rays[i], rh.ray);
          rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect1M(im.scene, &context, stream.data(), unsigned(stream.size()), sizeof(RTCRayHit));
        for (std::size_t i = begin; i < end; ++i) hits[i] = toHit(stream[i - begin]);
        break;
      }
    }
  });
  return hits;
}

std::vector<std::uint8_t> EmbreeReference::traceOccluded(std::span<const Ray> rays, bool coherent) {
  Impl& im = *m_impl;
  std::vector<std::uint8_t> occluded(rays.size(), 0);
  // Embree marks an occluded ray by setting tfar to -inf.
  auto blocked = [](float tfar) { return tfar < 0.0f && std::isinf(tfar); };
  im.parallelChunks(rays.size(), [&](std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    switch (im.options.api) {
      case EmbreeApi::kSingle:
        for (std::size_t i = begin; i < end; ++i) {
          RTCRay ray;
          setRay(rays[i], ray);
          rtcOccluded1(im.scene, &context, &ray);
          occluded[i] = blocked(ray.tfar);
        }
        break;
      case EmbreeApi::kPacket8:
      case EmbreeApi::kPacket16: {
        const int lanes = im.options.api == EmbreeApi::kPacket8 ? 8 : 16;
        alignas(64) RTCRay16 p16;
        alignas(32) RTCRay8 p8;
        alignas(64) int valid[16];
        for (std::size_t i = begin; i < end; i += lanes) {
          int n = int(std::min<std::size_t>(lanes, end - i));
          if (lanes == 8) {
            setPacket(&rays[i], n, 8, p8, valid);
            rtcOccluded8(valid, im.scene, &context, &p8);
          } else {
            setPacket(&rays[i], n, 16, p16, valid);
            rtcOccluded16(valid, im.scene, &context, &p16);
          }
          for (int k = 0; k < n; ++k) occluded[i + k] = blocked(lanes == 8 ? p8.tfar[k] : p16.tfar[k]);
        }
        break;
      }
      case EmbreeApi::kStream: {
        std::vector<RTCRay> stream(end - begin);
        for (std::size_t i = begin; i < end; ++i) setRay(rays[i], stream[i - begin]);
        rtcOccluded1M(im.scene, &context, stream.data(), unsigned(stream.size()), sizeof(RTCRay));
        for (std::size_t i = begin; i < end; ++i) occluded[i] = blocked(stream[i - begin].tfar);
        break;
      }
    }
  });
  return occluded;
}

}  // namespace wt
