#include "render/renderer.h"

#include "core/log.h"
#include "device/program.h"
#include "device/scene_args.h"
#include "render/camera_media.h"
#include "render/material_tables.h"
#include "shared/media.h"
#include "shared/rng.h"

#include <algorithm>
#include <chrono>
#include <type_traits>
#include <cmath>

namespace wt {
namespace {

WtFrameParams frameParams(const RenderSettings& s, const LightList& lights, int sample, int bounce) {
  WtFrameParams p{};
  p.width = cl_uint(s.width);
  p.height = cl_uint(s.height);
  p.sample = cl_uint(sample);
  p.bounce = cl_uint(bounce);
  p.max_bounces = cl_uint(s.maxBounces);
  auto lobeLimit = [&](int limit) { return cl_uint(limit < 0 ? s.maxBounces : std::min(limit, s.maxBounces)); };
  p.max_diffuse_bounces = lobeLimit(s.maxDiffuseBounces);
  p.max_specular_bounces = lobeLimit(s.maxSpecularBounces);
  p.max_transmission_bounces = lobeLimit(s.maxTransmissionBounces);
  p.seed = s.seed;
  p.exposure = exposureScale(s.tonemap, s.exposureStops);
  p.light_count = lights.sampleable ? cl_uint(lights.alias.size()) : 0u;
  p.analytic_count = lights.analyticCount;
  p.env_pmf = lights.environmentPmf;
  p.rr_min_depth = cl_uint(std::max(0, s.rrMinDepth));
  if (s.integrator == Integrator::Path) {
    p.flags = (s.useNee ? WT_FLAG_NEE : 0u) | (s.useMis ? WT_FLAG_MIS : 0u) |
              (s.powerHeuristic ? WT_FLAG_POWER_HEURISTIC : 0u) | (s.powerAtLambertian ? WT_FLAG_POWER_LAMBERTIAN : 0u) |
              (s.useRussianRoulette ? WT_FLAG_RR : 0u);
  }
  if (s.sobol) p.flags |= WT_FLAG_SOBOL;
  if (s.textureFootprint) p.flags |= WT_FLAG_TEXTURE_FOOTPRINT;
  p.accumulate_mode = s.accumulation;
  if (s.environmentHidden) p.flags |= WT_FLAG_ENV_HIDDEN;
  if (s.stopOnNonFinite) p.flags |= WT_FLAG_CHECK_NONFINITE;
  return p;
}

}  // namespace

Renderer::Renderer(Context& context, const Scene& scene, const RenderSettings& settings)
    : m_context(context), m_settings(settings) {
  auto phase = std::chrono::steady_clock::now();
  // seconds since the previous call (or the constructor's start)
  auto lap = [&phase]() {
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - phase).count();
    phase = now;
    return seconds;
  };
  CameraDesc desc = scene.camera ? *scene.camera : defaultCamera(scene.bounds());
  m_camera = makeCamera(desc, settings.width, settings.height);
  BvhBuildOptions bvhOptions;
  bvhOptions.builder = settings.bvhBuilder;
  bvhOptions.maxLeafSize = 0;  // leaves of up to kBvh4MaxLeafSize, chosen by the collapse
  bvhOptions.instancing = settings.instancing;
  bvhOptions.allSurfaceAttributes = settings.generalProgram;
  bvhOptions.texelsInPlace = settings.sceneOutlivesRenderer;
  bvhOptions.lambertianForms = settings.lambertianForms;
  m_scene = std::make_unique<SceneBuffers>(context, scene, bvhOptions);
  m_stats.sceneSeconds = lap();
  m_environment = settings.environmentMap.empty()
                      ? constantEnvironment(settings.background)
                      : loadEnvironmentMap(settings.environmentMap, settings.environmentIntensity,
                                           settings.environmentRotationDegrees);
  double envLum = m_environment.meanLuminance;
  m_lights = buildLightList(scene, *m_scene, envLum > 0.0 ? environmentPowerEstimate(scene, envLum) : 0.0,
                            settings.lightSampler, settings.lightCoverageWeights, settings.quadLights);

  m_features = sceneFeatures(scene, *m_scene, settings);
  m_kernelFeatures = renderKernelFeatures(m_features, context.info(), settings, *m_scene, m_lights);
  m_packetWidth = m_kernelFeatures.packetWidth;
  m_primitiveScale = m_scene->primitiveScale();
  {
    // the volumes the camera is inside, found on the host once (Cycles finds them too; Mitsuba asks the scene)
    WtMediaStack stack;
    for (wt_uint& id : stack.id) id = WT_MEDIUM_NONE;
    if (m_kernelFeatures.transmission) stack = cameraMediaStack(scene, glm::vec3(m_camera.origin.x, m_camera.origin.y, m_camera.origin.z));
    for (int k = 0; k < WT_MEDIA_STACK; ++k) m_cameraMedia.s[k] = stack.id[k];
  }
  m_shadowTraversal.assign(std::size_t(passLimit()) + 1, std::nullopt);
  m_extendTraversal.assign(std::size_t(passLimit()) + 1, std::nullopt);
  m_extendTrials.assign(std::size_t(passLimit()) + 1, TraversalTrials{});
  const KernelFeatures& features = m_kernelFeatures;
  m_stats.lightsSeconds = lap();
  m_program = buildProgram(context, features);
  m_frameProgram = buildFrameProgram(context, features.aov);
  m_stats.programSeconds = lap();
  if (settings.accumulation == WT_ACCUMULATE_DOUBLE && !context.info().fp64)
    throw DeviceError("double-precision accumulation needs fp64, which '" + context.info().name + "' lacks");
  // the feature set found the light list's rectangles (findQuadLights both times)
  if (m_lights.quadLights > 0 && !features.quadLights)
    throw std::logic_error("the light list has rectangle lights the program was built without");
  KernelFeatures lightKinds;
  setLightFeatures(lightKinds, m_lights);
  if ((lightKinds.lightTree && !features.lightTree) || (lightKinds.otherLights && !features.otherLights))
    throw std::logic_error("the light list has light kinds the program was built without");
  const ParamFeatures built{features.alpha, features.pbr && features.transmission && features.thinShadows,
                            features.quadLights};
  m_generate = {m_program, built};
  m_extend = {m_program, built};
  m_extendPacket = {m_program, built};
  m_shade = {m_program, built};
  m_connect = {m_program, built};
  m_connectPacket = {m_program, built};
  m_connectStream = {m_program, built};
  m_accumulate = {m_frameProgram, built};
  m_resolve = {m_frameProgram, built};
  m_tonemapper = Tonemapper(context, m_frameProgram, built, std::size_t(settings.width) * std::size_t(settings.height));
  m_stats.kernelsSeconds = lap();

  // connect runs only where shade can queue shadow rays: the same count of
  // lights shade's next-event estimation draws from
  const WtFrameParams first = frameParams(settings, m_lights, 0, 0);
  const cl_uint neeCount = features.integratorMinimal ? first.analytic_count
                                                      : ((first.flags & WT_FLAG_NEE) ? first.light_count : 0u);
  m_connectStage = neeCount > 0 || !settings.skipUnusedStages;
  if (settings.profile && !context.profiling())
    throw DeviceError("a profiled render needs a device queue made with profiling (Context(device, true))");

  std::size_t pixels = std::size_t(settings.width) * std::size_t(settings.height);
  cl::Context& ctx = context.context();
  PathNeeds needs;
  needs.shadows = m_connectStage;
  needs.instances = features.primitives[WT_PRIM_INSTANCE];
  needs.textures = features.textures;
  needs.aovs = settings.aovs;
  needs.media = features.transmission;
  needs.thinShadows = built.thinShadows;
  // a CPU device's kernels address host memory: the path state is pages
  // mapped here, faulted in by the huge page where the system allows (not
  // under Oclgrind, which takes CL_MEM_USE_HOST_PTR contents as never written)
  if (settings.hostPathMemory && context.info().isCpu && !context.underOclgrind()) {
    auto memory = std::make_unique<ZeroedMemory>(PathState::hostBytes(pixels, needs));
    if (memory->data()) m_pathMemory = std::move(memory);
  }
  m_path.allocate(ctx, pixels, needs, m_pathMemory ? m_pathMemory->data() : nullptr);
  m_counters = cl::Buffer(ctx, CL_MEM_READ_WRITE, WT_COUNTER_COUNT * sizeof(cl_uint));
  auto upload = [&](const auto& data) {
    using T = typename std::decay_t<decltype(data)>::value_type;
    std::size_t bytes = std::max<std::size_t>(data.size(), 1) * sizeof(T);
    cl::Buffer b(ctx, CL_MEM_READ_ONLY, bytes);
    if (!data.empty()) context.queue().enqueueWriteBuffer(b, CL_TRUE, 0, data.size() * sizeof(T), data.data());
    return b;
  };
  m_pbrTable = upload(pbrAlbedoTable());
  m_lightBuffer = upload(m_lights.lights);
  m_aliasBuffer = upload(m_lights.alias);
  m_emitterPdfBuffer = upload(m_lights.emitterPdfArea);
  m_lightTree = upload(m_lights.tree);
  m_emitterLeaf = upload(m_lights.emitterLeaf);
  if (built.quadLights) m_emitterQuad = upload(m_lights.emitterQuad);
  EnvironmentUpload env = environmentUpload(m_environment);
  // m_environment is the renderer's own and never changes: read in place where the device can
  auto uploadSpan = [&](auto span) { return readOnlyBuffer(context, span.data(), span.size_bytes(), true); };
  m_envTexels = uploadSpan(env.texels);
  m_envMarginal = uploadSpan(env.marginalCdf);
  m_envConditional = uploadSpan(env.conditionalCdf);

  cl::CommandQueue& q = context.queue();
  // the state and sample counts are left unwritten: the first fold writes them
  // (WT_FLAG_BLANK_ACCUMULATION), a read before it clears them (writeBlankAccumulation)
  if (settings.aovs) context.fill(m_path.aovAccum, 0u, 0, pixels * 64);
  context.fill(m_counters, 0u, 0, WT_COUNTER_COUNT * sizeof(cl_uint));
  context.fill(m_counters, 0xffffffffu, WT_COUNTER_FIRST_NONFINITE * sizeof(cl_uint), sizeof(cl_uint));
  q.finish();
  m_stats.buffersSeconds = lap();

  // Arguments that never change, by name; per-launch ones are set in
  // renderSample() and readImage(). The path state binds itself to every
  // parameter named after one of its buffers.
  m_path.bind(m_generate);
  m_generate.set("queue", m_path.queueA).set("counters", m_counters);

  // extend and connect (and their packet forms) trace against the same scene
  auto bindTracing = [&](auto& k) {
    m_path.bind(k);
    k.set("counters", m_counters)
        .set("nodes", m_scene->nodes)
        .set("node_count", m_scene->nodeCount)
        .set("tri_verts", m_scene->triVerts);
    bindGeometry(k, *m_scene);
    if (features.alpha) bindAlpha(k, *m_scene);
  };
  bindTracing(m_extend);
  bindTracing(m_extendPacket);

  m_path.bind(m_shade);
  m_shade.set("environment", m_environment.header)
      .set("env_texels", m_envTexels)
      .set("env_marginal_cdf", m_envMarginal)
      .set("env_conditional_cdf", m_envConditional)
      .set("counters", m_counters)
      .set("tri_info", m_scene->triangleInfo)
      .set("tri_verts", m_scene->triVerts)
      .set("normals", m_scene->normals)
      .set("materials", m_scene->materials)
      .set("lights", m_lightBuffer)
      .set("alias", m_aliasBuffer)
      .set("emitter_pdf_area", m_emitterPdfBuffer)
      .set("pbr_table", m_pbrTable)
      .set("light_tree", m_lightTree)
      .set("emitter_leaf", m_emitterLeaf);
  if (built.quadLights) m_shade.set("emitter_quad", m_emitterQuad);
  bindGeometry(m_shade, *m_scene);
  bindSurface(m_shade, *m_scene);

  bindTracing(m_connect);
  bindTracing(m_connectPacket);
  bindTracing(m_connectStream);
  // connect weighs the thin walls a shadow ray crosses by their materials where it meets them
  if (built.thinShadows) {
    auto bindWalls = [&](auto& k) {
      k.set("thin_materials", m_scene->materials)
          .set("thin_tri_info", m_scene->triangleInfo)
          .set("thin_normals", m_scene->normals)
          .set("thin_pbr_table", m_pbrTable)
          .set("thin_vertex_uv", m_scene->vertexUv)
          .set("thin_vertex_color", m_scene->vertexColor)
          .set("thin_vertex_tangent", m_scene->vertexTangent)
          .set("thin_material_textures", m_scene->materialTextures)
          .set("thin_textures", m_scene->textures)
          .set("thin_texture_levels", m_scene->textureLevels)
          .set("thin_texels", m_scene->texels);
    };
    bindWalls(m_connect);
    bindWalls(m_connectPacket);
    bindWalls(m_connectStream);
  }

  m_path.bind(m_accumulate);
  m_accumulate.set("counters", m_counters);
  m_path.bind(m_resolve);
}

Renderer::~Renderer() {
  // commands still queued may write the path state: done before its memory is unmapped
  if (m_pathMemory) {
    try {
      m_context.queue().finish();
    } catch (const cl::Error&) {
      // a failed queue runs nothing more
    }
  }
}

namespace {

/// What a profiled command was (RenderSettings::profile).
enum class Command : std::uint8_t { Generate, Extend, Shade, Connect, Accumulate, Transfer, ProfileRead };
struct TimedCommand {
  Command command;
  int bounce;
  cl::Event event;
};

/// Elements [first, first + count) of a buffer mapped for reading, unmapped on leaving.
template <class T>
class MappedRead {
 public:
  MappedRead(cl::CommandQueue& q, const cl::Buffer& buffer, std::size_t first, std::size_t count)
      : m_queue(q), m_buffer(buffer),
        m_data(static_cast<const T*>(
            q.enqueueMapBuffer(buffer, CL_TRUE, CL_MAP_READ, first * sizeof(T), count * sizeof(T)))) {}
  MappedRead(const MappedRead&) = delete;
  MappedRead& operator=(const MappedRead&) = delete;
  ~MappedRead() {
    try {
      m_queue.enqueueUnmapMemObject(m_buffer, const_cast<T*>(m_data));
    } catch (const cl::Error&) {
      // a failed unmap leaves the mapping; the next command reports the device's state
    }
  }
  const T* data() const { return m_data; }

 private:
  cl::CommandQueue& m_queue;
  const cl::Buffer& m_buffer;
  const T* m_data;
};

}  // namespace

KernelFeatures renderKernelFeatures(const FeatureSet& features, const DeviceInfo& device, const RenderSettings& settings,
                                    const SceneBuffers& buffers, const LightList& lights) {
  KernelFeatures k = settings.generalProgram ? generalKernelFeatures(features, device, settings.packetWidth)
                                             : kernelFeaturesFor(features, device, settings.packetWidth);
  if (!settings.generalProgram) setLightFeatures(k, lights);
  k.aov = settings.aovs;
  k.bvhCost = settings.aovs && settings.bvhCost;
  // shade on vector lanes where every surface is a triangle, Lambertian or
  // metallic-roughness without extensions but transmission, whose paths the
  // lanes shade one at a time (kernels/shade_lanes.cl; its misses read
  // triangle 0, so there must be one)
  k.shadeLanes = settings.shadeLanes && !settings.generalProgram && buffers.storedTriangles() > 0 &&
                 !k.integratorMinimal &&
                 !k.thinShadows && !k.specular && !k.clearcoat && !k.sheen && !k.anisotropy && !k.iridescence &&
                 !k.textures && !k.vertexColors && !k.alpha && !k.aov &&
                 std::none_of(k.primitives.begin(), k.primitives.end(), [](bool on) { return on; });
  if (k.shadeLanes) k.shadeLanesWidth = shadeLanesWidthFor(device, settings.shadeLanesWidth);
  // streams ask for a node's children early where the scene outgrows the cache (as the Tracer's)
  k.streamPrefetch = streamPrefetchFor(device, buffers.uploadedBytes);
  return k;
}

std::vector<std::uint32_t> shadowProbeEntries(std::vector<std::uint32_t> queue, std::size_t count) {
  if (queue.size() > count) {
    std::nth_element(queue.begin(), queue.begin() + std::ptrdiff_t(count), queue.end());
    queue.resize(count);
  }
  std::sort(queue.begin(), queue.end());
  return queue;
}

Traversal Renderer::probeShadowRays(int bounce) {
  // Up to kProbeRays of the paths with a shadow ray, lowest path index first:
  // the dense queue holds them in the order the device's threads appended
  // them, which varies from run to run, so the whole queue is read and the
  // lowest entries taken; neighbouring paths keep the span read near the
  // sample's size.
  constexpr std::size_t kProbeRays = 16384;
  cl::CommandQueue& q = m_context.queue();
  cl_uint count = 0;
  q.enqueueReadBuffer(m_counters, CL_TRUE, WT_COUNTER_SHADOW * sizeof(cl_uint), sizeof(cl_uint), &count);
  if (count == 0) return Traversal::kSingle;
  // mapped, not copied: on a CPU device a map is the buffer itself, and the
  // probe reads only the rays it keeps
  MappedRead<cl_uint> entries(q, m_path.shadowQueue, 0, count);
  std::vector<cl_uint> queue = shadowProbeEntries(std::vector<cl_uint>(entries.data(), entries.data() + count), kProbeRays);
  // a sample of paths no more than 16 times its size apart: fewer entries where they spread
  std::size_t n = queue.size();
  cl_uint lo = 0, hi = 0;
  for (;;) {
    lo = *std::min_element(queue.begin(), queue.begin() + std::ptrdiff_t(n));
    hi = *std::max_element(queue.begin(), queue.begin() + std::ptrdiff_t(n));
    if (std::size_t(hi - lo) < 16 * kProbeRays || n <= 64) break;
    n /= 2;
  }
  MappedRead<cl_float4> o(q, m_path.shadowO, lo, std::size_t(hi - lo) + 1);
  MappedRead<cl_float4> d(q, m_path.shadowD, lo, std::size_t(hi - lo) + 1);
  std::vector<Ray> rays(n);
  for (std::size_t i = 0; i < n; ++i) {
    const cl_float4 &ro = o.data()[queue[i] - lo], &rd = d.data()[queue[i] - lo];
    rays[i].origin = glm::vec3(ro.s[0], ro.s[1], ro.s[2]);
    rays[i].tmin = ro.s[3];
    rays[i].direction = glm::vec3(rd.s[0], rd.s[1], rd.s[2]);
    rays[i].tmax = rd.s[3];
  }
  const RayBatchStats stats = measureRays(rays, std::size_t(m_packetWidth));
  const Traversal choice = chooseTraversal(stats, m_primitiveScale, true, m_context.info().isCpu);
  log::debug("shadow rays of bounce " + std::to_string(bounce) + ": coherence " + std::to_string(stats.coherence) +
             ", origin spread " + std::to_string(stats.originSpread / m_primitiveScale) + " primitive scales: " +
             (choice == Traversal::kPacket ? "packets" : choice == Traversal::kStream ? "streams" : "single rays"));
  return choice;
}

int Renderer::passLimit() const {
  return std::max(m_settings.maxBounces, 0) + (m_kernelFeatures.transmission ? int(WT_MAX_FALSE_HITS) : 0);
}

void Renderer::renderSample() {
  auto start = std::chrono::steady_clock::now();
  const int sample = m_stats.samplesDone;
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  cl::CommandQueue& q = m_context.queue();
  // profiled: every command's event, in queue order; otherwise no events at all
  const bool profile = m_settings.profile;
  std::vector<TimedCommand> timed;
  auto event = [&](Command c, int bounce) -> cl::Event* {
    if (!profile) return nullptr;
    timed.push_back({c, bounce, {}});
    return &timed.back().event;
  };
  auto fill = [&](cl_uint word, std::size_t slot, int bounce) {
    m_context.fill(m_counters, word, slot * sizeof(cl_uint), sizeof(cl_uint), event(Command::Transfer, bounce));
    ++m_profile.fills;
  };
  double hostWait = 0.0;
  std::vector<std::pair<int, std::vector<cl_uint>>> shadowEntries;  // profiled: each bounce's shadow queue

  // generate: every pixel's path enters queue A
  m_generate.set("frame", frameParams(m_settings, m_lights, sample, 0))
      .set("camera", m_camera)
      .set("camera_media", m_cameraMedia);
  launch(m_generate, pixels, event(Command::Generate, 0));

  cl::Buffer* queueIn = &m_path.queueA;
  cl::Buffer* queueOut = &m_path.queueB;
  cl_uint inSlot = WT_COUNTER_QUEUE_A, outSlot = WT_COUNTER_QUEUE_B;
  std::size_t alive = pixels;
  // a pass per bounce, and with nested dielectrics up to WT_MAX_FALSE_HITS
  // more for paths that passed false hits (no bounces: shared/media.h)
  const int passes = passLimit();
  for (int bounce = 0; bounce <= passes && alive > 0; ++bounce) {
    m_stats.raysTraced += alive;
    if (m_profile.bounces.size() <= std::size_t(bounce)) m_profile.bounces.resize(bounce + 1);
    m_profile.bounces[bounce].passes += 1;
    m_profile.bounces[bounce].paths += alive;
    fill(0u, outSlot, bounce);
    // extend: closest hit of every queued path; camera rays in packets
    // (one origin: chooseTraversal's packets on any scene); later bounces'
    // rays as timed trials of both found faster on this scene and device
    // (whether a packet's incoherent lanes share nodes depends on the tree,
    // which the rays' directions and origins alone do not tell)
    const bool choose = m_settings.packets && !m_kernelFeatures.bvhCost;
    std::optional<Traversal>& extendChoice = m_extendTraversal[std::size_t(bounce)];
    if (choose && bounce > 0 && m_settings.extendTraversal) extendChoice = m_settings.extendTraversal;
    // samples 1 .. kExtendTrials alternate packets and single rays (sample 0
    // launches each kernel first, which a trial would time)
    const int trial = choose && bounce > 0 && !extendChoice && m_samplesRendered >= 1 &&
                              m_samplesRendered <= kExtendTrials
                          ? m_samplesRendered
                          : 0;
    const bool packets = choose && (bounce == 0 || (trial ? trial % 2 == 1 : extendChoice == Traversal::kPacket));
    // the shadow rays' traversal, measured on them in the first sample
    if (choose && m_settings.shadowTraversal) m_shadowTraversal[std::size_t(bounce)] = m_settings.shadowTraversal;
    const bool probe = choose && m_connectStage && !m_shadowTraversal[std::size_t(bounce)];
    const Traversal shadowTraversal =
        choose && !probe ? *m_shadowTraversal[std::size_t(bounce)] : Traversal::kSingle;
    // Shadow rays traced in packets, or measured, are appended to a dense
    // queue (an atomic counter from 0); otherwise shade writes entry i for
    // its item i (WT_NO_HIT: no shadow ray) and the queue has the bounce's
    // path count. connect and connect_stream take either.
    const bool compactShadows = probe || shadowTraversal == Traversal::kPacket;
    fill(compactShadows ? 0u : cl_uint(alive), WT_COUNTER_SHADOW, bounce);
    // stochastic transparency: numbers of their own per sample, bounce and stage
    // the general program takes the alpha key whether or not the scene has holes
    const bool alpha = m_kernelFeatures.alpha;
    auto extend = [&](auto& k, std::size_t items) {
      k.set("queue_slot", inSlot).set("queue", *queueIn);
      if (alpha)
        k.set("alpha_key", rng_alpha_key(cl_uint(sample), cl_uint(bounce), WT_DIM_ALPHA_EXTEND, m_settings.seed));
      launch(k, items, event(Command::Extend, bounce));
    };
    std::chrono::steady_clock::time_point extendStart;
    if (trial) {
      q.finish();  // the bounce's fills: the trial times extend alone
      extendStart = std::chrono::steady_clock::now();
    }
    if (packets)
      extend(m_extendPacket, (alive + m_packetWidth - 1) / m_packetWidth);
    else
      extend(m_extend, alive);
    if (trial) {
      q.finish();
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - extendStart).count();
      m_extendTrials[std::size_t(bounce)].add(packets ? Traversal::kPacket : Traversal::kSingle,
                                              seconds / double(alive));
    }

    // shade: emission and the next direction; survivors go to the other queue
    WtFrameParams shadeParams = frameParams(m_settings, m_lights, sample, bounce);
    if (compactShadows) shadeParams.flags |= WT_FLAG_COMPACT_SHADOWS;
    if (m_connectStage) shadeParams.flags |= WT_FLAG_SHADOW_QUEUE;
    m_shade.set("frame", shadeParams)
        .set("in_slot", inSlot)
        .set("out_slot", outSlot)
        .set("queue_in", *queueIn)
        .set("queue_out", *queueOut);
    const std::size_t lanes = std::size_t(m_kernelFeatures.shadeLanesWidth);
    launch(m_shade, m_kernelFeatures.shadeLanes ? (alive + lanes - 1) / lanes : alive,
           event(Command::Shade, bounce));

    // connect: shadow rays of this bounce (count read on the device); shade
    // makes none at the last bounce, which it shades for emission only
    const bool connect = m_settings.skipUnusedStages ? m_connectStage && bounce < passes
                                                     : m_lights.sampleable;
    if (connect) {
      auto run = [&](auto& k, std::size_t items) {
        if (alpha)
          k.set("alpha_key", rng_alpha_key(cl_uint(sample), cl_uint(bounce), WT_DIM_ALPHA_SHADOW, m_settings.seed));
        launch(k, items, event(Command::Connect, bounce));
      };
      const Traversal traversal = probe ? *(m_shadowTraversal[std::size_t(bounce)] = probeShadowRays(bounce))
                                        : shadowTraversal;
      if (traversal == Traversal::kPacket) {
        run(m_connectPacket, (alive + m_packetWidth - 1) / m_packetWidth);
      } else if (traversal == Traversal::kStream) {
        if (alpha)
          m_connectStream.set("alpha_key",
                              rng_alpha_key(cl_uint(sample), cl_uint(bounce), WT_DIM_ALPHA_SHADOW, m_settings.seed));
        m_connectStream.requireBound();
        m_context.launch(stage::ConnectStream::kName.data(), m_connectStream.kernel(),
                         (alive + WT_STREAM_WINDOW - 1) / WT_STREAM_WINDOW, Context::kStreamLocalSize,
                         event(Command::Connect, bounce));
        ++m_profile.kernelLaunches;
      } else {
        run(m_connect, alive);
      }
      // profiled: the sparse queue's shadow rays, counted on the host after the pass
      if (profile && !compactShadows && m_connectStage) {
        shadowEntries.emplace_back(bounce, std::vector<cl_uint>(alive));
        q.enqueueReadBuffer(m_path.shadowQueue, CL_FALSE, 0, alive * sizeof(cl_uint), shadowEntries.back().second.data(),
                            nullptr, event(Command::ProfileRead, bounce));
      }
    }

    // end of the bounce: the only point where the host reads a count back
    cl_uint counters[WT_COUNTER_COUNT];
    const auto readStart = std::chrono::steady_clock::now();
    q.enqueueReadBuffer(m_counters, CL_TRUE, 0, sizeof(counters), counters, nullptr, event(Command::Transfer, bounce));
    hostWait += std::chrono::duration<double>(std::chrono::steady_clock::now() - readStart).count();
    ++m_profile.blockingReads;
    if (profile && connect && compactShadows) m_profile.bounces[bounce].shadowRays += counters[WT_COUNTER_SHADOW];
    alive = counters[outSlot];
    if (m_settings.stopOnNonFinite && counters[WT_COUNTER_FIRST_NONFINITE] != 0xffffffffu)
      throwNonFinite(sample, counters[WT_COUNTER_FIRST_NONFINITE], counters[WT_COUNTER_NONFINITE_WHERE]);
    std::swap(queueIn, queueOut);
    std::swap(inSlot, outSlot);
  }

  // accumulate: fold the pass into the running mean
  WtFrameParams foldParams = frameParams(m_settings, m_lights, sample, 0);
  if (m_accumulationBlank) foldParams.flags |= WT_FLAG_BLANK_ACCUMULATION;
  m_accumulate.set("frame", foldParams);
  launch(m_accumulate, pixels, event(Command::Accumulate, 0));
  m_accumulationBlank = false;
  m_context.finish();
  ++m_stats.samplesDone;
  if (++m_samplesRendered == kExtendTrials + 1 && m_settings.packets && !m_kernelFeatures.bvhCost) {
    // the trials are over: each bounce both ways traced keeps the faster
    for (std::size_t b = 1; b < m_extendTraversal.size(); ++b) {
      const std::optional<Traversal> faster = m_extendTrials[b].faster();
      if (m_extendTraversal[b] || !faster) continue;
      m_extendTraversal[b] = faster;
      log::debug("closest hits of bounce " + std::to_string(b) + ": packets " +
                 std::to_string(m_extendTrials[b].packetRatio()) +
                 "x single rays' fastest trial: " + (*faster == Traversal::kPacket ? "packets" : "single rays"));
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m_stats.seconds += wall;
  m_profile.pixels = pixels;
  m_profile.maxBounces = m_settings.maxBounces;
  m_profile.samples += 1;
  m_profile.hostWaitSeconds += hostWait;
  if (!profile) {
    m_profile.wallSeconds += wall;
    return;
  }

  // the pass's device timeline: each command's time by stage and bounce, and
  // the gap before it (the device waiting on the host) against its bounce
  m_profile.timed = true;
  double profileReads = 0.0;
  cl_ulong lastEnd = 0;
  for (const TimedCommand& t : timed) {
    if (!t.event()) continue;  // a fill made without an event (Context::fill under Oclgrind)
    const cl_ulong begin = t.event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    const cl_ulong end = t.event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    const double seconds = end > begin ? double(end - begin) * 1e-9 : 0.0;
    const double gap = lastEnd != 0 && begin > lastEnd ? double(begin - lastEnd) * 1e-9 : 0.0;
    lastEnd = std::max(lastEnd, end);
    BounceProfile& b = m_profile.bounces[std::size_t(t.bounce)];
    switch (t.command) {
      case Command::Generate: m_profile.generateSeconds += seconds, m_profile.otherIdleSeconds += gap; break;
      case Command::Accumulate: m_profile.accumulateSeconds += seconds, m_profile.otherIdleSeconds += gap; break;
      case Command::Extend: b.extendSeconds += seconds, b.idleSeconds += gap; break;
      case Command::Shade: b.shadeSeconds += seconds, b.idleSeconds += gap; break;
      case Command::Connect: b.connectSeconds += seconds, b.idleSeconds += gap; break;
      case Command::Transfer: b.transferSeconds += seconds, b.idleSeconds += gap; break;
      case Command::ProfileRead: profileReads += seconds, b.idleSeconds += gap; break;
    }
  }
  // WT_NO_HIT (all ones): the item made no shadow ray
  for (const auto& [bounce, entries] : shadowEntries)
    m_profile.bounces[std::size_t(bounce)].shadowRays +=
        std::size_t(std::count_if(entries.begin(), entries.end(), [](cl_uint e) { return e != 0xffffffffu; }));
  m_profile.profileReadSeconds += profileReads;
  m_profile.wallSeconds += wall - profileReads;
}

void Renderer::throwNonFinite(int sample, std::uint32_t path, std::uint32_t where) {
  m_context.finish();
  const int x = int(path % std::uint32_t(m_settings.width)), y = int(path / std::uint32_t(m_settings.width));
  const int bounce = int(where & 0xffffu);
  const std::uint32_t what = where >> 16;
  const char* quantity = what == WT_NONFINITE_EMISSION ? "emitted radiance"
                         : what == WT_NONFINITE_LIGHT  ? "next-event contribution"
                                                       : "path throughput";
  throw NonFiniteSampleError("non-finite " + std::string(quantity) + " at pixel (" + std::to_string(x) + ", " +
                                 std::to_string(y) + "), sample " + std::to_string(sample) + ", bounce " +
                                 std::to_string(bounce) + " (stopped there: --stop-on-nan)",
                             x, y, sample, bounce);
}

Image Renderer::readImage() {
  Image image;
  readResolved(image, true);
  return image;
}

Image Renderer::readRadiance() {
  Image image;
  readResolved(image, false);
  return image;
}

Image Renderer::readDisplayImage() {
  Image image;
  readResolved(image, true, false);
  return image;
}

void Renderer::readResolved(Image& image, bool tonemap, bool floats) {
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  cl::CommandQueue& q = m_context.queue();
  writeBlankAccumulation();
  WtFrameParams frame = frameParams(m_settings, m_lights, m_stats.samplesDone, 0);
  // the 8-bit pixels alone: tone-mapped from the state's float mean in place,
  // without resolving mean and m2 (the double state needs its conversion)
  const bool meanInState = tonemap && !floats && m_settings.accumulation != WT_ACCUMULATE_DOUBLE;
  if (!meanInState) {
    m_resolve.set("frame", frame);
    launch(m_resolve, pixels);
  }
  if (tonemap) {
    if (meanInState) frame.flags |= WT_FLAG_MEAN_IN_STATE;
    m_tonemapper.run(frame, tonemapParams(m_settings.tonemap), meanInState ? m_path.state : m_path.mean, m_path.pixels);
  }

  std::vector<float> mean(floats ? 4 * pixels : 0), m2(floats ? 4 * pixels : 0);
  image.width = m_settings.width;
  image.height = m_settings.height;
  image.samples.resize(pixels);
  if (floats) {
    q.enqueueReadBuffer(m_path.mean, CL_FALSE, 0, mean.size() * 4, mean.data());
    q.enqueueReadBuffer(m_path.m2, CL_FALSE, 0, m2.size() * 4, m2.data());
  }
  q.enqueueReadBuffer(m_path.sampleCount, CL_FALSE, 0, pixels * 4, image.samples.data());
  if (tonemap) {
    image.srgba.resize(4 * pixels);
    q.enqueueReadBuffer(m_path.pixels, CL_FALSE, 0, pixels * 4, image.srgba.data());
  }
  cl_uint counters[WT_COUNTER_COUNT];
  q.enqueueReadBuffer(m_counters, CL_FALSE, 0, sizeof(counters), counters);
  m_context.finish();
  m_stats.nonFiniteSamples = counters[WT_COUNTER_NONFINITE];
  image.samplesDone = m_stats.samplesDone;

  if (m_settings.aovs) readAovs(image);
  if (!floats) return;

  image.rgb.resize(3 * pixels);
  image.rgbVariance.resize(3 * pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    std::uint32_t n = image.samples[i];
    for (int c = 0; c < 3; ++c) {
      image.rgb[3 * i + c] = mean[4 * i + c];
      image.rgbVariance[3 * i + c] = n > 1 ? m2[4 * i + c] / float(n - 1) : 0.0f;
    }
  }
}

Accumulation Renderer::saveAccumulation() {
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  cl::CommandQueue& q = m_context.queue();
  writeBlankAccumulation();
  Accumulation a;
  a.samplesDone = m_stats.samplesDone;
  a.state.resize(pixels * kAccumulationStateBytes);
  a.samples.resize(pixels);
  cl_uint counters[WT_COUNTER_COUNT];
  q.enqueueReadBuffer(m_path.state, CL_FALSE, 0, a.state.size(), a.state.data());
  q.enqueueReadBuffer(m_path.sampleCount, CL_FALSE, 0, pixels * 4, a.samples.data());
  q.enqueueReadBuffer(m_counters, CL_FALSE, 0, sizeof(counters), counters);
  if (m_settings.aovs) {
    a.aovs.resize(pixels * (kAovSumBytes + kAovIdBytes));
    q.enqueueReadBuffer(m_path.aovAccum, CL_FALSE, 0, pixels * kAovSumBytes, a.aovs.data());
    q.enqueueReadBuffer(m_path.aovIds, CL_FALSE, 0, pixels * kAovIdBytes, a.aovs.data() + pixels * kAovSumBytes);
  }
  m_context.finish();
  a.nonFiniteSamples = counters[WT_COUNTER_NONFINITE];
  return a;
}

void Renderer::restoreAccumulation(const Accumulation& saved) {
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  if (saved.state.size() != pixels * kAccumulationStateBytes || saved.samples.size() != pixels || saved.samplesDone < 0)
    throw std::invalid_argument("saved accumulation holds " + std::to_string(saved.samples.size()) +
                                " pixels, the image " + std::to_string(pixels));
  const std::size_t aovBytes = m_settings.aovs ? pixels * (kAovSumBytes + kAovIdBytes) : 0;
  if (saved.aovs.size() != aovBytes)
    throw std::invalid_argument(aovBytes ? "saved accumulation holds no AOVs (or another image's), this render records them"
                                         : "saved accumulation holds AOVs, this render records none");
  cl::CommandQueue& q = m_context.queue();
  if (aovBytes) {
    q.enqueueWriteBuffer(m_path.aovAccum, CL_FALSE, 0, pixels * kAovSumBytes, saved.aovs.data());
    q.enqueueWriteBuffer(m_path.aovIds, CL_FALSE, 0, pixels * kAovIdBytes, saved.aovs.data() + pixels * kAovSumBytes);
  }
  q.enqueueWriteBuffer(m_path.state, CL_FALSE, 0, saved.state.size(), saved.state.data());
  q.enqueueWriteBuffer(m_path.sampleCount, CL_FALSE, 0, pixels * 4, saved.samples.data());
  const cl_uint nonFinite = cl_uint(saved.nonFiniteSamples);
  q.enqueueWriteBuffer(m_counters, CL_FALSE, WT_COUNTER_NONFINITE * sizeof(cl_uint), sizeof(cl_uint), &nonFinite);
  m_context.finish();
  m_accumulationBlank = false;
  m_stats.samplesDone = saved.samplesDone;
  m_stats.nonFiniteSamples = saved.nonFiniteSamples;
}

void Renderer::writeBlankAccumulation() {
  if (!m_accumulationBlank) return;
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  // zero bits are 0.0f (and 0.0) as well
  m_context.fill(m_path.state, 0u, 0, pixels * kAccumulationStateBytes);
  m_context.fill(m_path.sampleCount, 0u, 0, pixels * 4);
  m_accumulationBlank = false;
}

void Renderer::resetAccumulation(int nextSample) {
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  // zero bits are 0.0f (and 0.0) as well
  m_context.fill(m_path.state, 0u, 0, pixels * kAccumulationStateBytes);
  m_context.fill(m_path.sampleCount, 0u, 0, pixels * 4);
  if (m_settings.aovs) m_context.fill(m_path.aovAccum, 0u, 0, pixels * 64);
  m_context.fill(m_counters, 0u, WT_COUNTER_NONFINITE * sizeof(cl_uint), sizeof(cl_uint));
  m_context.finish();
  m_accumulationBlank = false;
  m_stats.samplesDone = nextSample;
  m_stats.nonFiniteSamples = 0;
}

void Renderer::readAovs(Image& image) {
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  std::vector<float> sum(16 * pixels);
  std::vector<std::uint32_t> ids(4 * pixels);
  cl::CommandQueue& q = m_context.queue();
  q.enqueueReadBuffer(m_path.aovAccum, CL_FALSE, 0, sum.size() * 4, sum.data());
  q.enqueueReadBuffer(m_path.aovIds, CL_FALSE, 0, ids.size() * 4, ids.data());
  m_context.finish();
  image.aovs = decodeAovs(sum.data(), ids.data(), pixels);
}

Aovs decodeAovs(const float* sum, const std::uint32_t* ids, std::size_t pixels) {
  Aovs a;
  a.albedo.resize(3 * pixels);
  a.normal.resize(3 * pixels);
  a.position.resize(3 * pixels);
  a.uv.resize(2 * pixels);
  a.depth.resize(pixels);
  a.bounces.resize(pixels);
  a.bvhCost.resize(pixels);
  a.material.resize(pixels);
  a.instance.resize(pixels);
  a.primitive.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    const float* s = &sum[16 * i];  // kernels/aov.cl: albedo+samples, normal+bounces, position+depth, uv+hits
    const float n = s[3], hits = s[15];
    for (int c = 0; c < 3; ++c) {
      a.albedo[3 * i + c] = n > 0.0f ? s[c] / n : 0.0f;
      a.normal[3 * i + c] = n > 0.0f ? s[4 + c] / n : 0.0f;
      a.position[3 * i + c] = hits > 0.0f ? s[8 + c] / hits : 0.0f;
    }
    a.bounces[i] = n > 0.0f ? s[7] / n : 0.0f;
    a.bvhCost[i] = n > 0.0f ? s[14] / n : 0.0f;
    a.depth[i] = hits > 0.0f ? s[11] / hits : INFINITY;
    a.uv[2 * i] = hits > 0.0f ? s[12] / hits : 0.0f;
    a.uv[2 * i + 1] = hits > 0.0f ? s[13] / hits : 0.0f;
    a.material[i] = ids[4 * i];
    a.instance[i] = ids[4 * i + 1];
    a.primitive[i] = ids[4 * i + 2];
  }
  return a;
}

}  // namespace wt
