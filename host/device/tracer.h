// Ray batches traced outside the wavefront loop: the interface the traversal
// tests and the throughput benchmark use.
#pragma once

#include "device/context.h"
#include "device/scene_buffers.h"
#include "device/trace_params.h"
#include "scene/scene.h"

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

namespace wt {

struct Ray {
  glm::vec3 origin;
  float tmin = 0.0f;
  glm::vec3 direction;
  float tmax = 1e30f;
  /// the primitive the ray leaves (never hit at the ray's start): a scene
  /// triangle index, or a typed id (primId, host/geometry/primitives.h) of another type; or none
  std::uint32_t skip = 0xffffffffu;
};

struct RayHit {
  float t = 0.0f;
  float b1 = 0.0f, b2 = 0.0f;       ///< barycentrics of the triangle's v1 and v2
  std::uint32_t triangle = kNoHit;  ///< the scene's triangle index; kNoHit for a miss or another type
  std::uint32_t prim = kNoHit;      ///< what was hit: the scene's triangle index, or another type's typed id (primId)
  /// the instance (typed id, WT_PRIM_INSTANCE) whose copy of `triangle` (or
  /// of a sphere or curve: `prim` names the flattened scene's) was hit;
  /// kNoHit for a flat primitive or a miss
  std::uint32_t instance = kNoHit;
  static constexpr std::uint32_t kNoHit = 0xffffffffu;
};

/// How a batch is traced: one ray per work-item; packets of 8 or 16
/// consecutive rays per work-item (Tracer::packetWidth; kernels/bvh_packet.cl),
/// which pays on coherent rays (camera rays, shadow rays from neighbouring
/// pixels); or, for any-hit queries, streams of up to 64 rays that walk the
/// tree together (kernels/bvh_stream.cl), which pays on incoherent shadow
/// rays on CPUs (closest-hit queries given kStream are traced one by one).
/// All give the same answers; of two hits at exactly the same distance,
/// another may win.
enum class Traversal { kSingle, kPacket, kStream };

/// Whether streams ask for a node's children as it arrives (and keep their
/// rays' order instead of grouping them by octant): by the scene's size
/// against the device's cache (streamPrefetchFor), or always, or never.
enum class StreamPrefetch { kAuto, kOn, kOff };

/// How alike the directions of each packet's rays are: the mean, over the
/// packets of `width` consecutive rays, of the length of their unit
/// directions' mean. 1 when every packet's rays are parallel; about 0.33 for
/// directions drawn uniformly from the sphere (for packets of 8); 0 for no rays.
double packetCoherence(std::span<const Ray> rays, std::size_t width = 8);

/// What chooseTraversal reads off a batch, measured on a sample of its
/// packets of `width` consecutive rays (measureRays).
struct RayBatchStats {
  double coherence = 0.0;     ///< packetCoherence of the sampled packets
  double octantShare = 0.0;   ///< mean fraction of a packet's rays in the packet's most common direction octant
  double originSpread = 0.0;  ///< mean over packets of the RMS distance of the rays' origins from their mean, world units
  std::size_t packets = 0;    ///< packets sampled
};

/// The statistics of up to `maxPackets` packets of `width` consecutive
/// rays, spread evenly over the batch (a cost of O(maxPackets width), not of
/// the batch's size).
RayBatchStats measureRays(std::span<const Ray> rays, std::size_t width, std::size_t maxPackets = 2048);

/// Below this packetCoherence a packet's rays leave each other's boxes
/// within a few levels of the root, whatever their origins: no packets.
inline constexpr double kPacketMinCoherence = 0.95;
/// A packet's visit of one node costs about this many single-ray visits per
/// lane (its box tests run on all lanes, so the cost per visit grows with
/// the width): a packet that stays together costs this fraction of single
/// rays per ray, one that visits n leaf neighbourhoods n times it.
inline constexpr double kPacketLaneCost = 0.2;
/// Streams trace any-hit rays about this many times as fast as single rays
/// on a CPU, however incoherent (a node fetched once for all the rays in it).
inline constexpr double kStreamGain = 1.4;
/// A 4-wide tree's leaf box spans about this many primitive scales
/// (primitiveScale) of a surface: its leaves hold a few primitives
/// (bvh4Options).
inline constexpr double kLeafScales = 2.0;

/// The traversal for a batch with these statistics (auto), the cheapest per
/// ray by a cost model: a packet whose rays point nearly the same way
/// (kPacketMinCoherence) visits n = 1 + origin diameter / (kLeafScales
/// scale) leaf neighbourhoods at its origins, at n kPacketLaneCost single
/// visits per ray; single rays cost 1, streams (any hit, CPU) 1 /
/// kStreamGain. Camera rays (one origin, n = 1) always come out as packets;
/// random directions never do.
Traversal chooseTraversal(const RayBatchStats& stats, double scale, bool occlusion, bool cpu);

/// Timed trials of packets against single rays on the same kind of rays:
/// the faster is the one with the fastest trial. A trial that other work on
/// the machine interrupted says how busy the machine was, not how fast the
/// traversal is; the quickest of several is the least disturbed.
class TraversalTrials {
 public:
  /// A trial of `traversal` (kPacket or kSingle) that took `secondsPerRay`.
  void add(Traversal traversal, double secondsPerRay);
  /// The faster of the two once both have a trial; absent before.
  std::optional<Traversal> faster() const;
  /// Packets' fastest trial over single rays' (for the log); 0 before both ran.
  double packetRatio() const;

 private:
  std::array<double, 2> m_fastest{0.0, 0.0};  ///< [single, packet]; 0: no trial yet
};

class Tracer {
 public:
  /// packetWidth: rays per packet, 8 or 16; 0 picks by the device (packetWidthFor).
  Tracer(Context& context, const Scene& scene, const BvhBuildOptions& options = {}, int packetWidth = 0,
         StreamPrefetch prefetch = StreamPrefetch::kAuto);
  ~Tracer();

  std::vector<RayHit> traceClosest(std::span<const Ray> rays, Traversal traversal = Traversal::kSingle);
  std::vector<std::uint8_t> traceOccluded(std::span<const Ray> rays, Traversal traversal = Traversal::kSingle);

  const SceneBuffers& sceneBuffers() const { return *m_scene; }
  Context& context() const { return m_context; }
  /// Rays per packet of Traversal::kPacket on this device.
  int packetWidth() const { return m_packetWidth; }
  /// Whether this tracer's streams ask for a node's children early.
  bool streamPrefetch() const { return m_streamPrefetch; }
  /// The key of stochastic transparency's numbers (rng_alpha_key; alphaMode
  /// BLEND) for the next trace calls: ray i of a call draws from stream
  /// rng_alpha_ray(key, i), whichever the traversal. 0 until set.
  void setAlphaKey(std::uint32_t key) { m_alphaKey = key; }
  /// The scene's primitiveScale, for chooseTraversal.
  double primitiveScale() const { return m_scene->primitiveScale(); }
  /// chooseTraversal for these rays on this tracer's scene, device and packet width.
  Traversal chooseTraversal(std::span<const Ray> rays, bool occlusion) const;
  /// Kernel time of the last trace call (profiling events), seconds.
  double lastKernelSeconds() const { return m_lastKernelSeconds; }

 private:
  void uploadRays(std::span<const Ray> rays);
  /// Runs one of the five kernels over the uploaded rays; returns its kernel seconds.
  template <class Decl>
  void run(KernelArgs<Decl>& kernel, std::size_t rays, Traversal traversal);

  Context& m_context;
  std::unique_ptr<SceneBuffers> m_scene;
  int m_packetWidth = 8;
  bool m_streamPrefetch = false;
  bool m_alpha = false;  ///< the program has the alpha test (its kernels take WT_ALPHA_PARAMS)
  cl::Program m_program;
  KernelArgs<trace::Closest> m_closest;
  KernelArgs<trace::Occluded> m_occluded;
  KernelArgs<trace::ClosestPacket> m_closestPacket;
  KernelArgs<trace::OccludedPacket> m_occludedPacket;
  KernelArgs<trace::OccludedStream> m_occludedStream;
  cl::Buffer m_rayO, m_rayD, m_skip, m_out;
  cl::Buffer m_instances;  ///< per ray: in, the instance of the surface it leaves; out, the instance hit
  std::size_t m_capacity = 0;
  std::uint32_t m_alphaKey = 0;
  double m_lastKernelSeconds = 0.0;
};

}  // namespace wt
