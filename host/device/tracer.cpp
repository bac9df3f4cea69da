#include "device/tracer.h"

#include "device/program.h"
#include "device/scene_args.h"
#include "render/feature_set.h"
#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace wt {

Tracer::Tracer(Context& context, const Scene& scene, const BvhBuildOptions& options, int packetWidth,
               StreamPrefetch prefetch)
    : m_context(context), m_scene(std::make_unique<SceneBuffers>(context, scene, options)),
      m_packetWidth(packetWidthFor(context.info(), packetWidth, scene.triangles.size())),
      m_streamPrefetch(prefetch == StreamPrefetch::kAuto ? streamPrefetchFor(context.info(), m_scene->uploadedBytes)
                                                         : prefetch == StreamPrefetch::kOn) {
  // the scene's switches (sceneFeatures), less what tracing without shading never reads
  KernelFeatures features =
      kernelFeaturesFor(sceneFeatures(scene, *m_scene, RenderSettings{}), context.info(), m_packetWidth);
  features.pbr = features.transmission = features.specular = features.clearcoat = features.sheen = features.anisotropy = features.iridescence = false;
  // the alpha test reads the surface: texture coordinates, COLOR_0 and textures
  features.textures = features.alpha && features.textures;
  features.vertexColors = features.alpha && features.vertexColors;
  features.streamPrefetch = m_streamPrefetch;
  m_program = buildProgram(context, features, "trace.cl");
  m_alpha = features.alpha;
  const ParamFeatures built{features.alpha};
  m_closest = {m_program, built};
  m_occluded = {m_program, built};
  m_closestPacket = {m_program, built};
  m_occludedPacket = {m_program, built};
  m_occludedStream = {m_program, built};
}

Tracer::~Tracer() = default;

double packetCoherence(std::span<const Ray> rays, std::size_t width) {
  const std::size_t kPacket = std::max<std::size_t>(width, 1);
  double total = 0.0;
  std::size_t packets = 0;
  for (std::size_t first = 0; first < rays.size(); first += kPacket) {
    const std::size_t end = std::min(rays.size(), first + kPacket);
    glm::dvec3 sum(0.0);
    std::size_t count = 0;
    for (std::size_t i = first; i < end; ++i) {
      const glm::dvec3 d(rays[i].direction);
      const double length = glm::length(d);
      if (!(length > 0.0) || !std::isfinite(length)) continue;  // such rays never hit: no say in the choice
      sum += d / length;
      ++count;
    }
    if (count == 0) continue;
    total += glm::length(sum) / double(count);
    ++packets;
  }
  return packets > 0 ? total / double(packets) : 0.0;
}

RayBatchStats measureRays(std::span<const Ray> rays, std::size_t width, std::size_t maxPackets) {
  RayBatchStats stats;
  const std::size_t kWidth = std::max<std::size_t>(width, 1);
  const std::size_t packets = (rays.size() + kWidth - 1) / kWidth;
  if (packets == 0 || maxPackets == 0) return stats;
  // every step-th packet: the sample covers the whole batch (its pixels, its bounces)
  const std::size_t step = std::max<std::size_t>(1, packets / maxPackets);
  double coherence = 0.0, octants = 0.0, spread = 0.0;
  for (std::size_t p = 0; p < packets; p += step) {
    const std::span<const Ray> packet = rays.subspan(p * kWidth, std::min(kWidth, rays.size() - p * kWidth));
    std::size_t inOctant[8] = {};
    glm::dvec3 mean(0.0);
    std::size_t finite = 0;
    for (const Ray& r : packet) {
      if (!std::isfinite(r.origin.x + r.origin.y + r.origin.z)) continue;
      ++inOctant[(r.direction.x < 0.0f ? 1 : 0) | (r.direction.y < 0.0f ? 2 : 0) | (r.direction.z < 0.0f ? 4 : 0)];
      mean += glm::dvec3(r.origin);
      ++finite;
    }
    if (finite == 0) continue;
    mean /= double(finite);
    double squares = 0.0;
    for (const Ray& r : packet)
      if (std::isfinite(r.origin.x + r.origin.y + r.origin.z)) {
        const glm::dvec3 offset = glm::dvec3(r.origin) - mean;
        squares += glm::dot(offset, offset);
      }
    coherence += packetCoherence(packet, kWidth);
    octants += double(*std::max_element(std::begin(inOctant), std::end(inOctant))) / double(finite);
    spread += std::sqrt(squares / double(finite));
    ++stats.packets;
  }
  if (stats.packets == 0) return stats;
  stats.coherence = coherence / double(stats.packets);
  stats.octantShare = octants / double(stats.packets);
  stats.originSpread = spread / double(stats.packets);
  return stats;
}

void TraversalTrials::add(Traversal traversal, double secondsPerRay) {
  double& fastest = m_fastest[traversal == Traversal::kPacket ? 1 : 0];
  if (secondsPerRay > 0.0 && (fastest == 0.0 || secondsPerRay < fastest)) fastest = secondsPerRay;
}

std::optional<Traversal> TraversalTrials::faster() const {
  if (m_fastest[0] == 0.0 || m_fastest[1] == 0.0) return std::nullopt;
  return m_fastest[1] < m_fastest[0] ? Traversal::kPacket : Traversal::kSingle;
}

double TraversalTrials::packetRatio() const { return m_fastest[0] > 0.0 ? m_fastest[1] / m_fastest[0] : 0.0; }

Traversal chooseTraversal(const RayBatchStats& stats, double scale, bool occlusion, bool cpu) {
  const bool streams = occlusion && cpu;
  const Traversal incoherent = streams ? Traversal::kStream : Traversal::kSingle;
  if (stats.packets == 0 || stats.coherence < kPacketMinCoherence) return incoherent;
  // the leaf neighbourhoods a packet visits at its origins: 1 for one origin,
  // one more per leaf width of origin spread (diameter about 2 RMS radii)
  const double leaf = kLeafScales * std::max(scale, 1e-30);
  const double neighbourhoods = 1.0 + 2.0 * stats.originSpread / leaf;
  // cost per ray in single-ray visits
  const double packet = neighbourhoods * kPacketLaneCost, other = streams ? 1.0 / kStreamGain : 1.0;
  return packet < other ? Traversal::kPacket : incoherent;
}

Traversal Tracer::chooseTraversal(std::span<const Ray> rays, bool occlusion) const {
  return wt::chooseTraversal(measureRays(rays, std::size_t(m_packetWidth)), primitiveScale(), occlusion,
                             m_context.info().isCpu);
}

void Tracer::uploadRays(std::span<const Ray> rays) {
  std::size_t n = std::max<std::size_t>(rays.size(), 1);
  if (n > m_capacity) {
    m_rayO = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 16);
    m_rayD = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 16);
    m_skip = cl::Buffer(m_context.context(), CL_MEM_READ_ONLY, n * 4);
    m_instances = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, n * 4);
    m_out = cl::Buffer(m_context.context(), CL_MEM_READ_WRITE, n * 16);
    m_capacity = n;
  }
  // Split the interleaved rays into the two float4 streams the kernels read.
  std::vector<float> o(4 * rays.size()), d(4 * rays.size());
  std::vector<cl_uint> skip(rays.size()), skipInstance(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    o[4 * i + 0] = r.origin.x, o[4 * i + 1] = r.origin.y, o[4 * i + 2] = r.origin.z, o[4 * i + 3] = r.tmin;
    d[4 * i + 0] = r.direction.x, d[4 * i + 1] = r.direction.y, d[4 * i + 2] = r.direction.z,
              d[4 * i + 3] = r.tmax;
    // a scene triangle of an instanced copy is its geometry's triangle on that instance
    // and a sphere's or curve's of an instanced copy is its geometry's on that instance
    const bool triangle = primType(r.skip) == WT_PRIM_TRIANGLE;
    const auto [prim, instance] = m_scene->devicePrimitive(r.skip);
    skip[i] = triangle ? m_scene->leafTriangle(r.skip) : prim;
    skipInstance[i] = triangle ? m_scene->triangleInstance(r.skip) : instance;
  }
  if (!rays.empty()) {
    m_context.queue().enqueueWriteBuffer(m_rayO, CL_TRUE, 0, o.size() * 4, o.data());
    m_context.queue().enqueueWriteBuffer(m_rayD, CL_TRUE, 0, d.size() * 4, d.data());
    m_context.queue().enqueueWriteBuffer(m_skip, CL_TRUE, 0, skip.size() * 4, skip.data());
    m_context.queue().enqueueWriteBuffer(m_instances, CL_TRUE, 0, skipInstance.size() * 4, skipInstance.data());
  }
}

template <class Decl>
void Tracer::run(KernelArgs<Decl>& kernel, std::size_t rays, Traversal traversal) {
  const char* name = Decl::kName.data();
  kernel.set("count", cl_uint(rays))
      .set("ray_o", m_rayO)
      .set("ray_d", m_rayD)
      .set("nodes", m_scene->nodes)
      .set("node_count", m_scene->nodeCount)
      .set("tri_verts", m_scene->triVerts)
      .set("skip", m_skip)
      .set("instances", m_instances);
  if constexpr (findParam(Decl::kParams, "hits").has_value())
    kernel.set("hits", m_out);
  else
    kernel.set("occluded", m_out);
  bindGeometry(kernel, *m_scene);
  if (m_alpha) bindAlpha(kernel, *m_scene, m_alphaKey);
  kernel.requireBound();
  const std::size_t kPacket = std::size_t(m_packetWidth);
  std::size_t items = rays, localSize = Context::kLocalSize;
  if (traversal == Traversal::kPacket) {
    items = (rays + kPacket - 1) / kPacket;
  } else if (traversal == Traversal::kStream) {
    // a window of rays per work-item: small groups, so that every thread gets some
    items = (rays + WT_STREAM_WINDOW - 1) / WT_STREAM_WINDOW;
    localSize = Context::kStreamLocalSize;
  }
  m_context.resetStageTimes();
  m_context.launch(name, kernel.kernel(), items, localSize);
  m_context.finish();
  m_lastKernelSeconds =
      m_context.stageTimes().seconds.count(name) ? m_context.stageTimes().seconds.at(name) : 0.0;
}

std::vector<RayHit> Tracer::traceClosest(std::span<const Ray> rays, Traversal traversal) {
  uploadRays(rays);
  if (traversal == Traversal::kPacket)
    run(m_closestPacket, rays.size(), traversal);
  else
    run(m_closest, rays.size(), Traversal::kSingle);  // kStream: any hit only
  std::vector<float> raw(4 * rays.size());
  if (!rays.empty())
    m_context.queue().enqueueReadBuffer(m_out, CL_TRUE, 0, raw.size() * 4, raw.data());
  std::vector<cl_uint> instances(rays.size(), RayHit::kNoHit);
  if (!rays.empty() && m_scene->instanceCount() > 0)
    m_context.queue().enqueueReadBuffer(m_instances, CL_TRUE, 0, instances.size() * 4, instances.data());
  std::vector<RayHit> hits(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    std::uint32_t prim;
    std::memcpy(&prim, &raw[4 * i + 3], 4);
    hits[i].t = raw[4 * i + 0];
    hits[i].b1 = raw[4 * i + 1];
    hits[i].b2 = raw[4 * i + 2];
    const bool triangle = prim != RayHit::kNoHit && primType(prim) == WT_PRIM_TRIANGLE;
    const std::uint32_t instance = prim != RayHit::kNoHit ? instances[i] : RayHit::kNoHit;
    hits[i].triangle = triangle ? m_scene->sceneTriangle(prim, instance) : RayHit::kNoHit;
    hits[i].prim = triangle ? hits[i].triangle : m_scene->scenePrimitive(prim, instance);
    hits[i].instance = instance;
    // a mirroring copy's corners 1 and 2 are its geometry's 2 and 1
    if (triangle && instance != RayHit::kNoHit && m_scene->instanceMirrored(instance)) std::swap(hits[i].b1, hits[i].b2);
  }
  return hits;
}

std::vector<std::uint8_t> Tracer::traceOccluded(std::span<const Ray> rays, Traversal traversal) {
  uploadRays(rays);
  if (traversal == Traversal::kPacket)
    run(m_occludedPacket, rays.size(), traversal);
  else if (traversal == Traversal::kStream)
    run(m_occludedStream, rays.size(), traversal);
  else
    run(m_occluded, rays.size(), traversal);
  std::vector<cl_uint> raw(rays.size());
  if (!rays.empty())
    m_context.queue().enqueueReadBuffer(m_out, CL_TRUE, 0, raw.size() * 4, raw.data());
  return std::vector<std::uint8_t>(raw.begin(), raw.end());
}

}  // namespace wt
