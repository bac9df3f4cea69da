#include "bench/embree_reference.h"

#include "bvh/parallel.h"
#include "geometry/primitives.h"

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
static_assert(kChunk % 16 == 0, "a chunk holds whole packets");

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

/// What a hit names: a scene triangle, or another type's typed id (primId),
/// by the geometry's type (its WT_PRIM_* by geometry id).
void setHitPrimitive(RayHit& hit, const std::vector<std::uint32_t>& typeOfGeometry, unsigned geomID, unsigned primID) {
  const std::uint32_t type = typeOfGeometry[geomID];
  hit.triangle = type == WT_PRIM_TRIANGLE ? primID : RayHit::kNoHit;
  hit.prim = type == WT_PRIM_TRIANGLE ? primID : primId(type, primID);
}

RayHit toHit(const RTCRayHit& rh, const std::vector<std::uint32_t>& typeOfGeometry) {
  RayHit hit;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  hit.t = rh.ray.tfar;
  hit.b1 = rh.hit.u;
  hit.b2 = rh.hit.v;
  setHitPrimitive(hit, typeOfGeometry, rh.hit.geomID, rh.hit.primID);
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

/// Lane masks of one packet, in the alignment rtcIntersect16 wants.
struct alignas(64) PacketValid {
  int lanes[16];
};

struct EmbreeReference::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  EmbreeOptions options;
  int threads = 1;
  // The rays of the last call in the API's layout, kept between calls so
  // that a repeated trace touches no fresh memory.
  std::vector<RTCRayHit> rayHits;  ///< single, stream (closest)
  std::vector<RTCRay> rays1;       ///< single, stream (any hit)
  std::vector<RTCRayHit8> rayHits8;
  std::vector<RTCRayHit16> rayHits16;
  std::vector<RTCRay8> rays8;
  std::vector<RTCRay16> rays16;
  std::vector<PacketValid> valid;
  double lastTraceSeconds = 0.0;
  std::vector<std::uint32_t> typeOfGeometry;  ///< WT_PRIM_* by Embree geometry id
  std::vector<float> spheres;                 ///< x, y, z, radius per scene sphere (Embree reads this copy)
  std::vector<float> curveJoints;             ///< x, y, z, radius: both joints of every curve segment
  std::vector<std::uint32_t> curveFirst;      ///< per segment: its first joint
  std::vector<std::uint8_t> curveFlags;       ///< per segment: RTC_CURVE_FLAG_NEIGHBOR_LEFT / _RIGHT

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
  auto attach = [&](RTCGeometry geometry, std::uint32_t type) {
    const unsigned id = rtcAttachGeometry(im.scene, geometry);
    rtcReleaseGeometry(geometry);
    if (im.typeOfGeometry.size() <= id) im.typeOfGeometry.resize(id + 1, WT_PRIM_TRIANGLE);
    im.typeOfGeometry[id] = type;
  };
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
    attach(geometry, WT_PRIM_TRIANGLE);
  }
  if (!scene.spheres.empty()) {
    // the same centres and radii, one point sphere each, in scene order
    for (const Sphere& sphere : scene.spheres)
      im.spheres.insert(im.spheres.end(), {sphere.center.x, sphere.center.y, sphere.center.z, sphere.radius});
    RTCGeometry geometry = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    rtcSetGeometryBuildQuality(geometry, quality);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, im.spheres.data(), 0,
                               4 * sizeof(float), scene.spheres.size());
    rtcCommitGeometry(geometry);
    attach(geometry, WT_PRIM_SPHERE);
  }
  // curves: the segments wavetrace traces (B-splines subdivided, the same
  // joints and radii), as round linear curves told which neighbours exist,
  // in the order of their typed ids
  const PrimitiveRows rows = scene.curves.empty() ? PrimitiveRows{} : gatherPrimitives(scene);
  std::uint32_t segments = 0;
  for (std::uint32_t id : rows.ids) segments += primType(id) == WT_PRIM_CURVE;
  if (segments > 0) {
    for (std::uint32_t i = 0; i < segments; ++i) {
      const CurveSegment c = curveSegment(rows, i);
      im.curveFirst.push_back(std::uint32_t(im.curveJoints.size() / 4));
      im.curveJoints.insert(im.curveJoints.end(), {c.p0.x, c.p0.y, c.p0.z, c.p0.w, c.p1.x, c.p1.y, c.p1.z, c.p1.w});
      im.curveFlags.push_back(std::uint8_t((c.left ? RTC_CURVE_FLAG_NEIGHBOR_LEFT : 0) |
                                           (c.right ? RTC_CURVE_FLAG_NEIGHBOR_RIGHT : 0)));
    }
    RTCGeometry geometry = rtcNewGeometry(im.device, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
    rtcSetGeometryBuildQuality(geometry, quality);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, im.curveJoints.data(), 0,
                               4 * sizeof(float), im.curveJoints.size() / 4);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, im.curveFirst.data(), 0,
                               sizeof(std::uint32_t), segments);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_FLAGS, 0, RTC_FORMAT_UCHAR, im.curveFlags.data(), 0,
                               sizeof(std::uint8_t), segments);
    rtcCommitGeometry(geometry);
    attach(geometry, WT_PRIM_CURVE);
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

double EmbreeReference::lastTraceSeconds() const { return m_impl->lastTraceSeconds; }

// Each call has three passes over the rays on every thread: the rays put in
// the API's layout, then the trace alone (timed: lastTraceSeconds, as
// wavetrace's kernel time leaves out its upload and read-back), then the
// answers read out.

std::vector<RayHit> EmbreeReference::traceClosest(std::span<const Ray> rays, bool coherent) {
  Impl& im = *m_impl;
  const std::size_t n = rays.size();
  const EmbreeApi api = im.options.api;
  const int lanes = api == EmbreeApi::kPacket8 ? 8 : api == EmbreeApi::kPacket16 ? 16 : 1;
  const std::size_t packets = (n + std::size_t(lanes) - 1) / std::size_t(lanes);
  if (lanes == 1 && im.rayHits.size() < n) im.rayHits.resize(n);
  if (lanes == 8 && im.rayHits8.size() < packets) im.rayHits8.resize(packets);
  if (lanes == 16 && im.rayHits16.size() < packets) im.rayHits16.resize(packets);
  if (lanes > 1 && im.valid.size() < packets) im.valid.resize(packets);
  // chunks start at multiples of kChunk, so of the packet width
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    if (lanes == 1) {
      for (std::size_t i = begin; i < end; ++i) {
        RTCRayHit& rh = im.rayHits[i];
        setRay(rays[i], rh.ray);
        rh.hit.geomID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      return;
    }
    for (std::size_t i = begin; i < end; i += std::size_t(lanes)) {
      const int count = int(std::min<std::size_t>(std::size_t(lanes), end - i));
      const std::size_t p = i / std::size_t(lanes);
      if (lanes == 8) {
        setPacket(&rays[i], count, 8, im.rayHits8[p].ray, im.valid[p].lanes);
        std::fill(im.rayHits8[p].hit.geomID, im.rayHits8[p].hit.geomID + 8, RTC_INVALID_GEOMETRY_ID);
      } else {
        setPacket(&rays[i], count, 16, im.rayHits16[p].ray, im.valid[p].lanes);
        std::fill(im.rayHits16[p].hit.geomID, im.rayHits16[p].hit.geomID + 16, RTC_INVALID_GEOMETRY_ID);
      }
    }
  });
  const auto start = std::chrono::steady_clock::now();
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    switch (api) {
      case EmbreeApi::kSingle:
        for (std::size_t i = begin; i < end; ++i) rtcIntersect1(im.scene, &context, &im.rayHits[i]);
        break;
      case EmbreeApi::kPacket8:
        for (std::size_t i = begin; i < end; i += 8)
          rtcIntersect8(im.valid[i / 8].lanes, im.scene, &context, &im.rayHits8[i / 8]);
        break;
      case EmbreeApi::kPacket16:
        for (std::size_t i = begin; i < end; i += 16)
          rtcIntersect16(im.valid[i / 16].lanes, im.scene, &context, &im.rayHits16[i / 16]);
        break;
      case EmbreeApi::kStream:
        rtcIntersect1M(im.scene, &context, im.rayHits.data() + begin, unsigned(end - begin), sizeof(RTCRayHit));
        break;
    }
  });
  im.lastTraceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<RayHit> hits(n);
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (lanes == 1) {
        hits[i] = toHit(im.rayHits[i], im.typeOfGeometry);
        continue;
      }
      const std::size_t p = i / std::size_t(lanes), k = i % std::size_t(lanes);
      const unsigned geom = lanes == 8 ? im.rayHits8[p].hit.geomID[k] : im.rayHits16[p].hit.geomID[k];
      if (geom == RTC_INVALID_GEOMETRY_ID) continue;
      RayHit& h = hits[i];
      h.t = lanes == 8 ? im.rayHits8[p].ray.tfar[k] : im.rayHits16[p].ray.tfar[k];
      h.b1 = lanes == 8 ? im.rayHits8[p].hit.u[k] : im.rayHits16[p].hit.u[k];
      h.b2 = lanes == 8 ? im.rayHits8[p].hit.v[k] : im.rayHits16[p].hit.v[k];
      setHitPrimitive(h, im.typeOfGeometry, geom,
                      lanes == 8 ? im.rayHits8[p].hit.primID[k] : im.rayHits16[p].hit.primID[k]);
    }
  });
  return hits;
}

std::vector<std::uint8_t> EmbreeReference::traceOccluded(std::span<const Ray> rays, bool coherent) {
  Impl& im = *m_impl;
  const std::size_t n = rays.size();
  const EmbreeApi api = im.options.api;
  const int lanes = api == EmbreeApi::kPacket8 ? 8 : api == EmbreeApi::kPacket16 ? 16 : 1;
  const std::size_t packets = (n + std::size_t(lanes) - 1) / std::size_t(lanes);
  if (lanes == 1 && im.rays1.size() < n) im.rays1.resize(n);
  if (lanes == 8 && im.rays8.size() < packets) im.rays8.resize(packets);
  if (lanes == 16 && im.rays16.size() < packets) im.rays16.resize(packets);
  if (lanes > 1 && im.valid.size() < packets) im.valid.resize(packets);
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    if (lanes == 1) {
      for (std::size_t i = begin; i < end; ++i) setRay(rays[i], im.rays1[i]);
      return;
    }
    for (std::size_t i = begin; i < end; i += std::size_t(lanes)) {
      const int count = int(std::min<std::size_t>(std::size_t(lanes), end - i));
      const std::size_t p = i / std::size_t(lanes);
      if (lanes == 8)
        setPacket(&rays[i], count, 8, im.rays8[p], im.valid[p].lanes);
      else
        setPacket(&rays[i], count, 16, im.rays16[p], im.valid[p].lanes);
    }
  });
  const auto start = std::chrono::steady_clock::now();
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherent) context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    switch (api) {
      case EmbreeApi::kSingle:
        for (std::size_t i = begin; i < end; ++i) rtcOccluded1(im.scene, &context, &im.rays1[i]);
        break;
      case EmbreeApi::kPacket8:
        for (std::size_t i = begin; i < end; i += 8)
          rtcOccluded8(im.valid[i / 8].lanes, im.scene, &context, &im.rays8[i / 8]);
        break;
      case EmbreeApi::kPacket16:
        for (std::size_t i = begin; i < end; i += 16)
          rtcOccluded16(im.valid[i / 16].lanes, im.scene, &context, &im.rays16[i / 16]);
        break;
      case EmbreeApi::kStream:
        rtcOccluded1M(im.scene, &context, im.rays1.data() + begin, unsigned(end - begin), sizeof(RTCRay));
        break;
    }
  });
  im.lastTraceSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Embree marks an occluded ray by setting tfar to -inf.
  auto blocked = [](float tfar) { return tfar < 0.0f && std::isinf(tfar); };
  std::vector<std::uint8_t> occluded(n, 0);
  im.parallelChunks(n, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const std::size_t p = i / std::size_t(lanes), k = i % std::size_t(lanes);
      occluded[i] = blocked(lanes == 1 ? im.rays1[i].tfar : lanes == 8 ? im.rays8[p].tfar[k] : im.rays16[p].tfar[k]);
    }
  });
  return occluded;
}

}  // namespace wt
