// The wavefront scheduler: which stage runs when, the path-state and queue
// buffers, and the sample loop. One pass renders one sample per pixel:
// generate, then extend/shade per bounce until no path is alive, then
// accumulate.
#pragma once

#include "device/context.h"
#include "device/program.h"
#include "device/scene_buffers.h"
#include "render/feature_set.h"
#include "render/light_list.h"
#include "scene/environment.h"
#include "scene/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <memory>
#include <vector>

namespace wt {

enum class Integrator {
  Minimal,  ///< brute force (Falcor's MinimalPathTracer): emission at hits, environment on miss, one uniformly chosen analytic light per vertex; no MIS, no Russian roulette
  Path,     ///< next-event estimation towards every light by power, MIS, Russian roulette
};

struct RenderSettings {
  int width = 512;
  int height = 512;
  int samplesPerPixel = 64;
  int maxBounces = 8;       ///< hits shaded after the camera hit (0: direct view of emitters only)
  int maxDiffuseBounces = -1;       ///< diffuse (cosine-sampled) bounces a path may take; -1: maxBounces
  int maxSpecularBounces = -1;      ///< specular (GGX, mirror) bounces; -1: maxBounces
  int maxTransmissionBounces = -1;  ///< transmission (refraction, thin-walled) bounces; -1: maxBounces
  std::uint32_t seed = 0;
  float exposureStops = 0.0f;
  glm::vec3 background{0.0f};  ///< constant environment radiance seen by escaping paths (without environmentMap)
  std::string environmentMap;  ///< equirectangular .hdr/.exr lighting the scene (replaces background)
  float environmentIntensity = 1.0f;
  float environmentRotationDegrees = 0.0f;  ///< about +Y, counter-clockwise seen from above
  bool environmentHidden = false;  ///< camera rays see black where they escape; the environment still lights
  Integrator integrator = Integrator::Path;
  bool useNee = true;           ///< path: next-event estimation
  bool useMis = true;           ///< path: MIS between NEE and BSDF sampling
  bool powerHeuristic = false;  ///< path: power heuristic instead of balance
  bool useRussianRoulette = true;  ///< path
  int rrMinDepth = 3;           ///< path: first bounce at which roulette may end a path
  bool sobol = false;           ///< Owen-scrambled Sobol instead of independent random numbers
  bool textureFootprint = true;  ///< textures read at the mip level of the path's footprint (else the finest level)
  LightSampler lightSampler = LightSampler::Auto;  ///< path: how NEE picks among emissive triangles
  std::uint32_t accumulation = WT_ACCUMULATE_KAHAN;  ///< WT_ACCUMULATE_* (double needs fp64)
  BvhBuilder bvhBuilder = BvhBuilder::Auto;  ///< which tree the scene's BVH is (host/bvh/builders.h)
  Instancing instancing = Instancing::Off;   ///< whether repeated geometry is stored once (SceneBuffers)
  /// Camera rays and the shadow rays from their hits traced in packets of
  /// packetWidth neighbouring pixels (kernels/bvh_packet.cl); later
  /// bounces, incoherent, one ray per work-item. The same hits either way
  /// (of two at exactly the same distance, another may win).
  bool packets = true;
  int packetWidth = 0;  ///< rays per packet, 8 or 16; 0: by the device and the scene (packetWidthFor)
  /// Developer setting (--general-program): build every kernel switch on
  /// (generalKernelFeatures) instead of the scene's; the same image, for the
  /// specialised-vs-general tests and the bench.
  bool generalProgram = false;
#ifdef NDEBUG
  bool stopOnNonFinite = false;  ///< throw NonFiniteSampleError at the first NaN/Inf shade makes (on in debug builds)
#else
  bool stopOnNonFinite = true;
#endif
};

/// The first NaN/Inf of a render with RenderSettings::stopOnNonFinite: where
/// it arose. The sample it belongs to is not accumulated.
struct NonFiniteSampleError : std::runtime_error {
  NonFiniteSampleError(const std::string& what, int x, int y, int sample, int bounce)
      : std::runtime_error(what), x(x), y(y), sample(sample), bounce(bounce) {}
  int x, y;    ///< pixel, from the top left
  int sample;  ///< sample index
  int bounce;  ///< 0: the camera ray's hit
};

/// The accumulated image read back from the device.
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;              ///< linear radiance, per-pixel mean, row-major from the top
  std::vector<float> rgbVariance;      ///< per-pixel sample variance of the radiance (unbiased)
  std::vector<std::uint32_t> samples;  ///< samples folded into each pixel
  std::vector<std::uint8_t> srgba;     ///< tone-mapped 8-bit sRGB, alpha 255
};

struct RenderStats {
  int samplesDone = 0;
  std::uint64_t raysTraced = 0;       ///< extend rays (camera and bounce rays)
  std::uint64_t nonFiniteSamples = 0; ///< discarded NaN/Inf samples
  double seconds = 0.0;               ///< wall time in renderSample()
  double programSeconds = 0.0;        ///< building (or PoCL's cache loading) the program, in the constructor
};

class Renderer {
 public:
  Renderer(Context& context, const Scene& scene, const RenderSettings& settings);
  ~Renderer();

  /// Render and accumulate one more sample per pixel.
  void renderSample();
  /// Read the accumulated image (and tone-map it on the device).
  Image readImage();

  const RenderStats& stats() const { return m_stats; }
  const RenderSettings& settings() const { return m_settings; }
  const SceneBuffers& sceneBuffers() const { return *m_scene; }
  /// The light list NEE picks from (built from the scene at construction).
  const LightList& lights() const { return m_lights; }
  const Environment& environment() const { return m_environment; }
  /// What the scene and settings use (sceneFeatures), and the switches the
  /// program was built with.
  const FeatureSet& features() const { return m_features; }
  const KernelFeatures& kernelFeatures() const { return m_kernelFeatures; }

 private:
  [[noreturn]] void throwNonFinite(int sample, std::uint32_t path, std::uint32_t where);
  Context& m_context;
  RenderSettings m_settings;
  int m_packetWidth = 8;  ///< rays per packet (m_kernelFeatures.packetWidth)
  FeatureSet m_features;
  KernelFeatures m_kernelFeatures;
  WtCamera m_camera;
  std::unique_ptr<SceneBuffers> m_scene;
  cl::Program m_program;
  cl::Kernel m_generate, m_extend, m_extendPacket, m_shade, m_connect, m_connectPacket, m_accumulate, m_resolve,
      m_tonemap;
  LightList m_lights;
  Environment m_environment;
  cl::Buffer m_envTexels, m_envMarginal, m_envConditional;
  cl::Buffer m_lightBuffer, m_aliasBuffer, m_emitterPdfBuffer;
  cl::Buffer m_shadowQueue, m_shadowO, m_shadowD, m_shadowRadiance;
  cl::Buffer m_pbrTable, m_bounceCounts;
  cl::Buffer m_raySkip, m_shadowSkip;
  /// per path: the instance of its last hit (WT_NO_HIT: none), written by
  /// extend; its next rays leave (ray_skip or shadow_skip.x, this instance).
  /// One element when the scene has no instances (never read).
  cl::Buffer m_hitInstance;
  cl::Buffer m_rayCone;  ///< float2 per path: footprint spread so far, cone angle of its ray (materials/textured.cl)
  cl::Buffer m_lightTree, m_emitterLeaf, m_prevNormal;  ///< the triangle each ray leaves (and the emitter a shadow ray aims at): never hit
  // path state (structure of arrays, one entry per pixel)
  cl::Buffer m_rayO, m_rayD, m_hits, m_throughput, m_radiance;
  cl::Buffer m_queueA, m_queueB, m_counters;
  // accumulation
  cl::Buffer m_state, m_mean, m_m2, m_sampleCount, m_pixels;
  RenderStats m_stats;
};

}  // namespace wt
