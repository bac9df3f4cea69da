// wavetrace: the command line. `render` (the default scene when no file is
// named), `info`, `devices`, `bench`.
#include "bench/bench.h"
#include "cli/scale_out.h"
#include "bvh/builders.h"
#include "core/log.h"
#include "device/context.h"
#include "device/program.h"
#include "device/program_cache.h"
#include "output/debug_view.h"
#include "output/image_io.h"
#include "device/scene_buffers.h"
#include "geometry/primitives.h"
#include "render/feature_set.h"
#include "render/checkpoint.h"
#include "render/halting.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "render/tonemap.h"
#include "scene/camera_override.h"
#include "scene/default_scene.h"
#include "scene/generators.h"
#include "stress/stress.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <tuple>
#include <chrono>
#include <cmath>
#include <csignal>
#include <optional>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <ctime>
#include <sys/resource.h>
#include <unistd.h>

namespace {

std::atomic<bool> g_interrupted{false};
wt::MpiWorld* g_world = nullptr;  ///< this process's place in an MPI job (size 1 without one)

extern "C" void onInterrupt(int) { g_interrupted = true; }

/// Seconds since the kernel started this process (exec), from
/// /proc/self/stat in clock ticks (10 ms here); nullopt where unreadable.
std::optional<double> processAgeSeconds() {
  std::ifstream in("/proc/self/stat");
  std::string stat;
  if (!std::getline(in, stat)) return std::nullopt;
  // field 22 (starttime) counts from the one after the command name's ')'
  std::size_t close = stat.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream fields(stat.substr(close + 2));
  std::string field;
  for (int i = 3; i < 22 && fields >> field;) ++i;
  unsigned long long startTicks = 0;
  timespec boot{};
  if (!(fields >> startTicks) || clock_gettime(CLOCK_BOOTTIME, &boot) != 0) return std::nullopt;
  return double(boot.tv_sec) + double(boot.tv_nsec) * 1e-9 - double(startTicks) / double(sysconf(_SC_CLK_TCK));
}

/// CPU seconds the process has used, all threads (user and system).
double processCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  auto seconds = [](const timeval& t) { return double(t.tv_sec) + double(t.tv_usec) * 1e-6; };
  return seconds(u.ru_utime) + seconds(u.ru_stime);
}

/// Where a render's start-up goes, for -v: each phase's wall and CPU
/// seconds (the CPU time, all threads, stays meaningful on a loaded machine).
class StartupTimeline {
 public:
  StartupTimeline()
      : m_last(std::chrono::steady_clock::now()), m_lastCpu(processCpuSeconds()),
        m_startAge(processAgeSeconds().value_or(0.0)) {}
  /// End the phase `name` now.
  void mark(const std::string& name) {
    const auto now = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double>(now - m_last).count(), cpu = processCpuSeconds();
    m_total += wall;
    m_text += ", " + name + " " + ms(wall) + " (cpu " + ms(cpu - m_lastCpu) + ")";
    m_last = now;
    m_lastCpu = cpu;
  }
  /// A part of the phase ended next, measured inside it (wall only).
  void part(const std::string& name, double seconds) { m_text += " [" + name + " " + ms(seconds) + "]"; }
  std::string line() const {
    return "start-up: exec to main " + ms(m_startAge) + " (cpu " + ms(m_mainCpu) + ")" + m_text + "; " +
           ms(m_startAge + m_total) + " since exec (cpu " + ms(processCpuSeconds()) + ")";
  }

 private:
  static std::string ms(double seconds) { return std::to_string(int(std::lround(seconds * 1e3))) + " ms"; }
  std::chrono::steady_clock::time_point m_last;
  double m_lastCpu = 0.0;
  double m_mainCpu = m_lastCpu;
  double m_startAge = 0.0;
  double m_total = 0.0;
  std::string m_text;
};

std::optional<StartupTimeline> g_startup;  ///< made first thing in main

/// The options a scene file (.json) may also set: true where the command
/// line named them, which then win over the file.
struct GivenOptions {
  bool width = false, height = false, spp = false, maxBounces = false, seed = false, exposure = false;
  bool integrator = false, background = false, envMap = false, envIntensity = false, envRotation = false,
       envHidden = false, tonemap = false;
};

/// The tone mapping options `render` and `tonemap` share, as given.
struct TonemapOptions {
  std::string op = "pbr-neutral";
  std::string exposure = "0";  ///< stops, or auto, auto+STOPS, auto-STOPS
  float aperture = 1.0f, shutter = 1.0f, iso = 100.0f;
  float white = 0.0f;
  float whiteBalance = 0.0f;
  bool noDither = false;
  bool physical = false;  ///< --aperture, --shutter or --iso given
};

void addTonemapOptions(CLI::App* cmd, TonemapOptions& t) {
  cmd->add_option("--tonemap", t.op,
                  "Tone mapping operator for PNG output: " + wt::tonemapOperatorList() +
                      " (docs/tonemapping.md; the EXR stays linear)")
      ->check(CLI::IsMember(std::vector<std::string>(wt::kTonemapOperatorNames.begin(), wt::kTonemapOperatorNames.end())))
      ->capture_default_str();
  cmd->add_option("--exposure", t.exposure,
                  "Exposure for PNG output: stops (2^stops), or auto (the image's log-average luminance to middle "
                  "grey 0.18), or auto+STOPS / auto-STOPS")
      ->capture_default_str();
  cmd->add_option("--aperture", t.aperture, "Physical exposure: f-number N (scale ISO t / (100 N^2))")
      ->check(CLI::Range(0.1f, 100.0f));
  cmd->add_option("--shutter", t.shutter, "Physical exposure: shutter time t in seconds")
      ->check(CLI::Range(1e-6f, 3600.0f));
  cmd->add_option("--iso", t.iso, "Physical exposure: film speed (ISO)")->check(CLI::Range(1.0f, 409600.0f));
  cmd->add_option("--tonemap-white", t.white,
                  "reinhard-modified: the luminance mapped to white (default 4); hable: the linear white (default 11.2)")
      ->check(CLI::Range(0.01f, 1e6f));
  cmd->add_option("--white-balance", t.whiteBalance,
                  "Balance from light of this colour temperature (kelvin, 1905-25000) to D65 white (von Kries in LMS)")
      ->check(CLI::Range(1905.0f, 25000.0f));
  cmd->add_flag("--no-dither", t.noDither, "Quantise to 8 bits without the per-pixel dither");
}

/// The settings the options give, and the exposure in stops; contradictions are errors.
std::pair<wt::TonemapSettings, float> resolveTonemap(const TonemapOptions& t) {
  wt::TonemapSettings s;
  s.op = *wt::parseTonemapOperator(t.op);
  s.fNumber = t.aperture, s.shutterSeconds = t.shutter, s.iso = t.iso;
  s.white = t.white;
  s.whiteBalanceKelvin = t.whiteBalance;
  s.dither = !t.noDither;
  std::string stops = t.exposure;
  if (stops.rfind("auto", 0) == 0) {
    s.autoExposure = true;
    stops = stops.substr(4);
    if (stops.empty()) stops = "0";
    else if (stops[0] != '+' && stops[0] != '-')
      throw std::invalid_argument("--exposure: '" + t.exposure + "' is not auto, auto+STOPS or auto-STOPS");
    if (t.physical)
      throw std::invalid_argument("--exposure auto contradicts --aperture/--shutter/--iso (a physical exposure)");
  }
  std::size_t used = 0;
  float value = 0.0f;
  try {
    value = std::stof(stops, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != stops.size() || stops.empty() || !std::isfinite(value) || std::fabs(value) > 1000.0f)
    throw std::invalid_argument("--exposure: '" + t.exposure +
                                "' is not a number of stops in [-1000, 1000], auto, auto+STOPS or auto-STOPS");
  return {s, value};
}

struct RenderOptions {
  std::string scene;
  std::vector<std::string> outputs;
  wt::RenderSettings settings;
  std::string device;
  std::vector<float> background{0.0f, 0.0f, 0.0f};
  std::string integrator = "path";
  std::string misHeuristic = "auto";  ///< power at Lambertian vertices (docs/integrators.md)
  bool noNee = false, noMis = false, noRr = false;
  std::string sampler = "sobol";  ///< chosen by efficiency, 1 / (relMSE x time) (docs/integrators.md, "Samplers")
  std::string textureFilter = "footprint";
  std::string lightSampler = "auto";
  std::string reference, errorLog;
  std::string accumulation = "kahan";
  std::string bvh = "auto";
  std::string instancing = "auto";
  std::string traversal = "auto";
  int packetWidth = 0;
  int sceneIndex = -1;
  int camera = 0;
  std::vector<double> lookFrom, lookAt, up;  ///< --look-from, --look-at, --up: empty or x,y,z
  double fovDegrees = 0.0;                   ///< --fov; 0: the camera's own
  bool frame = false;
  bool noRecenter = false;
  int tessellate = 0;  ///< --tessellate: displaced meshes as triangles, this many per base edge (0: displaced)
  bool stopOnNan = false;
  std::string kernelDir;
  bool quiet = false;
  bool verbose = false;
  bool profile = false;     ///< --profile: stage times per bounce (a profiling queue)
  std::string profileJson;  ///< --profile-json FILE (implies --profile)
  TonemapOptions tonemap;
  double timeSeconds = 0.0;        ///< --time; 0: none
  double targetError = 0.0;        ///< --target-error; 0: none
  double checkpointSeconds = -1.0;  ///< --checkpoint; 0: none; < 0: not given (a job of several ranks: kJobCheckpointSeconds)
  bool resume = false;
  int chunkSpp = 0;    ///< --chunk-spp; 0: defaultChunkSpp
  bool chunkSppGiven = false;
  double rankTimeout = wt::ScaleOutOptions::kDefaultRankTimeout;  ///< --rank-timeout
  double startTimeout = 0.0;  ///< --start-timeout; 0: the larger of --rank-timeout and its default
  std::string aov;     ///< --aov: names, comma-separated, or "all"
  std::string aovOut;  ///< --aov-out: folder for one EXR per AOV
  std::string debug;   ///< --debug: a view (output/debug_view.h)
  std::vector<wt::Aov> aovs;               ///< parsed --aov
  wt::DebugView debugView = wt::DebugView::None;  ///< parsed --debug
  GivenOptions given;
};

std::optional<glm::dvec3> point(const std::vector<double>& v) {
  if (v.empty()) return std::nullopt;
  return glm::dvec3(v[0], v[1], v[2]);
}

/// --look-from, --look-at, --up, --fov and --frame over the scene's camera.
void applyCameraOptions(const RenderOptions& options, wt::Scene& scene) {
  wt::CameraOverride o;
  o.from = point(options.lookFrom);
  o.at = point(options.lookAt);
  o.up = point(options.up);
  if (options.fovDegrees != 0.0) o.fovDegrees = options.fovDegrees;
  o.frame = options.frame;
  wt::applyCameraOverride(scene, o);
}

/// Every file of a render's outputs (the -o images, --aov-out's AOV
/// images), each with how to write it to a path of its kind.
using OutputFile = std::pair<std::filesystem::path, std::function<void(const std::filesystem::path&)>>;
std::vector<OutputFile> outputFiles(const RenderOptions& options, const wt::Image& image) {
  std::vector<OutputFile> files;
  for (const std::string& out : options.outputs)
    files.emplace_back(out, [&](const std::filesystem::path& to) { wt::writeImage(to, image, options.aovs); });
  if (!options.aovOut.empty())
    for (wt::Aov aov : options.aovs)
      files.emplace_back(std::filesystem::path(options.aovOut) / (std::string(wt::aovName(aov)) + ".exr"),
                         [&image, aov](const std::filesystem::path& to) { wt::writeAovImage(to, image, aov); });
  return files;
}

void writeOutputs(const RenderOptions& options, const wt::Image& image, std::FILE* say) {
  for (const auto& [out, write] : outputFiles(options, image)) {
    write(out);
    std::fprintf(say, "wrote %s\n", out.c_str());
  }
}

/// The outputs of a render still under way (a job's periodic image): each
/// file written in full under a hidden name beside it, then all renamed over
/// theirs, unless `final` was set meanwhile (the render's own outputs were
/// written: they win). `mutex` guards `final` and the renames.
void writePartialOutputs(const RenderOptions& options, const wt::Image& image, std::mutex& mutex, const bool& final) {
  std::vector<std::pair<std::filesystem::path, std::filesystem::path>> parts;  // (hidden, output)
  auto removeParts = [&] {
    std::error_code ec;
    for (const auto& part : parts) std::filesystem::remove(part.first, ec);
  };
  try {
    for (const auto& [out, write] : outputFiles(options, image)) {
      std::filesystem::path part =
          out.parent_path() / ("." + out.stem().string() + ".partial" + out.extension().string());
      write(part);
      parts.emplace_back(std::move(part), out);
    }
  } catch (...) {
    removeParts();
    throw;
  }
  std::lock_guard<std::mutex> lock(mutex);
  if (final) return removeParts();
  for (const auto& [part, out] : parts) {
    std::error_code ec;
    std::filesystem::rename(part, out, ec);
    if (ec) {
      removeParts();
      throw wt::OutputError(out.string() + ": cannot replace the file with the merged samples: " + ec.message());
    }
  }
}

/// Parse --aov and --debug, check --aov-out; the AOVs are recorded where either asks.
void parseAovOptions(RenderOptions& options) {
  if (!options.aov.empty()) options.aovs = wt::parseAovList(options.aov);
  if (!options.debug.empty()) options.debugView = wt::parseDebugView(options.debug);
  if (!options.aovOut.empty()) {
    if (options.aovs.empty()) throw std::invalid_argument("--aov-out: names no AOVs to write (add --aov)");
    std::error_code ec;
    if (!std::filesystem::is_directory(options.aovOut, ec))
      throw std::invalid_argument("--aov-out: folder '" + options.aovOut + "' does not exist");
    wt::checkWritable(std::filesystem::path(options.aovOut) / "albedo.exr");
  }
  const bool onlyVariance = options.aovs.size() == 1 && options.aovs[0] == wt::Aov::Variance;
  options.settings.aovs = (!options.aovs.empty() && !onlyVariance) || options.debugView != wt::DebugView::None;
  options.settings.bvhCost = options.debugView == wt::DebugView::BvhCost;
  for (const std::string& out : options.outputs)
    if (!options.aovs.empty() && wt::imageFormatFor(out) == wt::ImageFormat::Png && options.aovOut.empty())
      wt::log::warnOnce(out + ": a PNG holds no AOV layers (write an .exr, or use --aov-out)");
}

/// The scene file's render settings and environment, except where the
/// command line named the option; says what was taken.
void applySceneSettings(const wt::SceneFileSettings& file, const std::string& sceneName, RenderOptions& options) {
  const GivenOptions& given = options.given;
  wt::RenderSettings& s = options.settings;
  std::string taken;
  auto note = [&](const std::string& what) { taken += (taken.empty() ? "" : ", ") + what; };
  if (file.width && !given.width) s.width = *file.width, note("width " + std::to_string(*file.width));
  if (file.height && !given.height) s.height = *file.height, note("height " + std::to_string(*file.height));
  if (file.samplesPerPixel && !given.spp)
    s.samplesPerPixel = *file.samplesPerPixel, note("spp " + std::to_string(*file.samplesPerPixel));
  if (file.maxBounces && !given.maxBounces)
    s.maxBounces = *file.maxBounces, note("max_bounces " + std::to_string(*file.maxBounces));
  if (file.seed && !given.seed) s.seed = *file.seed, note("seed " + std::to_string(*file.seed));
  if (file.exposureStops && !given.exposure && !options.tonemap.physical) {
    char text[64];
    if (file.autoExposure)
      std::snprintf(text, sizeof text, *file.exposureStops == 0.0f ? "auto" : "auto%+g", double(*file.exposureStops));
    else
      std::snprintf(text, sizeof text, "%g", double(*file.exposureStops));
    options.tonemap.exposure = text, note(std::string("exposure ") + text);
  }
  if (file.tonemap && !given.tonemap) options.tonemap.op = *file.tonemap, note("tonemap " + *file.tonemap);
  if (file.integrator && !given.integrator) options.integrator = *file.integrator, note("integrator " + *file.integrator);
  if (const auto& env = file.environment) {
    // --background or --env-map replaces the file's environment as a whole
    if (!given.background && !given.envMap) {
      if (env->color) {
        options.background = {env->color->x, env->color->y, env->color->z};
        note("environment color");
      } else {
        s.environmentMap = env->map;
        if (!given.envIntensity) s.environmentIntensity = env->intensity;
        if (!given.envRotation) s.environmentRotationDegrees = env->rotationDegrees;
        note("environment map " + env->map);
      }
    }
    if (env->hidden && !given.envHidden) s.environmentHidden = true, note("environment hidden");
  }
  if (!taken.empty())
    wt::log::info(sceneName + ": from the scene file: " + taken + " (command-line options take precedence)");
}

/// The render settings the options say (after applySceneSettings): one
/// place, so that `render` and `info` see the same feature set.
wt::RenderSettings renderSettings(const RenderOptions& options) {
  wt::RenderSettings settings = options.settings;
  std::tie(settings.tonemap, settings.exposureStops) = resolveTonemap(options.tonemap);
  for (float c : options.background)
    if (!(c >= 0.0f) || !std::isfinite(c)) throw std::invalid_argument("--background: components must be finite and >= 0");
  settings.background = glm::vec3(options.background[0], options.background[1], options.background[2]);
  settings.integrator = options.integrator == "minimal" ? wt::Integrator::Minimal : wt::Integrator::Path;
  settings.useNee = !options.noNee;
  settings.useMis = !options.noMis;
  if (options.stopOnNan) settings.stopOnNonFinite = true;
  settings.useRussianRoulette = !options.noRr;
  settings.powerHeuristic = options.misHeuristic == "power";
  settings.powerAtLambertian = options.misHeuristic == "auto";
  settings.sobol = options.sampler == "sobol";
  settings.textureFootprint = options.textureFilter == "footprint";
  settings.lightSampler = options.lightSampler == "power" ? wt::LightSampler::Power
                          : options.lightSampler == "tree" ? wt::LightSampler::Tree
                                                           : wt::LightSampler::Auto;
  settings.accumulation = options.accumulation == "single"   ? WT_ACCUMULATE_SINGLE
                          : options.accumulation == "double" ? WT_ACCUMULATE_DOUBLE
                                                             : WT_ACCUMULATE_KAHAN;
  settings.bvhBuilder = *wt::parseBvhBuilder(options.bvh);
  settings.instancing = *wt::parseInstancing(options.instancing);
  settings.packets = options.traversal == "auto";
  settings.packetWidth = options.packetWidth;
  return settings;
}

/// The scene `render` names (the default scene without one), with the scene
/// file's settings applied where the command line did not name them.
wt::SceneFile loadRenderScene(RenderOptions& options) {
  wt::GltfLoadOptions loadOptions;
  loadOptions.sceneIndex = options.sceneIndex;
  loadOptions.cameraIndex = options.camera;
  loadOptions.recenter = !options.noRecenter;
  wt::SceneFile loaded = options.scene.empty() ? wt::SceneFile{wt::loadDefaultScene(loadOptions), {}}
                                               : wt::loadSceneAny(options.scene, loadOptions);
  wt::Scene& scene = loaded.scene;
  applySceneSettings(loaded.settings, scene.sourceName, options);
  applyCameraOptions(options, scene);
  for (const std::string& w : scene.warnings) wt::log::warnOnce(scene.sourceName + ": " + w);
  if (options.tessellate > 0 && !scene.displacedMeshes.empty()) {
    const std::size_t made = wt::tessellateDisplaced(scene, options.tessellate);
    wt::log::info("--tessellate " + std::to_string(options.tessellate) + ": the displaced meshes as " +
                  std::to_string(made) + " triangles");
  }
  if (scene.triangles.empty() && scene.spheres.empty() && scene.curves.empty() && scene.sdfGrids.empty() &&
      scene.displacedMeshes.empty())
    wt::log::warnOnce(scene.sourceName + ": the scene has no geometry");
  return loaded;
}

int runScaleOutRender(RenderOptions options, wt::MpiWorld& world);

int runRender(RenderOptions options) {
  // several devices or ranks, or a chunked render on one (the order they share)
  if (g_world->active() || options.device == "all" || options.device.find(',') != std::string::npos ||
      options.chunkSppGiven)
    return runScaleOutRender(std::move(options), *g_world);
  wt::log::setQuiet(options.quiet);
  wt::log::setVerbose(options.verbose);
  if (!options.kernelDir.empty()) wt::setKernelDirectory(std::filesystem::path(options.kernelDir));

  // Fail on an unwritable output or a bad AOV before spending any time rendering.
  for (const std::string& out : options.outputs) wt::checkWritable(out);
  parseAovOptions(options);
  StartupTimeline& startup = *g_startup;
  startup.mark("arguments");

  auto loadStart = std::chrono::steady_clock::now();
  wt::SceneFile loaded = loadRenderScene(options);
  wt::Scene& scene = loaded.scene;
  double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - loadStart).count();
  startup.mark("scene loaded");

  if (!options.profileJson.empty()) {
    options.profile = true;
    const std::filesystem::path folder = std::filesystem::absolute(options.profileJson).parent_path();
    std::error_code ec;
    if (!std::filesystem::is_directory(folder, ec))
      throw std::invalid_argument("--profile-json: folder '" + folder.string() + "' does not exist");
  }
  // on the main thread: a thread that starts PoCL's LLVM gets LLVM's own signal stack,
  // which AddressSanitizer fails to unmap when that thread exits
  wt::DeviceInfo device = wt::selectDevice(options.device);
  startup.mark("OpenCL platforms and devices");
  // profiling events only when asked: without them the queue has no profiling property
  wt::Context context(device, options.profile);
  startup.mark("context");
  wt::RenderSettings settings = renderSettings(options);
  settings.profile = options.profile;
  settings.sceneOutlivesRenderer = true;  // `loaded` is destroyed after `renderer`
  wt::Renderer renderer(context, scene, settings);
  startup.mark("renderer");
  startup.part("scene buffers", renderer.stats().sceneSeconds);
  startup.part("lights", renderer.stats().lightsSeconds);
  startup.part("program", renderer.stats().programSeconds);
  startup.part("kernels", renderer.stats().kernelsSeconds);
  startup.part("buffers", renderer.stats().buffersSeconds);
  if (std::size_t left = renderer.sceneBuffers().skippedPrimitives())
    wt::log::warnOnce(scene.sourceName + ": " + std::to_string(left) +
                      " primitives left out (a sphere of radius <= 0, a curve segment of radius 0, an SDF grid without cells or "
                      "with a singular placement, or non-finite values)");
  const wt::BvhBuildStats& bvh = renderer.sceneBuffers().bvhStats();
  wt::log::info("scene " + scene.sourceName + ": " + std::to_string(scene.triangles.size()) + " triangles" +
                (scene.spheres.empty() ? std::string() : ", " + std::to_string(scene.spheres.size()) + " spheres") +
                (scene.curves.empty() ? std::string() : ", " + std::to_string(scene.curves.size()) + " curves") +
                (scene.sdfGrids.empty() ? std::string()
                                        : ", " + std::to_string(scene.sdfGrids.size()) + " SDF grids (" +
                                              std::to_string(renderer.sceneBuffers().primitiveCount(WT_PRIM_SDF_GRID)) +
                                              " bricks)") +
                (scene.displacedMeshes.empty()
                     ? std::string()
                     : ", " + std::to_string(scene.displacedMeshes.size()) + " displaced meshes (" +
                           std::to_string(renderer.sceneBuffers().primitiveCount(WT_PRIM_DISPLACED)) +
                           " base triangles, level " + std::to_string(wt::displacedLevel(scene.displacedMeshes[0])) + ")") +
                ", loaded in " + std::to_string(int(loadSeconds * 1e3)) + " ms; BVH (" +
                wt::bvhBuilderName(settings.bvhBuilder) + ") " +
                std::to_string(bvh.nodeCount) + " nodes built in " +
                std::to_string(bvh.buildSeconds * 1e3).substr(0, 6) + " ms; device " + device.name);
  {
    const wt::SceneBuffers& buffers = renderer.sceneBuffers();
    const double perTriangle = double(buffers.triangleBytes()) / double(std::max<std::size_t>(1, scene.triangles.size()));
    char line[256];
    std::snprintf(line, sizeof line,
                  "geometry on the device: %.1f B per scene triangle (nodes, triangles%s), %zu B with normals and "
                  "materials; instancing %s: %zu instances, %zu of %zu triangles in instanced copies",
                  perTriangle, buffers.instanceCount() > 0 ? ", instances" : "", buffers.geometryBytes(),
                  options.instancing.c_str(), buffers.instanceCount(), buffers.instancedTriangles(),
                  scene.triangles.size());
    wt::log::debug(line);
    if (buffers.hasTextures()) {
      // texels of the images' finest levels
      std::size_t baseTexels = 0;
      std::vector<bool> first(scene.textures.levels.size(), false);
      for (const WtTexture& t : scene.textures.textures) first[t.first_level] = true;
      for (std::size_t i = 0; i < first.size(); ++i)
        if (first[i]) baseTexels += std::size_t(scene.textures.levels[i].width) * scene.textures.levels[i].height;
      std::snprintf(line, sizeof line,
                    "textures: %zu images, %zu textures, %.1f MiB on the device (%.2f B per finest-level texel with "
                    "its mips), decoded and filtered in %.0f ms, uploaded in %.1f ms",
                    scene.textures.imageCount(), scene.textures.textures.size(),
                    double(buffers.textureBytes) / (1 << 20),
                    double(buffers.textureBytes) / double(std::max<std::size_t>(baseTexels, 1)),
                    scene.textureSeconds * 1e3, buffers.textureUploadSeconds * 1e3);
      wt::log::debug(line);
    }
  }

  {
    std::string names;
    for (const std::string& n : wt::featureNames(renderer.features())) names += " " + n;
    wt::log::debug("features:" + names + (settings.generalProgram ? " (general program: every switch on)" : "") +
                   "; program built in " + std::to_string(int(renderer.stats().programSeconds * 1e3)) + " ms");
  }

  // error against a reference at power-of-two sample counts (not timed)
  std::optional<wt::Image> reference;
  std::FILE* errorOut = nullptr;
  if (!options.reference.empty()) {
    reference = wt::readExr(options.reference);
    if (reference->width != settings.width || reference->height != settings.height)
      throw std::invalid_argument(options.reference + ": reference is " + std::to_string(reference->width) + "x" +
                                  std::to_string(reference->height) + ", the render " +
                                  std::to_string(settings.width) + "x" + std::to_string(settings.height));
    errorOut = options.errorLog.empty() ? stdout : std::fopen(options.errorLog.c_str(), "w");
    if (!errorOut) throw std::runtime_error(options.errorLog + ": cannot write the error log");
    std::fprintf(errorOut, "samples,seconds,rmse,relmse,relmse_raw,p99,mean_ratio\n");
  }
  // status lines go to stderr while stdout carries the error log, so stdout stays one CSV
  std::FILE* say = errorOut == stdout ? stderr : stdout;
  auto logError = [&]() {
    wt::ImageError e = wt::imageError(renderer.readImage(), *reference);
    std::fprintf(errorOut, "%d,%.6f,%.8g,%.8g,%.8g,%.8g,%.6f\n", renderer.stats().samplesDone,
                 renderer.stats().seconds, e.rmse, e.relMse, e.relMseRaw, e.p99, e.meanRatio);
    std::fflush(errorOut);
  };

  // checkpoints beside the first output; a resumed render must be the same render
  const std::filesystem::path checkpointPath = wt::checkpointPathFor(options.outputs.front());
  std::vector<wt::CheckpointField> identity;
  if (options.resume || options.checkpointSeconds > 0.0) {
    auto start = std::chrono::steady_clock::now();
    identity = wt::checkpointIdentity(scene, renderer);
    wt::log::debug("checkpoint identity (scene, environment and kernel hashes) in " +
                   std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()) + " s");
  }
  if (options.resume) {
    wt::Checkpoint saved = wt::readCheckpoint(checkpointPath);
    wt::requireSameRender(checkpointPath, saved, identity);
    if (saved.device != device.name)
      wt::log::warnOnce(checkpointPath.string() + ": rendered on '" + saved.device + "', resumed on '" + device.name +
                        "': rounding may differ from an uninterrupted render");
    renderer.restoreAccumulation(saved.accumulation);
    wt::log::info("resumed from " + checkpointPath.string() + " at " + std::to_string(saved.accumulation.samplesDone) +
                  " samples");
  }
  const int resumedSamples = renderer.stats().samplesDone;
  int checkpointSamples = resumedSamples;
  auto saveCheckpoint = [&]() {
    auto start = std::chrono::steady_clock::now();
    wt::Checkpoint c;
    c.identity = identity;
    c.device = device.name;
    c.pixels = std::uint64_t(settings.width) * std::uint64_t(settings.height);
    c.accumulation = renderer.saveAccumulation();
    wt::writeCheckpoint(checkpointPath, c);
    checkpointSamples = c.accumulation.samplesDone;
    wt::log::debug("checkpoint " + checkpointPath.string() + " at " + std::to_string(checkpointSamples) +
                   " samples written in " +
                   std::to_string(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()) + " s");
  };

  // a render only --time or --target-error bounds has no sample limit
  int spp = options.settings.samplesPerPixel;
  if ((options.timeSeconds > 0.0 || options.targetError > 0.0) && !options.given.spp && !loaded.settings.samplesPerPixel)
    spp = wt::kUnboundedSamples;
  wt::Halting halting({spp, options.timeSeconds, options.targetError}, resumedSamples);
  auto estimateError = [&]() {
    auto start = std::chrono::steady_clock::now();
    const double e = std::sqrt(wt::estimatedRelMse(renderer.readRadiance()));
    const double readSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int rendered = renderer.stats().samplesDone - resumedSamples;
    halting.recordError(renderer.stats().samplesDone, e, readSeconds,
                        rendered > 0 ? renderer.stats().seconds / rendered : 0.0);
  };

  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  const bool tty = isatty(STDERR_FILENO);
  const auto loopStart = std::chrono::steady_clock::now();
  auto lastReport = loopStart, lastCheckpoint = loopStart;
  auto since = [](std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  };
  auto progress = [&](bool last) {
    const wt::RenderStats& st = renderer.stats();
    const int rendered = st.samplesDone - resumedSamples;
    const std::string line = wt::progressLine(halting, st.samplesDone, st.seconds > 0.0 ? st.raysTraced / st.seconds * 1e-6 : 0.0,
                                              since(loopStart), rendered > 0 ? st.seconds / rendered : 0.0, last);
    // pad over the longer line it replaces
    std::fprintf(stderr, tty ? "\r%-78s%s" : "%s%s\n", line.c_str(), tty && last ? "\n" : "");
    std::fflush(stderr);
    lastReport = std::chrono::steady_clock::now();
  };
  wt::HaltReason reason = wt::HaltReason::None;
  std::string failure;
  try {
    while (!g_interrupted) {
      reason = halting.check(renderer.stats().samplesDone, since(loopStart));
      if (reason != wt::HaltReason::None) break;
      renderer.renderSample();
      int done = renderer.stats().samplesDone;
      if (done == resumedSamples + 1) startup.mark("first sample");
      if (reference && ((done & (done - 1)) == 0 || done == spp)) logError();
      if (halting.wantsErrorEstimate(done)) estimateError();
      if (options.checkpointSeconds > 0.0 && since(lastCheckpoint) >= options.checkpointSeconds) {
        saveCheckpoint();
        lastCheckpoint = std::chrono::steady_clock::now();
      }
      // a terminal line redrawn ten times a second; elsewhere a line every 5 s
      if (!options.quiet && since(lastReport) > (tty ? 0.1 : 5.0)) progress(false);
    }
  } catch (const std::exception& e) {
    failure = e.what();
  }
  if (!options.quiet && renderer.stats().samplesDone > resumedSamples) progress(true);
  const int done = renderer.stats().samplesDone;
  if (failure.empty() && options.checkpointSeconds > 0.0 && done > checkpointSamples) {
    try {
      saveCheckpoint();
    } catch (const std::exception& e) {
      failure = e.what();
    }
  }

  // why it stopped, and the error there
  if (failure.empty() && done > 0) {
    const char* why = reason == wt::HaltReason::Time          ? "--time budget reached"
                      : reason == wt::HaltReason::TargetError ? "--target-error reached"
                      : reason == wt::HaltReason::Samples     ? "--spp reached"
                                                              : "interrupted";
    std::fprintf(say, "stopped after %d samples (%s), %s of rendering\n", done, why, wt::formatDuration(since(loopStart)).c_str());
    if (options.targetError > 0.0 || reference) {
      if (halting.lastErrorSamples() != done) estimateError();
      std::fprintf(say, "error at %d samples: estimated %.5f", done, halting.lastError());
      if (reference) {
        wt::ImageError e = wt::imageError(renderer.readRadiance(), *reference);
        std::fprintf(say, ", measured %.5f against %s", std::sqrt(std::max(0.0, e.relMse)), options.reference.c_str());
        if ((done & (done - 1)) != 0 && done != spp) logError();
      }
      std::fprintf(say, " (relative RMS error of the pixel means)\n");
    }
    if (halting.errorChecks() > 0)
      wt::log::debug(std::to_string(halting.errorChecks()) + " error estimates read back in " +
                     std::to_string(halting.errorCheckSeconds()) + " s, " +
                     std::to_string(100.0 * halting.errorCheckSeconds() / std::max(1e-9, renderer.stats().seconds)) +
                     " % of the " + std::to_string(renderer.stats().seconds) + " s of sample passes");
    std::fflush(stdout);
  }

  if (renderer.stats().samplesDone > resumedSamples) {
    const wt::RenderProfile& profile = renderer.profile();
    if (options.profile) {
      std::fprintf(say, "%s", wt::profileTable(profile).c_str());
      std::fflush(say);
    } else {
      wt::log::debug(wt::profileSummary(profile));
    }
    if (!options.profileJson.empty()) {
      std::ofstream out(options.profileJson);
      out << wt::profileJson(profile);
      if (!out.flush()) throw std::runtime_error(options.profileJson + ": cannot write the profile");
      std::fprintf(say, "wrote %s\n", options.profileJson.c_str());
    }
  }
  if (errorOut && errorOut != stdout) std::fclose(errorOut);
  if (renderer.stats().samplesDone > 0)
    wt::log::debug("rendered " + std::to_string(renderer.stats().samplesDone) + " samples in " +
                   std::to_string(renderer.stats().seconds) + " s: " +
                   std::to_string(renderer.stats().seconds / renderer.stats().samplesDone * 1e3) + " ms per sample");

  // Whatever happened, keep what was accumulated.
  if (renderer.stats().samplesDone > 0) {
    startup.mark("other samples");
    // tone-mapped on the device only where a PNG shows it (or its auto exposure is reported)
    const bool png = std::any_of(options.outputs.begin(), options.outputs.end(), [](const std::string& out) {
      return wt::imageFormatFor(out) == wt::ImageFormat::Png;
    });
    // PNGs alone (no EXR, AOV folder or debug view) need only the 8-bit pixels
    const bool pngOnly = options.aovOut.empty() && options.debugView == wt::DebugView::None &&
                         std::all_of(options.outputs.begin(), options.outputs.end(), [](const std::string& out) {
                           return wt::imageFormatFor(out) == wt::ImageFormat::Png;
                         });
    wt::Image image = pngOnly                                   ? renderer.readDisplayImage()
                      : png || settings.tonemap.autoExposure ? renderer.readImage()
                                                              : renderer.readRadiance();
    startup.mark("image read");
    wt::applyDebugView(image, options.debugView);
    writeOutputs(options, image, say);
    startup.mark("written");
    // the kernel cache entries this render's misses left: written by a process of their own
    wt::storeDeferredProgramsInBackground(device);
    wt::log::debug(startup.line());
    if (settings.tonemap.autoExposure) {
      const float scale = renderer.autoExposure();
      wt::log::info("auto exposure: scale " + std::to_string(scale) + " (log-average luminance " +
                    std::to_string(WT_TONEMAP_MIDDLE_GREY / scale) + ")");
    }
    if (renderer.stats().nonFiniteSamples > 0) {
      // a pixel that lost samples has fewer than the passes rendered
      std::size_t pixels = 0;
      for (std::uint32_t n : image.samples) pixels += n < std::uint32_t(renderer.stats().samplesDone);
      wt::log::warnOnce(std::to_string(renderer.stats().nonFiniteSamples) + " NaN/Inf samples discarded in " +
                        std::to_string(pixels) + " pixels");
    }
  }
  if (!failure.empty()) {
    wt::log::error("render failed after " + std::to_string(renderer.stats().samplesDone) +
                   " samples: " + failure);
    return 1;
  }
  if (g_interrupted) {
    wt::log::error("interrupted after " + std::to_string(renderer.stats().samplesDone) +
                   " samples; the image so far was written");
    return 130;
  }
  // Every output is written and closed: leave without releasing the device's
  // buffers, programs and worker threads one by one (the exit frees them).
  std::fflush(nullptr);
  std::_Exit(0);
}

/// `render` split into sample chunks over several devices (--device 0,1,
/// all) and, under an MPI launcher, several processes (cli/scale_out.h).
/// Every rank loads the scene and builds its renderers; a rank that cannot
/// stops the whole job at start, with its message, on rank 0.
int runScaleOutRender(RenderOptions options, wt::MpiWorld& world) {
  const bool root = world.rank() == 0;
  // a job of several ranks keeps its merged samples on disk as it goes: a
  // launcher may SIGKILL rank 0 with no warning when another rank dies (srun)
  const bool defaultCheckpoint = world.active() && options.checkpointSeconds < 0.0;
  if (options.checkpointSeconds < 0.0)
    options.checkpointSeconds = world.active() ? wt::ScaleOutOptions::kJobCheckpointSeconds : 0.0;
  // there each checkpoint also writes the outputs: an image that outlives rank 0
  const bool partialOutputs = world.active() && options.checkpointSeconds > 0.0;
  wt::log::setQuiet(options.quiet || !root);
  wt::log::setVerbose(options.verbose && root);
  std::optional<wt::SceneFile> loaded;
  wt::DeviceSet devices;
  wt::RenderSettings settings;
  std::vector<wt::CheckpointField> identity;
  std::optional<wt::Moments> start;
  std::optional<wt::Image> reference;
  const std::filesystem::path checkpointPath = wt::checkpointPathFor(options.outputs.front());
  std::string setupError;
  wt::Fnv64 renderHash;
  const auto setupStart = std::chrono::steady_clock::now();
  try {
    if (!options.kernelDir.empty()) wt::setKernelDirectory(std::filesystem::path(options.kernelDir));
    if (root)
      for (const std::string& out : options.outputs) wt::checkWritable(out);
    parseAovOptions(options);
    // the stage times are per device queue; a split render has one per device and rank
    if (options.profile || !options.profileJson.empty())
      throw std::invalid_argument("--profile/--profile-json: not on several devices or ranks, nor with --chunk-spp "
                                  "(profile a one-device render)");
    loaded = loadRenderScene(options);
    settings = renderSettings(options);
    settings.sceneOutlivesRenderer = true;  // `loaded` is destroyed after `devices`
    if (root && !options.reference.empty()) {
      reference = wt::readExr(options.reference);
      if (reference->width != settings.width || reference->height != settings.height)
        throw std::invalid_argument(options.reference + ": reference is " + std::to_string(reference->width) + "x" +
                                    std::to_string(reference->height) + ", the render " +
                                    std::to_string(settings.width) + "x" + std::to_string(settings.height));
    }
    const std::vector<wt::DeviceInfo> infos = wt::selectDevices(options.device);
    for (std::size_t d = 0; d < infos.size(); ++d) {
      devices.contexts.push_back(std::make_unique<wt::Context>(infos[d]));
      devices.renderers.push_back(std::make_unique<wt::Renderer>(*devices.contexts.back(), loaded->scene, settings));
      devices.names.push_back("device " + std::to_string(infos[d].index) + " (" + infos[d].name + ")");
      // the image is read through the resolve and tone-map kernels, which
      // PoCL builds at their first launch: here, not after a signal, when
      // mpirun's SIGKILL follows in a second and a cold build takes longer
      if (root) {
        devices.renderers.back()->resetAccumulation(0);
        (void)devices.renderers.back()->readImage();
      }
    }
    identity = wt::checkpointIdentity(loaded->scene, *devices.renderers.front());
    for (const wt::CheckpointField& f : identity) renderHash.bytes(f.key.data(), f.key.size()), renderHash.bytes(f.value.data(), f.value.size());
    const std::size_t pixels = std::size_t(settings.width) * std::size_t(settings.height);
    if (root && options.resume) {
      wt::Checkpoint saved = wt::readCheckpoint(checkpointPath);
      wt::requireSameRender(checkpointPath, saved, identity);
      start = wt::momentsFromAccumulation(saved.accumulation, settings.accumulation, 0);
      wt::log::info("resumed from " + checkpointPath.string() + " at " + std::to_string(start->sampleEnd) + " samples");
    } else {
      start = wt::emptyMoments(pixels, 0, settings.aovs);
    }
  } catch (const std::exception& e) {
    setupError = e.what();
  }
  if (setupError.empty()) setupError = world.unsupportedLaunch();
  try {
    // a start (scene, BVH, kernel build) takes far longer than a sample
    // pass, and one rank's cold start longer than another's warm one
    const double startTimeout = options.startTimeout > 0.0
                                    ? options.startTimeout
                                    : std::max(options.rankTimeout, wt::ScaleOutOptions::kDefaultRankTimeout);
    world.agreeOnStart(setupError, renderHash.value(), startTimeout);
  } catch (const std::exception& e) {
    // on orted's machine under --enable-recovery a non-zero status hangs mpirun: 0, the error said
    const bool onlyZeroEnds = world.onRecoveringDaemon();
    if (!root) return onlyZeroEnds ? 0 : 1;  // rank 0 reports every rank's failure
    if (world.launcherIgnoresExitStatus()) {
      wt::log::error(e.what());
      world.abort(1);
    }
    if (onlyZeroEnds) {
      wt::log::error(std::string(e.what()) + " (exit status 0: there mpirun waits forever after any other)");
      return 0;
    }
    throw;
  }
  const double setupSeconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - setupStart).count();
  std::signal(SIGINT, onInterrupt);
  std::signal(SIGTERM, onInterrupt);
  const std::function<bool()> interrupted = [] { return g_interrupted.load(); };
  if (!root) return wt::serveRender(devices, world, interrupted, options.rankTimeout);

  const wt::Scene& scene = loaded->scene;
  std::string names;
  for (const std::string& n : devices.names) names += (names.empty() ? "" : ", ") + n;
  int spp = options.settings.samplesPerPixel;
  if ((options.timeSeconds > 0.0 || options.targetError > 0.0) && !options.given.spp && !loaded->settings.samplesPerPixel)
    spp = wt::kUnboundedSamples;
  const int chunkSpp = options.chunkSpp > 0 ? options.chunkSpp : wt::defaultChunkSpp(spp);
  wt::log::info("scene " + scene.sourceName + ": " + std::to_string(scene.triangles.size()) + " triangles; " +
                (world.active() ? std::to_string(world.size()) + " ranks, " : std::string()) + "on " + names +
                "; chunks of " + std::to_string(chunkSpp) + " samples; set up in " +
                std::to_string(int(setupSeconds * 1e3)) + " ms");

  if (defaultCheckpoint) {
    std::string files;
    for (const std::string& out : options.outputs) files += out + ", ";
    char every[32];
    std::snprintf(every, sizeof every, "%g", options.checkpointSeconds);
    wt::log::warnOnce("a job of " + std::to_string(world.size()) + " ranks: every " + every + " s rank 0 writes the " +
                      "merged samples to " + files + "and the checkpoint " + checkpointPath.string() +
                      " (--resume continues from it), so that a job killed as a whole (Slurm kills every rank when "
                      "one dies) loses at most that; --checkpoint SECONDS sets the interval, --checkpoint 0 turns "
                      "it off (docs/scale-out.md, Faults)");
  } else if (world.active() && world.launchedBySrun() && options.checkpointSeconds <= 0.0) {
    // Slurm's PMIx plugin SIGKILLs the whole step about a second after any task dies, with no signal before
    wt::log::warnOnce("under srun --mpi=pmix, Slurm kills every rank (SIGKILL) about a second after one dies, "
                      "whatever --kill-on-bad-exit says: rank 0 cannot write the merged samples then, and with "
                      "--checkpoint 0 nothing keeps them (docs/scale-out.md, Faults)");
  }
  wt::ScaleOutOptions run;
  run.samplesPerPixel = spp;
  run.chunkSpp = chunkSpp;
  run.timeSeconds = options.timeSeconds;
  run.quiet = options.quiet;
  run.interrupted = interrupted;
  run.checkpointSeconds = options.checkpointSeconds;
  run.targetError = options.targetError;
  run.rankTimeoutSeconds = options.rankTimeout;
  const std::size_t pixels = std::size_t(settings.width) * std::size_t(settings.height);
  // --reference: the error of the merged prefix at the first chunk boundary
  // at or past 1, 2, 4, ... samples and at the end (the one-device render
  // logs every power of two; a chunk boundary is where the split has one)
  std::FILE* errorOut = nullptr;
  struct CloseLog {
    std::FILE*& f;
    ~CloseLog() {
      if (f && f != stdout) std::fclose(f);
    }
  } closeLog{errorOut};
  int nextLogged = 1, lastLogged = 0;
  const auto renderStart = std::chrono::steady_clock::now();
  auto logError = [&](const wt::Moments& m) {
    const wt::ImageError e = wt::imageError(wt::imageFromMoments(m, settings.width, settings.height), *reference);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - renderStart).count();
    std::fprintf(errorOut, "%d,%.6f,%.8g,%.8g,%.8g,%.8g,%.6f\n", m.sampleEnd, seconds, e.rmse, e.relMse, e.relMseRaw,
                 e.p99, e.meanRatio);
    std::fflush(errorOut);
    lastLogged = m.sampleEnd;
  };
  if (reference) {
    errorOut = options.errorLog.empty() ? stdout : std::fopen(options.errorLog.c_str(), "w");
    if (!errorOut) throw std::runtime_error(options.errorLog + ": cannot write the error log");
    std::fprintf(errorOut, "samples,seconds,rmse,relmse,relmse_raw,p99,mean_ratio\n");
    run.merged = [&](const wt::Moments& m) {
      if (m.sampleEnd < nextLogged && m.sampleEnd != spp) return;
      logError(m);
      while (nextLogged <= m.sampleEnd) nextLogged *= 2;
    };
  }
  // status lines go to stderr while stdout carries the error log, so stdout stays one CSV
  std::FILE* say = errorOut == stdout ? stderr : stdout;
  auto saveCheckpoint = [&](const wt::Moments& m) {
    wt::Checkpoint c;
    c.identity = identity;
    c.device = devices.contexts.front()->info().name;
    c.pixels = pixels;
    c.accumulation = wt::accumulationFromMoments(m, settings.accumulation);
    wt::writeCheckpoint(checkpointPath, c);
  };
  // periodic checkpoints on a thread of their own: the write waits for the
  // disk (fsync), and the coordinator must keep taking results and signals
  // (under mpirun a dying rank leaves rank 0 about a second before SIGKILL)
  std::thread checkpointThread;
  std::atomic<bool> checkpointBusy{false};
  std::string checkpointError;
  // the periodic outputs (partialOutputs) and the final ones: the final win
  std::mutex outputsMutex;
  bool finalOutputs = false;
  std::unique_ptr<wt::Context> toneContext;  // the checkpoint thread's own, for a PNG's tone mapping
  bool needsTonemap = false;
  for (const std::string& out : options.outputs)
    needsTonemap |= options.debugView == wt::DebugView::None && wt::imageFormatFor(out) == wt::ImageFormat::Png;
  auto writePartial = [&](const wt::Moments& m) {
    // the image the final write would give for these samples, made on the
    // host: rank 0's devices are busy rendering chunks
    wt::Image image = wt::resolvedImage(m, settings.width, settings.height);
    if (needsTonemap) {
      if (!toneContext) toneContext = std::make_unique<wt::Context>(devices.contexts.front()->info());
      wt::tonemapImage(*toneContext, image, settings.tonemap, settings.exposureStops);
    }
    wt::applyDebugView(image, options.debugView);
    writePartialOutputs(options, image, outputsMutex, finalOutputs);
  };
  // the default's interval stretches where a write takes long: at most 1/20 of the time writing
  std::atomic<double> writeSeconds{0.0};
  auto writeStart = std::chrono::steady_clock::now();
  auto finishCheckpoint = [&] {
    if (checkpointThread.joinable()) checkpointThread.join();
  };
  struct JoinOnExit {
    std::thread& t;
    ~JoinOnExit() {
      if (t.joinable()) t.join();
    }
  } joinOnExit{checkpointThread};
  if (options.checkpointSeconds > 0.0)
    run.checkpoint = [&](const wt::Moments& m) {
      if (checkpointBusy) return;  // the previous one is still being written: the next interval takes this
      if (defaultCheckpoint && std::chrono::duration<double>(std::chrono::steady_clock::now() - writeStart).count() <
                                   20.0 * writeSeconds)
        return;
      finishCheckpoint();
      checkpointBusy = true;
      writeStart = std::chrono::steady_clock::now();
      checkpointThread = std::thread([&, copy = m] {
        try {
          saveCheckpoint(copy);
          if (partialOutputs) writePartial(copy);
          const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - writeStart).count();
          writeSeconds = took;
          wt::log::debug("checkpoint" + std::string(partialOutputs ? " and outputs" : "") + " of " +
                         std::to_string(copy.sampleEnd) + " samples written in " + std::to_string(took) + " s");
        } catch (const std::exception& e) {
          checkpointError = e.what();
        }
        checkpointBusy = false;
      });
    };
  const int resumed = start->sampleEnd;
  // whatever happened, keep what was merged; the exit status, and whether
  // only an abort may end the process (a lost device's thread is left behind)
  auto keepMerged = [&](wt::ScaleOutResult& result, int& code) -> bool {
    const int done = result.merged.sampleEnd;
    {
      // a periodic write still under way must not replace these
      std::lock_guard<std::mutex> lock(outputsMutex);
      finalOutputs = true;
    }
    if (done > 0) {
      wt::Renderer& out = *devices.renderers[std::size_t(result.outputDevice)];
      out.restoreAccumulation(wt::accumulationFromMoments(result.merged, settings.accumulation));
      wt::Image image = out.readImage();
      wt::applyDebugView(image, options.debugView);
      writeOutputs(options, image, say);
      if (result.merged.nonFiniteSamples > 0)
        wt::log::warnOnce(std::to_string(result.merged.nonFiniteSamples) + " NaN/Inf samples discarded");
    }
    const std::string kept = done > 0 ? "; the " + std::to_string(done) + " merged samples were written"
                                      : "; no chunk was merged, nothing written";
    // said before the checkpoint, which waits for the disk (fsync): under
    // mpirun a dying rank leaves rank 0 about a second before SIGKILL
    if (result.interrupted && result.failure.empty())
      wt::log::error("stopped by a signal after " + std::to_string(done) + " of " + std::to_string(spp) + " samples" +
                     (world.active() ? " (under mpirun also when a rank died or was killed: mpirun then stops every rank" +
                                           (result.silentLongest.empty() ? std::string()
                                                                         : "; the rank silent longest: " + result.silentLongest) +
                                           ")"
                                     : "") +
                     kept);
    const bool failedBefore = !result.failure.empty();
    auto sayFailure = [&] {
      wt::log::error("render failed after " + std::to_string(done) + " of " + std::to_string(spp) +
                     " samples: " + result.failure + kept);
    };
    if (failedBefore) sayFailure();  // before the checkpoint too
    finishCheckpoint();
    if (!checkpointError.empty() && result.failure.empty()) result.failure = checkpointError;
    // the default's checkpoint is for a job that did not finish; once the image is whole it goes
    const bool dropCheckpoint =
        defaultCheckpoint && !options.resume && result.failure.empty() && !result.interrupted;
    if (dropCheckpoint) {
      std::error_code ec;
      std::filesystem::remove(checkpointPath, ec);
    } else if (options.checkpointSeconds > 0.0 && done > resumed) {
      try {
        saveCheckpoint(result.merged);
      } catch (const std::exception& e) {
        if (result.failure.empty()) result.failure = e.what();
      }
    }
    // a lost device's thread is left behind: only an abort ends the process safely
    const bool lost = !result.lostRanks.empty() || !result.lostDevices.empty();
    const bool mustAbort = (world.active() && (lost || !result.failure.empty() || result.interrupted)) ||
                           !result.lostDevices.empty();
    if (!result.failure.empty()) {
      if (!failedBefore) sayFailure();
      code = 1;
      return mustAbort;
    }
    if (result.interrupted) {  // said above
      code = 130;
      return mustAbort;
    }
    if (mustAbort) {
      // the image is whole (the lost ranks' and devices' chunks were rendered
      // again); they may still run or hang, and MPI_Finalize or a return
      // (destroying the devices) would wait for them
      wt::log::info("finished without " + std::to_string(result.lostRanks.size()) + " lost rank(s) and " +
                    std::to_string(result.lostDevices.size()) + " lost device(s); ending (the image is complete)");
    }
    code = 0;
    return mustAbort;
  };
  // rank 0 stuck inside MPI (MpiGate in cli/scale_out.cpp): keep what was merged from the watchdog
  run.rescue = [&](wt::ScaleOutResult& result) {
    int code = 1;
    (void)keepMerged(result, code);
    world.exitWithoutMpi(code);
  };
  wt::ScaleOutResult result = wt::coordinateRender(devices, run, std::move(*start), world);
  const int done = result.merged.sampleEnd;
  std::string byRank;
  for (std::size_t r = 0; r < result.chunksByRank.size(); ++r)
    byRank += (r ? ", " : "") + std::to_string(result.chunksByRank[r]);
  wt::log::debug(std::to_string(result.chunks) + " chunks merged in " + std::to_string(result.mergeSeconds) +
                 " s of " + std::to_string(result.seconds) + " s; " + std::to_string(result.localChunks) +
                 " chunks on this process spent " + std::to_string(result.localOverheadSeconds) +
                 " s outside sample passes" +
                 (world.active() ? "; " + std::to_string(result.bytesReceived) + " result bytes received in " +
                                       std::to_string(result.receiveSeconds) + " s; chunks by rank: " + byRank
                                 : std::string()));
  if (result.failure.empty() && !result.interrupted && done > 0) {
    const char* why = result.reason == wt::HaltReason::Time          ? "--time budget reached"
                      : result.reason == wt::HaltReason::TargetError ? "--target-error reached"
                                                                     : "--spp reached";
    std::fprintf(say, "stopped after %d samples (%s), %s of rendering\n", done, why,
                wt::formatDuration(result.seconds).c_str());
    if (options.targetError > 0.0 || reference) {
      // the estimate of the merged image (the one-device render's line)
      const wt::Image merged = wt::imageFromMoments(result.merged, settings.width, settings.height);
      const double estimate =
          result.lastErrorSamples == done ? result.lastError : std::sqrt(wt::estimatedRelMse(merged));
      if (reference && lastLogged != done) logError(result.merged);  // the last row, before the line
      std::fprintf(say, "error at %d samples: estimated %.5f", done, estimate);
      if (reference) {
        wt::ImageError e = wt::imageError(merged, *reference);
        std::fprintf(say, ", measured %.5f against %s", std::sqrt(std::max(0.0, e.relMse)), options.reference.c_str());
      }
      std::fprintf(say, " (relative RMS error of the pixel means)\n");
    }
    std::fflush(stdout);
  }

  int code = 0;
  const bool mustAbort = keepMerged(result, code);
  // under srun an MPI_Abort(0) comes back as 137, a killed task's status, as when the image is lost
  if (mustAbort && code == 0 && world.launchedBySrun()) code = wt::MpiWorld::kCompleteWithLosses;
  if (mustAbort) world.abort(code);
  return code;
}

/// `wavetrace info`: the scene's feature set (as `render` would derive it
/// with the same options), the switches it compiles in, and its statistics.
int runInfo(RenderOptions options) {
  wt::log::setQuiet(options.quiet);
  wt::GltfLoadOptions loadOptions;
  loadOptions.sceneIndex = options.sceneIndex;
  loadOptions.cameraIndex = options.camera;
  loadOptions.recenter = !options.noRecenter;
  wt::SceneFile loaded = wt::loadSceneAny(options.scene, loadOptions);
  wt::Scene& scene = loaded.scene;
  applySceneSettings(loaded.settings, scene.sourceName, options);
  for (const std::string& w : scene.warnings) wt::log::warnOnce(scene.sourceName + ": " + w);
  wt::DeviceInfo device = wt::selectDevice(options.device);
  wt::Context context(device);
  const wt::RenderSettings settings = renderSettings(options);
  wt::BvhBuildOptions bvhOptions;  // as the renderer builds it
  bvhOptions.builder = settings.bvhBuilder;
  bvhOptions.maxLeafSize = 0;
  bvhOptions.instancing = settings.instancing;
  wt::SceneBuffers buffers(context, scene, bvhOptions);
  const wt::FeatureSet features = wt::sceneFeatures(scene, buffers, settings);

  std::printf("scene: %s\n", options.scene.c_str());
  std::printf("features:");
  for (const std::string& name : wt::featureNames(features)) std::printf(" %s", name.c_str());
  std::printf("\nswitches (on %s):", device.name.c_str());
  // the light kinds as the renderer's list holds them (an environment entry where the settings give one)
  const wt::LightList lights =
      wt::buildLightList(scene, buffers, features.environmentMap || features.constantSky ? 1.0 : 0.0,
                         settings.lightSampler, settings.lightCoverageWeights, settings.quadLights);
  for (const std::string& d : wt::kernelDefines(wt::renderKernelFeatures(features, device, settings, buffers, lights)))
    std::printf(" %s", d.substr(3).c_str());  // without "-D "
  std::printf("\n");

  // geometry
  std::size_t curvePoints = 0;
  for (const wt::Curve& c : scene.curves) curvePoints += c.pointCount;
  std::size_t baseTriangles = 0;
  for (const wt::DisplacedMesh& m : scene.displacedMeshes) baseTriangles += m.triangles.size();
  std::printf("primitives: %zu triangles, %zu spheres, %zu curves (%zu points), %zu SDF grids, %zu displaced meshes "
              "(%zu base triangles), %zu vertices\n",
              scene.triangles.size(), scene.spheres.size(), scene.curves.size(), curvePoints, scene.sdfGrids.size(),
              scene.displacedMeshes.size(), baseTriangles, scene.positions.size());
  std::printf("instances: %zu mesh copies and %zu sphere, curve, SDF or displaced copies in the file; instancing %s: %zu instances, "
              "%zu triangles in instanced copies\n",
              scene.instances.size(), scene.primitiveInstances.size(), options.instancing.c_str(),
              buffers.instanceCount(), buffers.instancedTriangles());
  // materials
  std::size_t lambertian = 0, pbr = 0, pbrLambertian = 0, mask = 0, blend = 0;
  for (const WtMaterial& m : scene.materials) {
    (m.model == WT_MATERIAL_PBR ? pbr : lambertian) += 1;
    pbrLambertian += m.model == WT_MATERIAL_PBR && wt::isLambertian(m);
    mask += m.alpha_mode == WT_ALPHA_MASK;
    blend += m.alpha_mode == WT_ALPHA_BLEND;
  }
  std::printf("materials: %zu (%zu lambertian, %zu metallic-roughness, %zu of them exactly Lambertian and rendered as "
              "such; alpha: %zu mask, %zu blend; %zu triangles alpha-tested)\n",
              scene.materials.size(), lambertian, pbr, pbrLambertian, mask, blend, buffers.alphaTriangles());
  // lights
  std::size_t kinds[WT_LIGHT_DIRECTIONAL + 1] = {};
  for (const wt::PunctualLight& l : scene.lights)
    if (l.type >= WT_LIGHT_POINT && l.type <= WT_LIGHT_DIRECTIONAL) ++kinds[l.type];
  auto emitting = [&](std::uint32_t material) {
    if (material >= scene.materials.size()) return false;
    const WtVec4& e = scene.materials[material].emission;
    return e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
  };
  std::size_t emissiveTriangles = 0, emissiveSpheres = 0, emissiveCurves = 0;
  for (const WtTriangle& t : scene.triangles) emissiveTriangles += emitting(t.material);
  for (const wt::Sphere& sp : scene.spheres) emissiveSpheres += emitting(sp.material);
  for (const wt::Curve& c : scene.curves) emissiveCurves += emitting(c.material);
  std::string environment = "none";
  if (features.environmentMap)
    environment = "map " + settings.environmentMap;
  else if (features.constantSky)
    environment = "constant (" + std::to_string(settings.background.x) + ", " + std::to_string(settings.background.y) +
                  ", " + std::to_string(settings.background.z) + ")";
  std::printf("lights: %zu punctual (%zu point, %zu spot, %zu directional), %zu emissive triangles, %zu emissive "
              "spheres, %zu emissive curves; environment: %s\n",
              scene.lights.size(), kinds[WT_LIGHT_POINT], kinds[WT_LIGHT_SPOT], kinds[WT_LIGHT_DIRECTIONAL],
              emissiveTriangles, emissiveSpheres, emissiveCurves, environment.c_str());
  // how next-event estimation picks among them (the switches above follow it)
  std::printf("light sampling: alias table %zu (punctual %u, environment %s); light tree ", lights.alias.size(),
              lights.analyticCount, lights.environmentPmf > 0.0f ? "yes" : "no");
  if (lights.tree.empty())
    std::printf("none");
  else
    std::printf("%zu nodes over the emissive triangles", lights.tree.size());
  std::printf("; rectangle lights %zu; emissive primitives of other types %zu%s\n", lights.quadLights,
              lights.emissivePrimitives, lights.sampleable ? "" : "; nothing to sample (no NEE)");
  // textures: the images' finest levels
  const wt::TextureSet& ts = scene.textures;
  std::printf("textures: %zu images, %zu textures, %.2f MiB with mips (%.2f MiB on the device)",
              ts.imageCount(), ts.textures.size(), double(ts.bytes()) / (1 << 20),
              double(buffers.textureBytes) / (1 << 20));
  std::vector<bool> seen(ts.levels.size(), false);
  std::string sizes;
  for (const WtTexture& t : ts.textures) {
    if (t.first_level >= ts.levels.size() || seen[t.first_level]) continue;
    seen[t.first_level] = true;
    const WtTextureLevel& l = ts.levels[t.first_level];
    sizes += (sizes.empty() ? "" : ", ") + std::to_string(l.width) + "x" + std::to_string(l.height);
  }
  std::printf("%s%s\n", sizes.empty() ? "" : ": ", sizes.c_str());
  // acceleration structures
  const wt::Bvh4Stats& bvh = buffers.bvh4Stats();
  std::printf("bvh: %zu nodes, depth %d (4-wide, triangles); %zu nodes, depth %d (other primitives); stack %d entries\n",
              bvh.nodeCount, bvh.maxDepth, buffers.primitiveBvhStats().nodeCount,
              buffers.primitiveBvhStats().maxDepth, features.bvhStackSize);
  return 0;
}

struct TonemapCommand {
  std::string input;
  std::vector<std::string> outputs;
  std::string device;
  TonemapOptions tonemap;
};

/// `wavetrace tonemap IN.exr -o OUT.png`: the render's tonemap stage on a linear EXR.
int runTonemap(const TonemapCommand& cmd) {
  for (const std::string& out : cmd.outputs) {
    if (wt::imageFormatFor(out) != wt::ImageFormat::Png)
      throw std::invalid_argument(out + ": tonemap writes PNG (the EXR is the linear input)");
    wt::checkWritable(out);
  }
  auto [settings, stops] = resolveTonemap(cmd.tonemap);
  wt::Image image = wt::readExr(cmd.input);
  wt::Context context(wt::selectDevice(cmd.device));
  float scale = 1.0f;
  wt::tonemapImage(context, image, settings, stops, &scale);
  for (const std::string& out : cmd.outputs) {
    wt::writeImage(out, image);
    std::printf("wrote %s (%s)\n", out.c_str(), wt::tonemapOperatorName(settings.op).c_str());
  }
  if (settings.autoExposure)
    wt::log::info("auto exposure: scale " + std::to_string(scale) + " (log-average luminance " +
                  std::to_string(WT_TONEMAP_MIDDLE_GREY / scale) + ")");
  return 0;
}

/// `store-programs`: write the kernel cache entries a render left to the
/// background (storeDeferredProgramsInBackground), jobs on standard input.
/// It yields to everything else on the machine, and fails silently.
int runStorePrograms(int device, const std::string& kernelDir) {
  setpriority(PRIO_PROCESS, 0, 19);
  std::ostringstream jobs;
  jobs << std::cin.rdbuf();
  if (!kernelDir.empty()) wt::setKernelDirectory(std::filesystem::path(kernelDir));
  wt::DeviceInfo info = wt::selectDevice(std::to_string(device));
  wt::Context context(info);
  int stored = 0;
  const std::vector<wt::DeferredStore> list = wt::parseDeferredStores(jobs.str());
  for (const wt::DeferredStore& job : list) stored += wt::storeProgramEntry(context, wt::expandKernelSource(job.label), job);
  return stored == int(list.size()) ? 0 : 1;
}

int runDevices() {
  std::vector<wt::DeviceInfo> devices = wt::listDevices();
  if (devices.empty()) {
    wt::log::error("no OpenCL device found (install an ICD, e.g. pocl-opencl-icd)");
    return 1;
  }
  int def = wt::defaultDeviceIndex(devices);
  for (const wt::DeviceInfo& d : devices)
    std::printf("%s %d: %s [%s] %s%s\n", d.index == def ? "*" : " ", d.index, d.name.c_str(),
                d.platformName.c_str(), d.version.c_str(), d.fp64 ? ", fp64" : "");
  std::printf("(* = default)\n");
  return 0;
}

}  // namespace

/// `render --help` by topic: each option's group by its long name. An option
/// missing here lands in "Other options", which tests/CMakeLists.txt's
/// cli.help_groups refuses, so a new option must be placed.
void groupRenderOptions(CLI::App* cmd) {
  static const std::pair<const char*, std::vector<std::string>> kGroups[] = {
      {"Scene and camera",
       {"--scene-index", "--camera", "--look-from", "--look-at", "--up", "--fov", "--frame", "--no-recenter", "--tessellate",
        "--background", "--env-map", "--env-intensity", "--env-rotation", "--env-hidden"}},
      {"Image and sampling", {"--output", "--width", "--height", "--spp", "--seed", "--sampler", "--accumulation"}},
      {"Light transport",
       {"--integrator", "--max-bounces", "--max-diffuse-bounces", "--max-specular-bounces",
        "--max-transmission-bounces", "--no-nee", "--no-mis", "--mis-heuristic", "--no-rr", "--rr-depth",
        "--light-sampler", "--texture-filter"}},
      {"Tone mapping (PNG only; the EXR stays linear)",
       {"--tonemap", "--exposure", "--aperture", "--shutter", "--iso", "--tonemap-white", "--white-balance",
        "--no-dither"}},
      {"Stopping, error and checkpoints",
       {"--time", "--target-error", "--reference", "--error-log", "--checkpoint", "--resume"}},
      {"AOVs and debugging", {"--aov", "--aov-out", "--debug", "--stop-on-nan"}},
      {"Device, BVH and kernels",
       {"--device", "--chunk-spp", "--rank-timeout", "--start-timeout", "--bvh", "--instancing", "--traversal", "--packet-width", "--kernel-dir", "--kernel-cache",
        "--general-program"}},
      {"Messages and profiling", {"--quiet", "--verbose", "--profile", "--profile-json"}},
  };
  for (CLI::Option* opt : cmd->get_options()) {
    const std::string name = opt->get_name();
    if (opt->get_positional() || name == "--help") continue;
    const char* group = "Other options";
    for (const auto& [title, names] : kGroups)
      if (std::find(names.begin(), names.end(), name) != names.end()) group = title;
    opt->group(group);
  }
}

int main(int argc, char** argv) {
  g_startup.emplace();
  wt::MpiWorld world(argc, argv);
  g_world = &world;
  CLI::App app{"wavetrace: a wavefront path tracer for OpenCL devices"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "wavetrace 0.1.0");

  RenderOptions render;
  CLI::App* renderCmd = app.add_subcommand("render", "Render a glTF scene or a scene file (the built-in Cornell box when none is named)");
  renderCmd->add_option("scene", render.scene,
                        "Scene: .gltf, .glb, a scene file .json (docs/scene-format.md; its render settings and "
                        "environment apply unless named here) or a built-in name");
  renderCmd->add_option("-o,--output", render.outputs, "Output image(s), .exr (linear float) or .png (sRGB); repeatable")
      ->default_str("render.png");
  renderCmd->add_option("--spp", render.settings.samplesPerPixel, "Samples per pixel")
      ->check(CLI::Range(1, 1 << 24))->capture_default_str();
  renderCmd->add_option("--width", render.settings.width, "Image width in pixels")
      ->check(CLI::Range(1, 16384))->capture_default_str();
  renderCmd->add_option("--height", render.settings.height, "Image height in pixels")
      ->check(CLI::Range(1, 16384))->capture_default_str();
  renderCmd->add_option("--max-bounces", render.settings.maxBounces, "Bounces after the camera hit")
      ->check(CLI::Range(0, 1024))->capture_default_str();
  renderCmd->add_option("--max-diffuse-bounces", render.settings.maxDiffuseBounces,
                        "Diffuse (cosine-sampled) bounces a path may take (default: --max-bounces)")
      ->check(CLI::Range(0, 1024));
  renderCmd->add_option("--max-specular-bounces", render.settings.maxSpecularBounces,
                        "Specular (GGX and mirror) bounces a path may take (default: --max-bounces)")
      ->check(CLI::Range(0, 1024));
  renderCmd->add_option("--max-transmission-bounces", render.settings.maxTransmissionBounces,
                        "Transmission bounces (refraction, thin-walled transmission) a path may take (default: --max-bounces)")
      ->check(CLI::Range(0, 1024));
  renderCmd->add_option("--seed", render.settings.seed, "Random seed")->capture_default_str();
  addTonemapOptions(renderCmd, render.tonemap);
  renderCmd->add_option("--background", render.background,
                        "Constant environment radiance R,G,B seen by rays that leave the scene")
      ->delimiter(',')->expected(3)->capture_default_str();
  renderCmd->add_option("--integrator", render.integrator,
                        "minimal (brute-force reference) or path (NEE, MIS, Russian roulette)")
      ->check(CLI::IsMember({"minimal", "path"}))->capture_default_str();
  renderCmd->add_flag("--no-nee", render.noNee, "path: no next-event estimation");
  renderCmd->add_flag("--no-mis", render.noMis, "path: NEE without multiple importance sampling");
  renderCmd->add_option("--mis-heuristic", render.misHeuristic,
                        "path: balance, power, or auto (power at Lambertian vertices, balance elsewhere)")
      ->check(CLI::IsMember({"auto", "balance", "power"}))->capture_default_str();
  renderCmd->add_flag("--no-rr", render.noRr, "path: no Russian roulette");
  renderCmd->add_option("--sampler", render.sampler,
                        "sobol (Owen-scrambled Sobol; the default, for its error per unit of time) or independent (hashed)")
      ->check(CLI::IsMember({"independent", "sobol"}))->capture_default_str();
  renderCmd->add_option("--texture-filter", render.textureFilter,
                         "footprint: textures read at the mip level of the path's footprint (ray cone at the camera hit, "
                         "path spread after); finest: always the finest level (point sampling, slower to converge)")
      ->check(CLI::IsMember({"footprint", "finest"}))->capture_default_str();
  renderCmd->add_option("--light-sampler", render.lightSampler,
                        "path: how NEE picks an emissive triangle: power (alias table), tree (light tree, by "
                        "importance at the shading point) or auto (the tree from 8 emitters on)")
      ->check(CLI::IsMember({"auto", "power", "tree"}))->capture_default_str();
  renderCmd->add_option("--rr-depth", render.settings.rrMinDepth, "path: first bounce Russian roulette may end")
      ->check(CLI::Range(0, 1024))->capture_default_str();
  renderCmd->add_option("--accumulation", render.accumulation,
                        "Running-mean precision: single, kahan (compensated single) or double (fp64 devices)")
      ->check(CLI::IsMember({"single", "kahan", "double"}))->capture_default_str();
  renderCmd->add_option("--bvh", render.bvh,
                        "BVH builder: auto (one tree per geometry placed more than once; ploc up to 65536 "
                        "triangles, lbvh above), lbvh (Morton codes, fastest), ploc (PLOC clustering in Morton order, "
                        "SAH on top) or sah (top-down binned SAH, slow)")
      ->check(CLI::IsMember({"auto", "lbvh", "ploc", "sah"}))->capture_default_str();
  renderCmd->add_option("--instancing", render.instancing,
                        "Geometry placed several times (glTF nodes sharing a mesh): on, stored once with one "
                        "transform per copy (two-level BVH); off, every copy flattened; auto, on where the "
                        "flattened copies would not fit the device's global memory cache (32 MiB where it reports none)")
      ->check(CLI::IsMember({"auto", "on", "off"}))->capture_default_str();
  renderCmd->add_option("--traversal", render.traversal,
                        "auto: camera rays in packets of neighbouring pixels, later bounces in packets or one ray per "
                        "work-item, whichever traced faster in timed trials over the second to fifth samples; "
                        "each bounce's shadow rays in packets, streams (CPUs) or alone, chosen from a sample of them "
                        "measured in the first sample (docs/performance.md); single: every ray alone")
      ->check(CLI::IsMember({"auto", "single"}))->capture_default_str();
  renderCmd->add_option("--packet-width", render.packetWidth,
                        "Pixels per packet with --traversal auto: 8 or 16; 0 picks by the device (16 where its native "
                        "float vector is 16 wide and the scene has at most 349525 triangles; never by the image size)")
      ->check(CLI::IsMember({0, 8, 16}))->capture_default_str();
  renderCmd->add_option("--reference", render.reference,
                        "EXR of the converged image: log the error at 1, 2, 4, ... samples (see --error-log)");
  renderCmd->add_option("--error-log", render.errorLog,
                        "CSV of samples, seconds, RMSE, relMSE, p99 against --reference (default: stdout)");
  renderCmd->add_option("--env-map", render.settings.environmentMap,
                        "Equirectangular environment (.hdr, .exr) lighting the scene; replaces --background");
  renderCmd->add_option("--env-intensity", render.settings.environmentIntensity, "Scale on the environment")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  renderCmd->add_option("--env-rotation", render.settings.environmentRotationDegrees,
                        "Turn the environment about +Y, degrees, counter-clockwise seen from above")
      ->capture_default_str();
  renderCmd->add_flag("--env-hidden", render.settings.environmentHidden,
                      "Camera rays see black where they escape; the environment still lights the scene");
  renderCmd->add_option("--device", render.device,
                        "Device index or name substring (see 'wavetrace devices'); a comma-separated list or 'all' "
                        "renders on several at once, the samples shared out in chunks (docs/scale-out.md)");
  renderCmd->add_option("--chunk-spp", render.chunkSpp,
                        "Samples per chunk when the render is shared over devices or MPI ranks (default: spp/64, "
                        "1 to 64); the image depends on it, not on how many devices or ranks render it")
      ->check(CLI::Range(1, 1 << 20));
  renderCmd->add_option("--rank-timeout", render.rankTimeout,
                        "A worker rank or a device of a split render that shows no progress for this many seconds "
                        "(no message, or no sample pass done on the chunk it holds) is lost; its chunks go to the "
                        "others and the image is finished without it; a rank 0 that sends nothing that long ends "
                        "the job, and a rank 0 blocked that long inside one MPI call writes what it merged and "
                        "ends it. Must exceed the slowest device's sample pass (docs/scale-out.md, Faults)")
      ->check(CLI::PositiveNumber)->capture_default_str();
  renderCmd->add_option("--start-timeout", render.startTimeout,
                        "An MPI rank that has not finished starting (scene, BVH, kernel build) this many seconds "
                        "after another has ends the job, named (default: --rank-timeout, at least 120)")
      ->check(CLI::PositiveNumber);
  renderCmd->add_option("--scene-index", render.sceneIndex, "glTF scene to render (default: the file's default scene)")
      ->check(CLI::Range(-1, 1 << 20));
  renderCmd->add_option("--look-from", render.lookFrom, "Camera position X,Y,Z in the file's world coordinates")
      ->delimiter(',')->expected(3);
  renderCmd->add_option("--look-at", render.lookAt,
                        "Point X,Y,Z the camera looks at (alone: the camera turns in place; --look-from alone keeps "
                        "its view direction)")
      ->delimiter(',')->expected(3);
  renderCmd->add_option("--up", render.up, "Camera up direction X,Y,Z (default: the camera's own up)")
      ->delimiter(',')->expected(3);
  renderCmd->add_option("--fov", render.fovDegrees, "Vertical field of view in degrees (perspective cameras)");
  renderCmd->add_flag("--frame", render.frame,
                      "Replace the scene's camera by one framing the scene's bounds (from +Z, a little above)");
  renderCmd->add_option("--camera", render.camera, "Camera to use, by order in the scene")
      ->check(CLI::Range(0, 1 << 20))->capture_default_str();
  renderCmd->add_flag("--stop-on-nan", render.stopOnNan,
                      "Stop at the first NaN/Inf a path makes and name its pixel, sample and bounce "
                      "(always on in debug builds); the samples before it are still written");
  renderCmd->add_option("--tessellate", render.tessellate,
                        "Comparison only: turn displaced meshes into triangles, N per base edge (N^2 per base "
                        "triangle; N = 2^L is the displaced surface itself)")
      ->check(CLI::Range(0, 1024));
  renderCmd->add_flag("--no-recenter", render.noRecenter,
                      "Keep the file's world coordinates (default: the scene is stored relative to the camera, "
                      "in double precision, so it renders the same far from the world origin)");
  renderCmd->add_option("--aov", render.aov,
                        "AOVs to write as layers of the EXR output, comma-separated: albedo, normal, depth, "
                        "position, material, instance, variance, or all (docs/command-line.md)");
  renderCmd->add_option("--aov-out", render.aovOut, "Also write each --aov as its own EXR in this folder (NAME.exr)");
  renderCmd->add_option("--debug", render.debug,
                        "Render a debug view instead of the image: normals, albedo, uv, depth, bounces or bvh-cost");
  renderCmd->add_option("--kernel-dir", render.kernelDir, "Developer option: read kernels from this folder");
  renderCmd->add_flag("--general-program", render.settings.generalProgram,
                      "Developer option: build every kernel switch on instead of the scene's feature set (the same "
                      "image; for comparisons)");
  renderCmd->add_option("--time", render.timeSeconds,
                        "Stop after the sample pass that crosses this many seconds of rendering (scene loading and "
                        "kernel builds not counted); without --spp, no sample limit")
      ->check(CLI::PositiveNumber);
  renderCmd->add_option("--target-error", render.targetError,
                        "Stop when the estimated relative error of the pixel means (RMS over pixels and channels of "
                        "standard error / (mean^2 + 0.01)^0.5, from each pixel's variance) falls below this, e.g. "
                        "0.02; estimated from 16 samples on; without --spp, no sample limit")
      ->check(CLI::PositiveNumber);
  renderCmd->add_option("--checkpoint", render.checkpointSeconds,
                        "Every this many seconds (and at the end) write the running accumulation to OUTPUT.wtckpt "
                        "beside the first output, atomically; in an MPI job of several ranks also the outputs, "
                        "default every 60 s there (removed once the image is whole); 0: never")
      ->check(CLI::NonNegativeNumber);
  renderCmd->add_flag("--resume", render.resume,
                      "Continue from OUTPUT.wtckpt: the same image as an uninterrupted render of the same total "
                      "--spp; refused for another scene or other settings");
  renderCmd->add_flag("--profile", render.profile,
                      "After the render, print the time of every stage at every bounce (OpenCL profiling events), "
                      "the queue sizes, rays per second per stage and the share of wall time outside kernels");
  renderCmd->add_option("--profile-json", render.profileJson, "Write the --profile figures as JSON to this file (implies --profile)");
  renderCmd->add_flag("-q,--quiet", render.quiet, "No progress output");
  renderCmd->add_flag("-v,--verbose", render.verbose,
                      "Timings of the scene set-up (BVH build phases) and of each program's build (kernel cache hit or miss), "
                      "and the paths alive per bounce");
  // one folder for whichever command runs: only the given subcommand's option is parsed
  std::string kernelCache;
  const char* kernelCacheHelp =
      "Folder of compiled kernels (default: $WAVETRACE_CACHE_DIR, else $XDG_CACHE_HOME/wavetrace/kernels, "
      "else ~/.cache/wavetrace/kernels); 'off': compile every time";
  renderCmd->add_option("--kernel-cache", kernelCache, kernelCacheHelp);
  groupRenderOptions(renderCmd);

  RenderOptions info;
  info.instancing = "auto";
  CLI::App* infoCmd =
      app.add_subcommand("info", "Print a scene's feature set (what its program compiles in) and its statistics");
  infoCmd->add_option("scene", info.scene, "glTF (.gltf/.glb) or scene file (.json)")->required();
  infoCmd->add_option("--device", info.device, "Device index or name substring");
  infoCmd->add_option("--integrator", info.integrator, "path or minimal, as for render")
      ->check(CLI::IsMember({"path", "minimal"}));
  infoCmd->add_option("--env-map", info.settings.environmentMap, "Environment map, as for render");
  infoCmd->add_option("--background", info.background, "Constant environment radiance, as for render")
      ->expected(3);
  infoCmd->add_option("--instancing", info.instancing, "off, on or auto, as for render")
      ->check(CLI::IsMember({"off", "on", "auto"}));
  infoCmd->add_option("--scene-index", info.sceneIndex, "glTF scene (default: the file's default scene)");

  CLI::App* devicesCmd = app.add_subcommand("devices", "List OpenCL platforms and devices");

  // started by a render (storeDeferredProgramsInBackground), not by users: no help entry
  int storeDevice = 0;
  std::string storeKernelDir;
  CLI::App* storeCmd = app.add_subcommand("store-programs", "")->group("");
  storeCmd->add_option("--device", storeDevice)->required();
  storeCmd->add_option("--kernel-dir", storeKernelDir);

  TonemapCommand tonemapArgs;
  CLI::App* tonemapCmd = app.add_subcommand("tonemap", "Tone-map a linear EXR (e.g. a render's) to an 8-bit sRGB PNG");
  tonemapCmd->add_option("input", tonemapArgs.input, "Linear EXR")->required()->check(CLI::ExistingFile);
  tonemapCmd->add_option("-o,--output", tonemapArgs.outputs, "Output PNG(s)")->required();
  tonemapCmd->add_option("--device", tonemapArgs.device, "Device index or name substring");
  addTonemapOptions(tonemapCmd, tonemapArgs.tonemap);

  wt::BenchOptions bench;
  CLI::App* benchCmd = app.add_subcommand("bench", "BVH build and ray throughput benchmark");
  benchCmd->add_option("scenes", bench.scenes,
                       "Scene files, .gltf, .glb or .json, or scenes made in code: gen:soup, gen:displaced-sphere, "
                       "gen:forest, gen:many-lights, gen:all (default: built-in Cornell box, MetalRoughSpheresNoTextures "
                       "and DamagedHelmet from the asset folder, a generated 1M-triangle mesh, sphere field, head of hair)");
  benchCmd->add_option("--kernel-cache", kernelCache, kernelCacheHelp);
  benchCmd->add_option("--assets", bench.assetsDir, "Asset folder (default: ../shared/assets beside the source, or from here)");
  benchCmd->add_option("--device", bench.device, "Device index or name substring");
  benchCmd->add_flag("--json", bench.json, "Machine-readable output");
  benchCmd->add_option("--primary-width", bench.primaryWidth, "Primary ray set is N x N")
      ->check(CLI::Range(1, 8192))->capture_default_str();
  benchCmd->add_option("--path-width", bench.pathWidth, "The path-tracing figure renders N x N pixels")
      ->check(CLI::Range(1, 4096))->capture_default_str();
  benchCmd->add_option("--path-spp", bench.pathSamples, "The path-tracing figure's samples per pixel (at least; exactly with --min-time 0)")
      ->check(CLI::Range(1, 1024))->capture_default_str();
  benchCmd->add_option("--tessellate", bench.tessellate,
                       "Each scene with displaced meshes gains a row: the same meshes as triangles, N per base edge "
                       "(N = 2^L is the displaced surface itself)")
      ->check(CLI::Range(0, 1024));
  benchCmd->add_option("--mesh-triangles", bench.meshTriangles, "Size of the generated mesh")
      ->check(CLI::Range(2, 1 << 26))->capture_default_str();
  benchCmd->add_option("--spheres", bench.sphereCount, "Spheres of the generated sphere field (0: none)")
      ->check(CLI::Range(0, 1 << 26))->capture_default_str();
  benchCmd->add_option("--hair-guides", bench.hairGuides,
                       "Guide strands of the generated head of hair, 100 children each, 15 segments a strand (0: none)")
      ->check(CLI::Range(0, 1 << 16))->capture_default_str();
  benchCmd->add_option("--repetitions", bench.repetitions, "Timed runs per figure (median)")
      ->check(CLI::Range(1, 1000))->capture_default_str();
  benchCmd->add_option("--min-time", bench.minSeconds,
                       "Seconds: each tracer's timed runs of a ray set go on past --repetitions until they add up "
                       "to this, up to 20 x --repetitions runs (0: exactly --repetitions); the path figure runs for twice this (0: exactly --path-spp)")
      ->check(CLI::Range(0.0, 60.0))->capture_default_str();
  benchCmd->add_option("--embree-api", bench.embreeApi,
                       "Embree reference: how rays are handed over; fastest: each set with every API, "
                       "compared with the fastest")
      ->check(CLI::IsMember({"fastest", "single", "packet8", "packet16", "stream"}))->capture_default_str();
  benchCmd->add_option("--embree-quality", bench.embreeQuality, "Embree reference: build quality 0 low, 1 medium, 2 high")
      ->check(CLI::Range(0, 2))->capture_default_str();
  benchCmd->add_flag("--embree-robust", bench.embreeRobust, "Embree reference: RTC_SCENE_FLAG_ROBUST");
  benchCmd->add_option("--bvh", bench.bvh,
                       "The BVH builder whose tree is compared with Embree and renders the path figure")
      ->check(CLI::IsMember({"auto", "lbvh", "ploc", "sah"}))->capture_default_str();
  benchCmd->add_option("--instancing", bench.instancing,
                       "Geometry placed several times: on (stored once, two-level BVH), off (flattened) or auto "
                       "(on where the flattened copies would not fit the device's cache), for every tree and the path figure; "
                       "off by default, the geometry Embree traces")
      ->check(CLI::IsMember({"auto", "on", "off"}))->capture_default_str();
  benchCmd->add_option("--compare-bvh", bench.compareBvh,
                       "Builders whose trees are traced on the same rays (tree quality table); none: --compare-bvh none")
      ->delimiter(',')->check(CLI::IsMember({"auto", "lbvh", "ploc", "sah", "none"}))->capture_default_str();
  benchCmd->add_option("--compare-program", bench.compareProgram,
                       "general: the path figure also renders with the general program (every switch on), "
                       "for the specialised-vs-general table; none: skip it (no second program to build)")
      ->check(CLI::IsMember({"general", "none"}))->capture_default_str();
  benchCmd->add_option("--traversal", bench.traversal,
                       "single: one ray per work-item; packet: a packet of rays per work-item; stream: shadow rays "
                       "as streams of 64 that walk the tree together; auto: as the renderer chooses from the rays "
                       "(packets where a packet's rays point nearly one way, coherence >= 0.95, and leave few leaves' "
                       "worth of surface apart, origin_spread in --json; else streams for shadow rays on a CPU; else single)")
      ->check(CLI::IsMember({"single", "packet", "stream", "auto"}));
  benchCmd->add_option("--packet-width", bench.packetWidth,
                       "Rays per packet: 8 or 16; 0 picks by the device and the scene (16 where its native float vector "
                       "is 16 wide and the scene has at most 349525 triangles)")
      ->check(CLI::IsMember({0, 8, 16}))->capture_default_str();
  benchCmd->add_option("--max-leaf-size", bench.maxLeafSize, "Every tree: no leaf holds more triangles (0: 16, as render); the collapse to 4 wide chooses the leaves up to it")
      ->check(CLI::Range(0, 64));
  benchCmd->add_option("--ab-kernel-dir", bench.abKernelDir,
                       "Kernel development: the tree comparison gains a row, the --bvh tree traced by the kernels in "
                       "this folder, interleaved with the built-in kernels' row in one process");
  benchCmd->add_option("--ab-packet-width", bench.abPacketWidth,
                       "Kernel development: the tree comparison gains a row, the --bvh tree traced in packets of "
                       "this many rays, interleaved with the --packet-width row in one process")
      ->check(CLI::IsMember({8, 16}));
  benchCmd->add_option("--ab-traversal", bench.abTraversal,
                       "Kernel development: the tree comparison gains a row per value (comma-separated), the --bvh "
                       "tree with every set traced this way, interleaved with the row traced as --traversal chose")
      ->delimiter(',')->check(CLI::IsMember({"single", "packet", "stream"}));
  benchCmd->add_option("--ploc-radius", bench.plocRadius, "ploc trees: neighbours searched on each side")
      ->check(CLI::Range(1, 64))->capture_default_str();
  benchCmd->add_option("--ploc-top-prims", bench.plocTopPrims,
                       "ploc trees: clustering stops at clusters of this many primitives on average, binned SAH "
                       "builds the rest (0: PLOC to the root)")
      ->check(CLI::Range(0, 1 << 20))->capture_default_str();

  wt::StressOptions stress;
  std::string stressDevice;
  bool stressJson = false;
  CLI::App* stressCmd = app.add_subcommand("stress", "Numerical-stability stress suite: every row with its figure and pass/fail");
  stressCmd->add_flag("--quick", stress.quick, "Small images and ray counts (the subset the tests run)");
  stressCmd->add_option("--group", stress.groups,
                        "Only these groups: transform, cracks, self-intersection, degenerate, materials, textures, "
                        "accumulation, non-finite, primitives, far-furnace (repeatable)");
  stressCmd->add_option("--device", stressDevice, "Device index or name substring");
  stressCmd->add_flag("--json", stressJson, "Machine-readable output");
  stressCmd->add_option("--kernel-cache", kernelCache, kernelCacheHelp);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  // PoCL leaves the worker threads of its CPU device unpinned unless
  // POCL_AFFINITY is set, and unpinned workers made the bench's short
  // kernels bimodal. Pinned threads of several processes at once cannot
  // move aside, though (the test suite under ctest -j2 got slower), and
  // renders, whose launches are long, gain nothing: so for the bench only,
  // set before PoCL starts, and never over the user's own setting
  // (docs/lab/2026-12-02-performance-log.md, "PoCL's worker threads").
  if (*benchCmd) setenv("POCL_AFFINITY", "1", 0);
  if (!kernelCache.empty()) wt::setProgramCacheDirectory(kernelCache);
  wt::setProgramStoreExecutable("/proc/self/exe");

  try {
    if (*renderCmd) {
      if (render.outputs.empty()) render.outputs.push_back("render.png");
      auto given = [&](const char* name) { return renderCmd->count(name) > 0; };
      render.given = {given("--width"), given("--height"), given("--spp"), given("--max-bounces"), given("--seed"),
                      given("--exposure"), given("--integrator"), given("--background"), given("--env-map"),
                      given("--env-intensity"), given("--env-rotation"), given("--env-hidden"), given("--tonemap")};
      render.tonemap.physical = given("--aperture") || given("--shutter") || given("--iso");
      render.chunkSppGiven = given("--chunk-spp");
      return runRender(render);
    }
    if (*infoCmd) {
      info.given = {false, false, false, false, false, false, infoCmd->count("--integrator") > 0,
                    infoCmd->count("--background") > 0, infoCmd->count("--env-map") > 0};
      return runInfo(info);
    }
    if (*devicesCmd) return runDevices();
    if (*storeCmd) return runStorePrograms(storeDevice, storeKernelDir);
    if (*tonemapCmd) {
      tonemapArgs.tonemap.physical =
          tonemapCmd->count("--aperture") + tonemapCmd->count("--shutter") + tonemapCmd->count("--iso") > 0;
      return runTonemap(tonemapArgs);
    }
    if (*benchCmd) return wt::runBench(bench);
    if (*stressCmd) return wt::runStressCommand(stress, stressDevice, stressJson);
  } catch (const cl::Error& e) {
    wt::log::error(std::string("OpenCL call ") + e.what() + " failed: " + wt::clErrorName(e.err()));
    return 1;
  } catch (const std::exception& e) {
    wt::log::error(e.what());
    return 1;
  }
  return 0;
}
