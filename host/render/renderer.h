// The wavefront scheduler: which stage runs when, the path-state and queue
// buffers, and the sample loop. One pass renders one sample per pixel:
// generate, then extend/shade per bounce until no path is alive, then
// accumulate.
#pragma once

#include <array>

#include "core/zeroed_memory.h"
#include "device/context.h"
#include "device/program.h"
#include "device/scene_buffers.h"
#include "device/tracer.h"
#include "render/feature_set.h"
#include "render/path_state.h"
#include "render/stage_params.h"
#include "render/light_list.h"
#include "render/render_profile.h"
#include "render/tonemap.h"
#include "scene/environment.h"
#include "scene/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <memory>
#include <optional>
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
  float exposureStops = 0.0f;  ///< exposure compensation (PNG only): the image scaled by 2^stops
  TonemapSettings tonemap;     ///< operator, physical or auto exposure, white balance, dither (PNG only)
  glm::vec3 background{0.0f};  ///< constant environment radiance seen by escaping paths (without environmentMap)
  std::string environmentMap;  ///< equirectangular .hdr/.exr lighting the scene (replaces background)
  float environmentIntensity = 1.0f;
  float environmentRotationDegrees = 0.0f;  ///< about +Y, counter-clockwise seen from above
  bool environmentHidden = false;  ///< camera rays see black where they escape; the environment still lights
  Integrator integrator = Integrator::Path;
  bool useNee = true;           ///< path: next-event estimation
  bool useMis = true;           ///< path: MIS between NEE and BSDF sampling
  bool powerHeuristic = false;  ///< path: power heuristic instead of balance
  /// path, without powerHeuristic: the power heuristic at Lambertian vertices, balance elsewhere
  bool powerAtLambertian = true;
  bool useRussianRoulette = true;  ///< path
  int rrMinDepth = 3;           ///< path: first bounce at which roulette may end a path
  bool sobol = false;           ///< Owen-scrambled Sobol instead of independent random numbers
  bool textureFootprint = true;  ///< textures read at the mip level of the path's footprint (else the finest level)
  LightSampler lightSampler = LightSampler::Auto;  ///< path: how NEE picks among emissive triangles
  /// Developer setting (tests): the light list weighs an emitter with holes by
  /// its mean coverage (buildLightList); false: by its emission alone.
  bool lightCoverageWeights = true;
  /// Developer setting (A/B, tests): metallic-roughness materials that are
  /// exactly Lambertian rendered as the Lambertian model (kernelMaterial,
  /// the same image up to float rounding); false: by the general model.
  bool lambertianForms = true;
  /// Developer setting (A/B, tests): two emissive triangles that make a
  /// rectangle are one light, sampled by solid angle (findQuadLights); false:
  /// two triangle lights, as before.
  bool quadLights = true;
  /// Developer setting (A/B, tests): shade runs several paths per work-item on
  /// vector lanes where every surface is a triangle, Lambertian or plain
  /// metallic-roughness (KernelFeatures::shadeLanes); false: one path per work-item, as shade.cl.
  bool shadeLanes = true;
  int shadeLanesWidth = 0;  ///< developer setting: paths per lanes work-item, 8 or 16; 0: by the device (shadeLanesWidthFor)
  std::uint32_t accumulation = WT_ACCUMULATE_KAHAN;  ///< WT_ACCUMULATE_* (double needs fp64)
  BvhBuilder bvhBuilder = BvhBuilder::Auto;  ///< which tree the scene's BVH is (host/bvh/builders.h)
  Instancing instancing = Instancing::Off;   ///< whether repeated geometry is stored once (SceneBuffers)
  /// Camera rays traced in packets of packetWidth neighbouring pixels
  /// (kernels/bvh_packet.cl); each later bounce's closest hits in packets or
  /// one ray per work-item, whichever traced that bounce faster in timed
  /// trials of both (the second to fifth samples this renderer renders);
  /// each bounce's shadow rays as chooseTraversal (host/device/tracer.h) picks
  /// from a sample of them measured in the first sample: packets, streams
  /// (kernels/bvh_stream.cl) or one ray per work-item. false: every ray
  /// alone. The same hits either way (of two at exactly the same distance,
  /// another may win).
  bool packets = true;
  /// Developer setting (tests): with `packets`, every bounce's shadow rays
  /// traced this way instead of as chooseTraversal picks; nullopt: picked.
  std::optional<Traversal> shadowTraversal;
  /// Developer setting (tests): with `packets`, bounces after the first
  /// trace their closest hits this way (kPacket or kSingle) with no trials;
  /// nullopt: timed.
  std::optional<Traversal> extendTraversal;
  int packetWidth = 0;  ///< rays per packet, 8 or 16; 0: by the device and the scene (packetWidthFor)
  /// Developer setting (--general-program): build every kernel switch on
  /// (generalKernelFeatures) instead of the scene's; the same image, for the
  /// specialised-vs-general tests and the bench.
  bool generalProgram = false;
  /// The caller keeps the scene alive and unchanged as long as the renderer,
  /// so a CPU device reads the scene's texels in place (readOnlyBuffer).
  bool sceneOutlivesRenderer = false;
  /// Stages and buffers the scene and settings cannot use are neither
  /// allocated nor launched (the connect stage without light sampling);
  /// false runs and allocates them all, for tests that the image is the same.
  bool skipUnusedStages = true;
  /// Record the AOVs (Image::aovs, kernels/aov.cl): compiled in and their
  /// buffers allocated only when set.
  bool aovs = false;
  /// On a CPU device the per-pixel buffers are memory the renderer maps
  /// itself (ZeroedMemory: huge pages, CL_MEM_USE_HOST_PTR); false: the
  /// device allocates them, for the tests that the image is the same.
  bool hostPathMemory = true;
  /// With aovs: traversal counts the nodes each camera ray visits
  /// (Aovs::bvhCost; WT_BVH_COST, kernels compiled for the debug view only).
  /// Counted by single-ray traversal: camera rays are not traced in packets.
  bool bvhCost = false;
  /// Time every stage of every bounce from profiling events and count the
  /// shadow rays (Renderer::profile()): needs a Context made with profiling
  /// (else DeviceError); off, the renderer makes no events at all.
  bool profile = false;
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

/// Arbitrary output variables, per pixel, row-major from the top (empty
/// unless RenderSettings::aovs). Albedo and normal are a denoiser's guides:
/// those of the first hit that is no perfect mirror or smooth glass, the
/// environment's radiance (albedo) and a zero normal where the path escapes
/// first; averaged over the samples. Depth, position and uv average the
/// samples whose camera ray hit (depth infinity, position and uv 0 where
/// none did); the ids are the first sample's (kNoId: a miss).
struct Aovs {
  static constexpr std::uint32_t kNoId = 0xffffffffu;
  std::vector<float> albedo;    ///< rgb
  std::vector<float> normal;    ///< xyz, world space, shading normal facing the camera (not renormalised)
  std::vector<float> depth;     ///< distance along the camera ray to its hit
  std::vector<float> position;  ///< xyz, world space
  std::vector<float> uv;        ///< TEXCOORD_0 of the camera hit (barycentrics without one)
  std::vector<float> bounces;   ///< surfaces the path hit, mean over samples
  std::vector<float> bvhCost;   ///< triangle-tree nodes the camera ray visited, mean over samples (0 without RenderSettings::bvhCost)
  std::vector<std::uint32_t> material;   ///< material index
  std::vector<std::uint32_t> instance;   ///< instance index (kNoId: geometry not instanced)
  std::vector<std::uint32_t> primitive;  ///< typed primitive id of the hit (its geometry's, for an instance)
  bool empty() const { return albedo.empty(); }
};

/// The accumulated image read back from the device.
struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;              ///< linear radiance, per-pixel mean, row-major from the top
  std::vector<float> rgbVariance;      ///< per-pixel sample variance of the radiance (unbiased)
  std::vector<std::uint32_t> samples;  ///< samples folded into each pixel
  std::vector<std::uint8_t> srgba;     ///< tone-mapped 8-bit sRGB, alpha 255
  Aovs aovs;                           ///< with RenderSettings::aovs
  int samplesDone = 0;                 ///< the render's sample count (an EXR records it); 0: unknown
};

/// The AOV images of `pixels` pixels from their device sums (kAovSumBytes
/// per pixel: kernels/aov.cl's 16 floats) and ids (kAovIdBytes per pixel).
Aovs decodeAovs(const float* sums, const std::uint32_t* ids, std::size_t pixels);

/// The running accumulation exactly as the device holds it: what a
/// checkpoint saves and a resume restores (host/render/checkpoint.h).
struct Accumulation {
  int samplesDone = 0;                   ///< sample passes folded in (the next pass's sample index)
  std::uint64_t nonFiniteSamples = 0;    ///< NaN/Inf samples discarded so far
  std::vector<std::uint8_t> state;       ///< kAccumulationStateBytes per pixel (accumulate.cl's state)
  std::vector<std::uint32_t> samples;    ///< samples folded into each pixel
  /// With RenderSettings::aovs: the AOV sums (kAovSumBytes per pixel, all
  /// pixels) then the first sample's ids (kAovIdBytes per pixel); else empty.
  std::vector<std::uint8_t> aovs;
};

/// Bytes of accumulation state per pixel (PathState::state: float4[4]).
constexpr std::size_t kAccumulationStateBytes = 64;
/// Bytes of AOV accumulation per pixel: PathState::aovAccum (float4[4]) and aovIds (uint4).
constexpr std::size_t kAovSumBytes = 64, kAovIdBytes = 16;

struct RenderStats {
  int samplesDone = 0;
  std::uint64_t raysTraced = 0;       ///< extend rays (camera and bounce rays)
  std::uint64_t nonFiniteSamples = 0; ///< discarded NaN/Inf samples
  double seconds = 0.0;               ///< wall time in renderSample()
  double programSeconds = 0.0;        ///< building (or PoCL's cache loading) the program, in the constructor
  // the rest of the constructor, for the start-up timeline (render -v)
  double sceneSeconds = 0.0;    ///< scene buffers: BVH build and upload
  double lightsSeconds = 0.0;   ///< environment, light list and feature set
  double kernelsSeconds = 0.0;  ///< the kernels made from the program and checked against their declarations
  double buffersSeconds = 0.0;  ///< path state, light and environment buffers: allocated, uploaded, cleared
};

class Renderer {
 public:
  Renderer(Context& context, const Scene& scene, const RenderSettings& settings);
  ~Renderer();

  /// Render and accumulate one more sample per pixel.
  void renderSample();
  /// How bounce `bounce`'s shadow rays are traced: chosen in the first
  /// sample from a sample of them (chooseTraversal); nullopt before it, past
  /// maxBounces, or where the traversal is not chosen (packets off, the
  /// bvh-cost view, no connect stage).
  std::optional<Traversal> shadowTraversal(int bounce) const {
    return bounce >= 0 && std::size_t(bounce) < m_shadowTraversal.size() ? m_shadowTraversal[std::size_t(bounce)]
                                                                          : std::nullopt;
  }
  /// How bounce `bounce`'s closest hits are traced once the trials have
  /// decided (kPacket or kSingle); nullopt before, for bounce 0 (always
  /// packets), or where packets are off.
  std::optional<Traversal> extendTraversal(int bounce) const {
    return bounce > 0 && std::size_t(bounce) < m_extendTraversal.size() ? m_extendTraversal[std::size_t(bounce)]
                                                                         : std::nullopt;
  }
  /// Read the accumulated image (and tone-map it on the device).
  Image readImage();
  /// The mean, variance and sample counts only (no tone mapping, srgba
  /// left empty): the cheaper read the halting criteria make.
  Image readRadiance();
  /// The tone-mapped 8-bit pixels and the per-pixel counts only (rgb and
  /// its variance left empty): all a PNG needs, a quarter of the bytes.
  Image readDisplayImage();
  /// The running accumulation, for a checkpoint.
  Accumulation saveAccumulation();
  /// Continue from a saved accumulation of the same scene and settings:
  /// the next pass renders sample `saved.samplesDone`. Throws
  /// std::invalid_argument when its size is not this image's.
  void restoreAccumulation(const Accumulation& saved);
  /// Start an empty accumulation whose next pass renders sample
  /// `nextSample`: a chunk of a render split over devices or processes
  /// (render/distributed.h).
  void resetAccumulation(int nextSample);
  const RenderStats& stats() const { return m_stats; }
  /// Paths per bounce, and with RenderSettings::profile the stage times.
  const RenderProfile& profile() const { return m_profile; }
  const RenderSettings& settings() const { return m_settings; }
  const SceneBuffers& sceneBuffers() const { return *m_scene; }
  /// The light list NEE picks from (built from the scene at construction).
  const LightList& lights() const { return m_lights; }
  const Environment& environment() const { return m_environment; }
  /// What the scene and settings use (sceneFeatures), and the switches the
  /// program was built with (also the checkpoint's identity).
  const FeatureSet& features() const { return m_features; }
  const KernelFeatures& kernelFeatures() const { return m_kernelFeatures; }
  /// The wavefront passes after the camera's a sample may take: maxBounces,
  /// and WT_MAX_FALSE_HITS more where paths may pass false hits of nested
  /// dielectrics, which are no bounces (kernels/shared/media.h).
  int passLimit() const;
  /// Bytes of the per-pixel buffers (PathState) on the device.
  std::size_t pathStateBytes() const { return m_path.bytes; }
  /// The scale auto exposure gave the last readImage() (1 without it).
  float autoExposure() { return m_settings.tonemap.autoExposure ? m_tonemapper.autoExposure() : 1.0f; }

 private:
  /// Resolve the accumulation state into mean and m2, and read the per-pixel
  /// counts into `image`, with mean and m2 where `floats`, the 8-bit pixels where `tonemap`.
  void readResolved(Image& image, bool tonemap, bool floats = true);
  void readAovs(Image& image);
  [[noreturn]] void throwNonFinite(int sample, std::uint32_t path, std::uint32_t where);
  Context& m_context;
  RenderSettings m_settings;
  int m_packetWidth = 8;  ///< rays per packet (m_kernelFeatures.packetWidth)
  FeatureSet m_features;
  KernelFeatures m_kernelFeatures;
  WtCamera m_camera;
  cl_uint4 m_cameraMedia{};  ///< the medium stack every path starts with (cameraMediaStack)
  std::unique_ptr<SceneBuffers> m_scene;
  cl::Program m_program;
  cl::Program m_frameProgram;  ///< accumulate and tonemap (buildFrameProgram), shared by every feature set
  KernelArgs<stage::Generate> m_generate;
  KernelArgs<stage::Extend> m_extend;
  KernelArgs<stage::ExtendPacket> m_extendPacket;
  KernelArgs<stage::Shade> m_shade;
  KernelArgs<stage::Connect> m_connect;
  KernelArgs<stage::ConnectPacket> m_connectPacket;
  KernelArgs<stage::ConnectStream> m_connectStream;
  /// How each bounce's shadow rays are traced (m_settings.packets), chosen
  /// from a sample of them in the first sample (probeShadowRays); absent
  /// until then. Packets only where shade appends them densely.
  std::vector<std::optional<Traversal>> m_shadowTraversal;
  /// Each later bounce's extend traversal (m_settings.packets): packets and
  /// single rays alternate over kExtendTrials samples after the first, each
  /// bounce's extend timed (seconds per ray, m_extendTrials[bounce]); then
  /// the one with the fastest trial is kept. Absent until decided.
  static constexpr int kExtendTrials = 6;
  std::vector<std::optional<Traversal>> m_extendTraversal;
  std::vector<TraversalTrials> m_extendTrials;
  int m_samplesRendered = 0;  ///< samples this renderer has rendered (the trials count them, not the sample index)
  double m_primitiveScale = 1.0;  ///< primitiveScale of the scene, for chooseTraversal
  /// chooseTraversal for bounce `bounce`'s queued shadow rays (counters read back).
  Traversal probeShadowRays(int bounce);
  KernelArgs<stage::Accumulate> m_accumulate;
  KernelArgs<stage::Resolve> m_resolve;
  Tonemapper m_tonemapper;
  /// Launch a stage whose every argument is set (else DeviceError naming it).
  /// `event`: its profiling event (RenderSettings::profile).
  template <class Decl>
  void launch(KernelArgs<Decl>& k, std::size_t count, cl::Event* event = nullptr) {
    k.requireBound();
    m_context.launch(Decl::kName.data(), k.kernel(), count, Context::kLocalSize, event);
    ++m_profile.kernelLaunches;
  }
  /// Whether shade can queue shadow rays, so connect and its buffers exist.
  bool m_connectStage = true;
  /// The accumulation state and sample counts were never written (the first
  /// fold writes them whole: WT_FLAG_BLANK_ACCUMULATION).
  bool m_accumulationBlank = true;
  /// Zero the accumulation where it was never written, before it is read.
  void writeBlankAccumulation();
  LightList m_lights;
  Environment m_environment;
  cl::Buffer m_envTexels, m_envMarginal, m_envConditional;
  cl::Buffer m_lightBuffer, m_aliasBuffer, m_emitterPdfBuffer;
  cl::Buffer m_pbrTable;
  cl::Buffer m_lightTree, m_emitterLeaf, m_emitterQuad;
  /// The memory m_path's buffers are (RenderSettings::hostPathMemory), unmapped after them.
  std::unique_ptr<ZeroedMemory> m_pathMemory;
  PathState m_path;      ///< per pixel: path state, queues, shadow rays, accumulation
  cl::Buffer m_counters;  ///< WT_COUNTER_*
  RenderStats m_stats;
  RenderProfile m_profile;
};

/// The render program's switches for a scene's feature set on a device
/// (what `wavetrace info` prints and the Renderer builds); `lights` decides
/// which light kinds shade samples (setLightFeatures).
KernelFeatures renderKernelFeatures(const FeatureSet& features, const DeviceInfo& device, const RenderSettings& settings,
                                    const SceneBuffers& buffers, const LightList& lights);

/// The `count` lowest of a dense shadow queue's path indices, ascending:
/// the same whatever order the device's threads appended them in.
std::vector<std::uint32_t> shadowProbeEntries(std::vector<std::uint32_t> queue, std::size_t count);

}  // namespace wt
