#include "render/renderer.h"

#include "device/program.h"
#include "render/material_tables.h"
#include "shared/rng.h"

#include <algorithm>
#include <chrono>
#include <type_traits>
#include <cmath>

namespace wt {
namespace {

/// Where WT_ALPHA_PARAMS start in extend, extend_packet, connect and
/// connect_packet: after their 11 arguments and WT_GEOMETRY_PARAMS (5).
constexpr int kAlphaArg = 16;

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
  p.exposure = std::exp2(s.exposureStops);
  p.light_count = lights.sampleable ? cl_uint(lights.alias.size()) : 0u;
  p.analytic_count = lights.analyticCount;
  p.env_pmf = lights.environmentPmf;
  p.rr_min_depth = cl_uint(std::max(0, s.rrMinDepth));
  if (s.integrator == Integrator::Path) {
    p.flags = (s.useNee ? WT_FLAG_NEE : 0u) | (s.useMis ? WT_FLAG_MIS : 0u) |
              (s.powerHeuristic ? WT_FLAG_POWER_HEURISTIC : 0u) | (s.useRussianRoulette ? WT_FLAG_RR : 0u);
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
  CameraDesc desc = scene.camera ? *scene.camera : defaultCamera(scene.bounds());
  m_camera = makeCamera(desc, settings.width, settings.height);
  BvhBuildOptions bvhOptions;
  bvhOptions.builder = settings.bvhBuilder;
  bvhOptions.maxLeafSize = 0;  // leaves of up to kBvh4MaxLeafSize, chosen by the collapse
  bvhOptions.instancing = settings.instancing;
  bvhOptions.allSurfaceAttributes = settings.generalProgram;
  m_scene = std::make_unique<SceneBuffers>(context, scene, bvhOptions);
  m_environment = settings.environmentMap.empty()
                      ? constantEnvironment(settings.background)
                      : loadEnvironmentMap(settings.environmentMap, settings.environmentIntensity,
                                           settings.environmentRotationDegrees);
  double envLum = m_environment.meanLuminance;
  m_lights = buildLightList(scene, *m_scene, envLum > 0.0 ? environmentPowerEstimate(scene, envLum) : 0.0,
                            settings.lightSampler);

  m_features = sceneFeatures(scene, *m_scene, settings);
  m_kernelFeatures = settings.generalProgram ? generalKernelFeatures(m_features, context.info(), settings.packetWidth)
                                             : kernelFeaturesFor(m_features, context.info(), settings.packetWidth);
  m_packetWidth = m_kernelFeatures.packetWidth;
  const KernelFeatures& features = m_kernelFeatures;
  const auto buildStart = std::chrono::steady_clock::now();
  m_program = buildProgram(context, features);
  m_stats.programSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - buildStart).count();
  m_generate = cl::Kernel(m_program, "generate");
  m_extend = cl::Kernel(m_program, "extend");
  m_extendPacket = cl::Kernel(m_program, "extend_packet");
  m_shade = cl::Kernel(m_program, "shade");
  m_connect = cl::Kernel(m_program, "connect");
  m_connectPacket = cl::Kernel(m_program, "connect_packet");
  m_accumulate = cl::Kernel(m_program, "accumulate");
  m_resolve = cl::Kernel(m_program, "accumulate_resolve");
  if (settings.accumulation == WT_ACCUMULATE_DOUBLE && !context.info().fp64)
    throw DeviceError("double-precision accumulation needs fp64, which '" + context.info().name + "' lacks");
  m_tonemap = cl::Kernel(m_program, "tonemap");

  std::size_t pixels = std::size_t(settings.width) * std::size_t(settings.height);
  cl::Context& ctx = context.context();
  auto make = [&](std::size_t bytesPerPixel) {
    return cl::Buffer(ctx, CL_MEM_READ_WRITE, pixels * bytesPerPixel);
  };
  m_rayO = make(16), m_rayD = make(16), m_hits = make(16);
  m_throughput = make(16), m_radiance = make(16);
  m_queueA = make(4), m_queueB = make(4);
  m_counters = cl::Buffer(ctx, CL_MEM_READ_WRITE, WT_COUNTER_COUNT * sizeof(cl_uint));
  m_state = make(64), m_mean = make(16), m_m2 = make(16), m_sampleCount = make(4), m_pixels = make(4);
  m_shadowQueue = make(4), m_shadowO = make(16), m_shadowD = make(16), m_shadowRadiance = make(16);
  m_bounceCounts = make(8);  // ushort4: diffuse, specular, transmission bounces
  m_raySkip = make(4), m_shadowSkip = make(8), m_prevNormal = make(16);
  m_hitInstance = features.primitives[WT_PRIM_INSTANCE] ? make(4) : cl::Buffer(ctx, CL_MEM_READ_WRITE, 4);
  m_rayCone = features.textures ? make(8) : cl::Buffer(ctx, CL_MEM_READ_WRITE, 8);
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
  EnvironmentUpload env = environmentUpload(m_environment);
  auto uploadSpan = [&](auto span) {
    cl::Buffer b(ctx, CL_MEM_READ_ONLY, span.size_bytes());
    context.queue().enqueueWriteBuffer(b, CL_TRUE, 0, span.size_bytes(), span.data());
    return b;
  };
  m_envTexels = uploadSpan(env.texels);
  m_envMarginal = uploadSpan(env.marginalCdf);
  m_envConditional = uploadSpan(env.conditionalCdf);

  cl::CommandQueue& q = context.queue();
  // zero bits are 0.0f as well
  context.fill(m_state, 0u, 0, pixels * 64);
  context.fill(m_sampleCount, 0u, 0, pixels * 4);
  context.fill(m_counters, 0u, 0, WT_COUNTER_COUNT * sizeof(cl_uint));
  context.fill(m_counters, 0xffffffffu, WT_COUNTER_FIRST_NONFINITE * sizeof(cl_uint), sizeof(cl_uint));
  q.finish();

  // Arguments that never change; per-launch ones are set in renderSample().
  int a = 2;  // generate: frame, camera set per pass
  for (cl::Buffer* b : {&m_rayO, &m_rayD, &m_throughput, &m_radiance, &m_queueA, &m_counters, &m_bounceCounts,
                        &m_raySkip, &m_rayCone})
    m_generate.setArg(a++, *b);

  for (cl::Kernel* k : {&m_extend, &m_extendPacket}) {
    k->setArg(0, m_counters);
    k->setArg(3, m_rayO);
    k->setArg(4, m_rayD);
    k->setArg(5, m_scene->nodes);
    k->setArg(6, m_scene->nodeCount);
    k->setArg(7, m_scene->triVerts);
    k->setArg(8, m_hits);
    k->setArg(9, m_raySkip);
    k->setArg(10, m_hitInstance);
    m_scene->bindGeometry(*k, 11);
    if (features.alpha) m_scene->bindAlpha(*k, kAlphaArg);
  }

  // shade: 0 frame, 1 environment, 2-4 its arrays, 5 counters, 6-9 queues (per bounce), 10- fixed
  m_shade.setArg(1, m_environment.header);
  m_shade.setArg(2, m_envTexels);
  m_shade.setArg(3, m_envMarginal);
  m_shade.setArg(4, m_envConditional);
  m_shade.setArg(5, m_counters);
  a = 10;
  for (cl::Buffer* b : {&m_rayO, &m_rayD, &m_hits, &m_throughput, &m_radiance, &m_scene->triangleInfo,
                        &m_scene->triVerts, &m_scene->normals, &m_scene->materials, &m_lightBuffer,
                        &m_aliasBuffer, &m_emitterPdfBuffer, &m_shadowQueue, &m_shadowO, &m_shadowD,
                        &m_shadowRadiance, &m_pbrTable, &m_bounceCounts, &m_raySkip, &m_shadowSkip,
                        &m_lightTree, &m_emitterLeaf, &m_prevNormal, &m_hitInstance})
    m_shade.setArg(a++, *b);
  m_scene->bindGeometry(m_shade, a);
  m_shade.setArg(a + 5, m_rayCone);
  m_scene->bindSurface(m_shade, a + 6);

  for (cl::Kernel* k : {&m_connect, &m_connectPacket}) {
    a = 0;
    for (cl::Buffer* b : {&m_counters, &m_shadowQueue, &m_shadowO, &m_shadowD, &m_shadowRadiance, &m_scene->nodes})
      k->setArg(a++, *b);
    k->setArg(a++, m_scene->nodeCount);
    k->setArg(a++, m_scene->triVerts);
    k->setArg(a++, m_radiance);
    k->setArg(a++, m_shadowSkip);
    k->setArg(a++, m_hitInstance);
    m_scene->bindGeometry(*k, a);
    if (features.alpha) m_scene->bindAlpha(*k, kAlphaArg);
  }

  a = 1;
  for (cl::Buffer* b : {&m_radiance, &m_state, &m_sampleCount, &m_counters})
    m_accumulate.setArg(a++, *b);
  m_resolve.setArg(1, m_state);
  m_resolve.setArg(2, m_mean);
  m_resolve.setArg(3, m_m2);

  m_tonemap.setArg(1, m_mean);
  m_tonemap.setArg(2, m_pixels);
}

Renderer::~Renderer() = default;

void Renderer::renderSample() {
  auto start = std::chrono::steady_clock::now();
  const int sample = m_stats.samplesDone;
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  cl::CommandQueue& q = m_context.queue();

  // generate: every pixel's path enters queue A
  m_generate.setArg(0, frameParams(m_settings, m_lights, sample, 0));
  m_generate.setArg(1, m_camera);
  m_context.launch("generate", m_generate, pixels);

  cl::Buffer* queueIn = &m_queueA;
  cl::Buffer* queueOut = &m_queueB;
  cl_uint inSlot = WT_COUNTER_QUEUE_A, outSlot = WT_COUNTER_QUEUE_B;
  std::size_t alive = pixels;
  for (int bounce = 0; bounce <= m_settings.maxBounces && alive > 0; ++bounce) {
    m_stats.raysTraced += alive;
    m_context.fill(m_counters, 0u, outSlot * sizeof(cl_uint), sizeof(cl_uint));
    // extend: closest hit of every queued path; camera rays in packets
    const bool packets = m_settings.packets && bounce == 0;
    // Shadow rays traced in packets are appended to a dense queue (an atomic
    // counter from 0); otherwise shade writes entry i for its item i
    // (WT_NO_HIT: no shadow ray) and the queue has the bounce's path count.
    m_context.fill(m_counters, packets ? 0u : cl_uint(alive), WT_COUNTER_SHADOW * sizeof(cl_uint), sizeof(cl_uint));
    cl::Kernel& extend = packets ? m_extendPacket : m_extend;
    extend.setArg(1, inSlot);
    extend.setArg(2, *queueIn);
    // stochastic transparency: numbers of their own per sample, bounce and stage
    if (m_kernelFeatures.alpha)
      extend.setArg(kAlphaArg, rng_alpha_key(cl_uint(sample), cl_uint(bounce), WT_DIM_ALPHA_EXTEND, m_settings.seed));
    if (packets)
      m_context.launch("extend_packet", extend, (alive + m_packetWidth - 1) / m_packetWidth);
    else
      m_context.launch("extend", extend, alive);

    // shade: emission and the next direction; survivors go to the other queue
    WtFrameParams shadeParams = frameParams(m_settings, m_lights, sample, bounce);
    if (packets) shadeParams.flags |= WT_FLAG_COMPACT_SHADOWS;
    m_shade.setArg(0, shadeParams);
    m_shade.setArg(6, inSlot);
    m_shade.setArg(7, outSlot);
    m_shade.setArg(8, *queueIn);
    m_shade.setArg(9, *queueOut);
    m_context.launch("shade", m_shade, alive);

    // connect: shadow rays of this bounce (count read on the device)
    if (m_lights.sampleable) {
      if (m_kernelFeatures.alpha)
        (packets ? m_connectPacket : m_connect)
            .setArg(kAlphaArg, rng_alpha_key(cl_uint(sample), cl_uint(bounce), WT_DIM_ALPHA_SHADOW, m_settings.seed));
      if (packets)
        m_context.launch("connect_packet", m_connectPacket, (alive + m_packetWidth - 1) / m_packetWidth);
      else
        m_context.launch("connect", m_connect, alive);
    }

    // end of the bounce: the only point where the host reads a count back
    cl_uint counters[WT_COUNTER_COUNT];
    q.enqueueReadBuffer(m_counters, CL_TRUE, 0, sizeof(counters), counters);
    alive = counters[outSlot];
    if (m_settings.stopOnNonFinite && counters[WT_COUNTER_FIRST_NONFINITE] != 0xffffffffu)
      throwNonFinite(sample, counters[WT_COUNTER_FIRST_NONFINITE], counters[WT_COUNTER_NONFINITE_WHERE]);
    std::swap(queueIn, queueOut);
    std::swap(inSlot, outSlot);
  }

  // accumulate: fold the pass into the running mean
  m_accumulate.setArg(0, frameParams(m_settings, m_lights, sample, 0));
  m_context.launch("accumulate", m_accumulate, pixels);
  m_context.finish();
  ++m_stats.samplesDone;
  m_stats.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
  const std::size_t pixels = std::size_t(m_settings.width) * std::size_t(m_settings.height);
  cl::CommandQueue& q = m_context.queue();
  m_resolve.setArg(0, frameParams(m_settings, m_lights, m_stats.samplesDone, 0));
  m_context.launch("accumulate_resolve", m_resolve, pixels);
  m_tonemap.setArg(0, frameParams(m_settings, m_lights, m_stats.samplesDone, 0));
  m_context.launch("tonemap", m_tonemap, pixels);

  std::vector<float> mean(4 * pixels), m2(4 * pixels);
  Image image;
  image.width = m_settings.width;
  image.height = m_settings.height;
  image.samples.resize(pixels);
  image.srgba.resize(4 * pixels);
  q.enqueueReadBuffer(m_mean, CL_FALSE, 0, mean.size() * 4, mean.data());
  q.enqueueReadBuffer(m_m2, CL_FALSE, 0, m2.size() * 4, m2.data());
  q.enqueueReadBuffer(m_sampleCount, CL_FALSE, 0, pixels * 4, image.samples.data());
  q.enqueueReadBuffer(m_pixels, CL_FALSE, 0, pixels * 4, image.srgba.data());
  cl_uint counters[WT_COUNTER_COUNT];
  q.enqueueReadBuffer(m_counters, CL_FALSE, 0, sizeof(counters), counters);
  m_context.finish();
  m_stats.nonFiniteSamples = counters[WT_COUNTER_NONFINITE];

  image.rgb.resize(3 * pixels);
  image.rgbVariance.resize(3 * pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    std::uint32_t n = image.samples[i];
    for (int c = 0; c < 3; ++c) {
      image.rgb[3 * i + c] = mean[4 * i + c];
      image.rgbVariance[3 * i + c] = n > 1 ? m2[4 * i + c] / float(n - 1) : 0.0f;
    }
  }
  return image;
}

}  // namespace wt
