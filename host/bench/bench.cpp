#include "bench/bench.h"

#include "bvh/lbvh.h"
#include "core/log.h"
#include "device/context.h"
#include "device/tracer.h"
#include "render/renderer.h"
#include "scene/default_scene.h"
#include "scene/generators.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace wt {
namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct SceneResult {
  std::string name;
  std::size_t triangles = 0;
  double buildSeconds = 0.0;
  std::size_t nodes = 0;
  double sah = 0.0;
  double bytesPerTriangle = 0.0;
  double primaryWallMrays = 0.0, primaryKernelMrays = 0.0;
  double primaryHitFraction = 0.0;
  double pathMrays = 0.0;
};

/// Camera rays through pixel centres, as the generate stage makes them.
std::vector<Ray> primaryRays(const Scene& scene, int width) {
  CameraDesc desc = scene.camera ? *scene.camera : defaultCamera(scene.bounds());
  WtCamera cam = makeCamera(desc, width, width);
  glm::vec3 origin(cam.origin.x, cam.origin.y, cam.origin.z);
  glm::vec3 right(cam.right.x, cam.right.y, cam.right.z), up(cam.up.x, cam.up.y, cam.up.z);
  glm::vec3 forward(cam.forward.x, cam.forward.y, cam.forward.z);
  bool ortho = cam.origin.w == float(WT_CAMERA_ORTHOGRAPHIC);
  std::vector<Ray> rays(std::size_t(width) * width);
  for (int y = 0; y < width; ++y)
    for (int x = 0; x < width; ++x) {
      float sx = 2.0f * (x + 0.5f) / width - 1.0f, sy = 1.0f - 2.0f * (y + 0.5f) / width;
      Ray& r = rays[std::size_t(y) * width + x];
      glm::vec3 offset = sx * right + sy * up;
      r.origin = ortho ? origin + offset : origin;
      r.direction = ortho ? forward : glm::normalize(forward + offset);
      r.tmin = cam.forward.w;
      r.tmax = 1e30f;
    }
  return rays;
}

SceneResult benchScene(Context& context, const std::string& name, const Scene& scene,
                       const BenchOptions& options) {
  SceneResult result;
  result.name = name;
  result.triangles = scene.triangles.size();

  // BVH build, median of several
  std::vector<Aabb> bounds(scene.triangles.size());
  for (std::size_t i = 0; i < bounds.size(); ++i) bounds[i] = scene.triangleBounds(std::uint32_t(i));
  std::vector<double> builds;
  Bvh bvh;
  for (int r = 0; r < options.repetitions + 1; ++r) {
    bvh = buildLbvh(bounds);
    if (r > 0) builds.push_back(bvh.stats.buildSeconds);
  }
  result.buildSeconds = median(builds);
  result.nodes = bvh.stats.nodeCount;
  result.sah = bvh.stats.sahCost;

  // primary rays: kernel time from profiling events, wall time around the call
  Tracer tracer(context, scene);
  result.bytesPerTriangle =
      scene.triangles.empty() ? 0.0 : double(tracer.sceneBuffers().uploadedBytes) / scene.triangles.size();
  std::vector<Ray> rays = primaryRays(scene, options.primaryWidth);
  std::vector<RayHit> hits = tracer.traceClosest(rays);  // warm-up (and first-launch compile)
  std::size_t hitCount = std::count_if(hits.begin(), hits.end(), [](const RayHit& h) { return h.triangle != RayHit::kNoHit; });
  result.primaryHitFraction = rays.empty() ? 0.0 : double(hitCount) / rays.size();
  std::vector<double> wall, kernel;
  for (int r = 0; r < options.repetitions; ++r) {
    auto start = std::chrono::steady_clock::now();
    tracer.traceClosest(rays);
    wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    kernel.push_back(tracer.lastKernelSeconds());
  }
  result.primaryWallMrays = rays.size() / median(wall) * 1e-6;
  result.primaryKernelMrays = rays.size() / median(kernel) * 1e-6;

  // whole paths: the wavefront renderer, rays of every bounce
  RenderSettings settings;
  settings.width = settings.height = options.pathWidth;
  settings.samplesPerPixel = options.pathSamples;
  Renderer renderer(context, scene, settings);
  renderer.renderSample();  // warm-up
  std::uint64_t raysBefore = renderer.stats().raysTraced;
  double secondsBefore = renderer.stats().seconds;
  for (int s = 0; s < options.pathSamples; ++s) renderer.renderSample();
  result.pathMrays = double(renderer.stats().raysTraced - raysBefore) /
                     (renderer.stats().seconds - secondsBefore) * 1e-6;
  return result;
}

}  // namespace

int runBench(const BenchOptions& options) {
  DeviceInfo device = selectDevice(options.device);
  Context context(device, /*profiling=*/true);

  std::vector<std::pair<std::string, Scene>> scenes;
  if (options.scenes.empty()) {
    scenes.emplace_back("cornell (default)", loadDefaultScene());
    scenes.emplace_back("bumpy grid " + std::to_string(options.meshTriangles / 1000) + "k",
                        makeBumpyGrid(std::uint32_t(options.meshTriangles)));
  } else {
    for (const std::string& path : options.scenes) scenes.emplace_back(path, loadScene(path));
  }

  std::vector<SceneResult> results;
  for (auto& [name, scene] : scenes) {
    log::info("bench: " + name + " (" + std::to_string(scene.triangles.size()) + " triangles)");
    results.push_back(benchScene(context, name, scene, options));
  }

  if (options.json) {
    std::printf("{\"device\": \"%s\", \"scenes\": [\n", device.name.c_str());
    for (std::size_t i = 0; i < results.size(); ++i) {
      const SceneResult& r = results[i];
      std::printf("  {\"name\": \"%s\", \"triangles\": %zu, \"bvh_build_s\": %.6f, \"bvh_mtris_per_s\": %.3f, "
                  "\"bvh_nodes\": %zu, \"bvh_sah\": %.3f, \"bytes_per_triangle\": %.1f, "
                  "\"primary_mrays_wall\": %.3f, \"primary_mrays_kernel\": %.3f, \"primary_hit_fraction\": %.4f, "
                  "\"path_mrays\": %.3f}%s\n",
                  r.name.c_str(), r.triangles, r.buildSeconds, r.triangles / r.buildSeconds * 1e-6, r.nodes,
                  r.sah, r.bytesPerTriangle, r.primaryWallMrays, r.primaryKernelMrays,
                  r.primaryHitFraction, r.pathMrays, i + 1 < results.size() ? "," : "");
    }
    std::printf("]}\n");
    return 0;
  }
  std::printf("device: %s (%s)\n", device.name.c_str(), device.platformName.c_str());
  std::printf("primary rays: %dx%d, median of %d; paths: %dx%d, %d spp, up to 8 bounces\n\n",
              options.primaryWidth, options.primaryWidth, options.repetitions, options.pathWidth,
              options.pathWidth, options.pathSamples);
  std::printf("%-22s %10s %9s %9s %9s %7s %8s %12s %12s %10s\n", "scene", "triangles", "build ms",
              "Mtris/s", "nodes", "SAH", "B/tri", "primary Mr/s", "(kernel)", "path Mr/s");
  for (const SceneResult& r : results)
    std::printf("%-22s %10zu %9.2f %9.2f %9zu %7.2f %8.1f %12.2f %12.2f %10.2f\n", r.name.c_str(),
                r.triangles, r.buildSeconds * 1e3, r.triangles / r.buildSeconds * 1e-6, r.nodes, r.sah,
                r.bytesPerTriangle, r.primaryWallMrays, r.primaryKernelMrays, r.pathMrays);
  return 0;
}

}  // namespace wt
