// Stress rows for the geometry types beside triangles (host/geometry/): a
// scene of them translated and scaled far from unit size and the origin
// renders the same image, rays re-spawned from their surfaces never find
// the surface they left, and degenerate ones are refused or left out with
// a warning, never a crash or a NaN.
#include "stress/stress.h"
#include "stress/stress_rows.h"

#include "core/spawn.h"
#include "device/tracer.h"
#include "geometry/primitives.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/generators.h"
#include "scene/scene_file.h"
#include "scene/sdf_volume.h"

#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

namespace wt {
namespace {

using stress_rows::Rendered;
using stress_rows::render;
using stress_rows::secondsSince;

/// Spheres from 1/1000 to 1000 of the view's size (a ground sphere, a
/// glass, a metal and a small diffuse one, an emitter), every coordinate
/// and radius scaled by `scale` and moved by `translate` on every axis, as
/// a scene file.
std::string sphereSceneJson(double translate, double scale) {
  const stress_rows::ScaledJson json{translate, scale};
  auto p = [&](double x, double y, double z) { return json.point(x, y, z); };
  auto r = [&](double radius) { return json.length(radius); };
  return json.stage(
      R"(    "glass": {"base_color": [1, 1, 1], "roughness": 0, "transmission": 1, "ior": 1.5},
    "metal": {"base_color": [0.9, 0.6, 0.3], "metallic": 1, "roughness": 0.2},
    "white": {"type": "lambert", "base_color": [0.8, 0.8, 0.8]},
)",
      R"(    {"type": "sphere", "center": )" + p(-0.6, 0.5, 0) + R"(, "radius": )" + r(0.5) + R"(, "material": "glass"},
    {"type": "sphere", "center": )" + p(0.6, 0.4, 0.2) + R"(, "radius": )" + r(0.4) + R"(, "material": "metal"},
    {"type": "sphere", "center": )" + p(0.1, 0.05, 0.9) + R"(, "radius": )" + r(0.05) + R"(, "material": "white"},
    {"type": "curves", "radius": )" + r(0.02) + R"(, "material": "metal", "strands": [[)" + p(-0.2, 0.05, 0.5) + ", " +
          p(0.0, 0.25, 0.6) + ", " + p(0.25, 0.1, 0.7) + ", " + p(0.45, 0.3, 0.55) + R"(]]},
)");
}

/// A scene file of one object (JSON text) must be refused, naming the
/// file and objects[0].
StressRow refusedObjectRow(const std::string& what, const char* object) {
  const auto start = std::chrono::steady_clock::now();
  std::string error;
  try {
    loadSceneFileFromMemory(std::string(R"({"version": 1, "objects": [)") + object + "]}", "degenerate.json", ".");
  } catch (const SceneError& e) {
    error = e.what();
  }
  StressRow row;
  row.group = "primitives";
  row.name = "scene file, " + what;
  row.figure = error.empty() ? "loaded" : "error: " + error;
  row.criterion = "an error naming the file and objects[0]";
  row.pass = error.find("degenerate.json") != std::string::npos && error.find("objects[0]") != std::string::npos;
  row.seconds = secondsSince(start);
  return row;
}

/// A scene made in code (no validator in the way) whose degenerate
/// primitives must be left out, `leftOut` of them, while one good emitter of
/// radiance 1 in front of the camera renders: no NaN, the centre pixel 1.
StressRow leftOutRow(Context& context, const StressOptions& options, Scene scene,
                     std::chrono::steady_clock::time_point start, const std::string& name, std::size_t leftOut) {
  scene.camera = CameraDesc{};
  RenderSettings settings;
  settings.width = settings.height = 16;
  settings.samplesPerPixel = options.quick ? 4 : 16;
  settings.maxBounces = 4;
  Renderer renderer(context, scene, settings);
  for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
  const Image image = renderer.readImage();
  const std::size_t nonFinitePixels = stress_rows::nonFinitePixels(image);
  const float centre = image.rgb[3 * (8 * 16 + 8)];
  StressRow row;
  row.group = "primitives";
  row.name = name;
  row.figure = std::to_string(renderer.sceneBuffers().skippedPrimitives()) + " left out, " +
               std::to_string(renderer.stats().nonFiniteSamples) + " NaN/Inf samples, " +
               std::to_string(nonFinitePixels) + " non-finite pixels; centre pixel " + stressFormat("%.3f", centre);
  row.criterion = std::to_string(leftOut) +
                  " left out (the renderer warns), no NaN, the good one seen (centre pixel 1, its radiance)";
  row.pass = renderer.sceneBuffers().skippedPrimitives() == leftOut && renderer.stats().nonFiniteSamples == 0 &&
             nonFinitePixels == 0 && std::abs(centre - 1.0f) < 1e-4f;
  row.seconds = secondsSince(start);
  return row;
}

std::vector<StressRow> sphereTransforms(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  const stress_rows::TransformStudy study = stress_rows::transformStudy(options, 6);
  auto renderCase = [&](double translate, double scale, bool recenter) {
    GltfLoadOptions load;
    load.recenter = recenter;
    return render(context, loadSceneFileFromMemory(sphereSceneJson(translate, scale), "spheres (stress)", ".", load).scene,
                  study.settings);
  };
  const Rendered reference = renderCase(0.0, 1.0, true);
  struct Case {
    std::string name;
    double translate, scale;
    bool recenter;
  };
  std::vector<Case> cases = {{"translated by 1e+06 (recentred, the default)", 1e6, 1.0, true},
                             {"scaled by 1e-04 (recentred)", 0.0, 1e-4, true},
                             {"scaled by 1e+04 (recentred)", 0.0, 1e4, true},
                             {"translated by 1e+03 (world coordinates, --no-recenter)", 1e3, 1.0, false}};
  if (options.quick) cases.resize(2);
  for (const Case& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const Rendered r = renderCase(c.translate, c.scale, c.recenter);
    rows.push_back(stress_rows::agreementRow("spheres and a curve from 1e-3 to 1e3 of the view (glass, metal, an emitter): " + c.name,
                                             r, reference, study, "against the untransformed scene", start));
  }
  return rows;
}

/// Rays re-spawned off one sphere at elevations from 1e-4 to 1.2 rad:
/// outwards (a convex surface: nothing may be hit) and inwards (the sphere
/// must be met again, at the far side of the chord).
StressRow sphereSelfIntersection(Context& context, const StressOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> s(-1.0f, 1.0f);
  auto randomUnit = [&] {
    glm::vec3 d;
    do d = glm::vec3(s(rng), s(rng), s(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-3f);
    return glm::normalize(d);
  };
  std::uint64_t rays = 0, outHits = 0, inEarly = 0, inLost = 0, undecidable = 0;
  std::string first;
  const int hitsPer = options.quick ? 300 : 4000;
  for (float radius : {1e-4f, 1.0f, 1e4f})
    for (float offset : {0.0f, 1e2f, 1e4f}) {
      const glm::vec3 center = offset * radius * glm::normalize(glm::vec3(1.0f, -0.6f, 0.8f));
      Scene scene;
      scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
      scene.spheres.push_back({center, radius, 0});
      Tracer tracer(context, scene);
      std::vector<Ray> firstRays(static_cast<std::size_t>(hitsPer));
      for (Ray& r : firstRays) {
        r.origin = center + radius * 3.0f * randomUnit();
        r.direction = glm::normalize(center + radius * 0.999f * randomUnit() - r.origin);
      }
      const std::vector<RayHit> hits = tracer.traceClosest(firstRays);
      std::vector<Ray> out, in;
      std::vector<float> chord;
      for (std::size_t i = 0; i < hits.size(); ++i) {
        if (hits[i].prim == RayHit::kNoHit) continue;
        glm::vec3 error, n;
        const glm::vec3 p = spherePoint(center, radius, firstRays[i].origin, firstRays[i].direction, hits[i].t, &error, &n);
        for (float elevation : {1e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.2f}) {
          const glm::vec3 tangent = glm::normalize(glm::cross(n, randomUnit()));
          Ray r;
          r.skip = hits[i].prim;
          r.origin = offsetRayOrigin(p, error, n);
          r.direction = glm::normalize(std::cos(elevation) * tangent + std::sin(elevation) * n);
          out.push_back(r);
          r.origin = offsetRayOrigin(p, error, -n);
          r.direction = glm::normalize(std::cos(elevation) * tangent - std::sin(elevation) * n);
          in.push_back(r);
          chord.push_back(2.0f * radius * std::sin(elevation));
        }
      }
      const std::vector<RayHit> again = tracer.traceClosest(out), across = tracer.traceClosest(in);
      const std::vector<std::uint8_t> blocked = tracer.traceOccluded(out, Traversal::kStream);
      std::uint64_t bad = 0;
      for (std::size_t i = 0; i < out.size(); ++i) {
        outHits += (again[i].prim != RayHit::kNoHit) + (blocked[i] != 0);
        // the far side: a chord of 2 r sin(elevation), to the float precision
        // of the coordinates; a chord within 16 float spacings of them is
        // below what the origin's own rounding can tell (not counted)
        const float spacing = 1.1920929e-7f * (glm::length(center) + radius);
        const bool decidable = chord[i] > 16.0f * spacing;
        const bool lost = decidable && across[i].prim == RayHit::kNoHit;
        const bool early = decidable && !lost && across[i].t < chord[i] - 1e-3f * chord[i] - 4.0f * spacing;
        inLost += lost;
        inEarly += early;
        undecidable += !decidable;
        bad += lost + early + (again[i].prim != RayHit::kNoHit) + (blocked[i] != 0);
      }
      rays += 3 * out.size();
      if (bad && first.empty())
        first = "; first at radius " + stressFormat("%.0e", radius) + ", " + stressFormat("%.0e", offset) + " radii out";
    }
  StressRow row;
  row.group = "primitives";
  row.name = "spheres left at elevations 1e-4 to 1.2 rad, radii 1e-4 to 1e4, up to 1e4 radii from the origin";
  row.figure = std::to_string(outHits) + " hits (closest + any) leaving outwards, " + std::to_string(inEarly) +
               " hits short of the far side and " + std::to_string(inLost) + " misses leaving inwards, in " +
               std::to_string(rays) + " rays (" + std::to_string(undecidable) +
               " inward chords within 16 float spacings of the coordinates not counted)" + first;
  row.criterion = "0 of each";
  row.pass = outHits == 0 && inEarly == 0 && inLost == 0 && rays > 0;
  row.seconds = secondsSince(start);
  return row;
}

std::vector<StressRow> sphereDegenerate(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  // in a scene file: refused, naming the field
  struct FileCase {
    const char* name;
    const char* object;
  };
  const FileCase files[] = {{"radius 0", R"({"type": "sphere", "center": [0, 0, 0], "radius": 0})"},
                            {"radius -1", R"({"type": "sphere", "center": [0, 0, 0], "radius": -1})"},
                            {"radius 1e39 (past float)", R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e39})"},
                            {"centre 1e39 (past float)", R"({"type": "sphere", "center": [1e39, 0, 0], "radius": 1})"}};
  for (const FileCase& c : files) rows.push_back(refusedObjectRow(std::string("a sphere of ") + c.name, c.object));
  // made in code (no validator in the way): left out, the rest renders
  const auto start = std::chrono::steady_clock::now();
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(1.0f)));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  scene.spheres = {{glm::vec3(0.0f), 0.0f, 0}, {glm::vec3(nan, 0.0f, 0.0f), 1.0f, 0}, {glm::vec3(0.0f), inf, 0},
                   {glm::vec3(0.0f), -2.0f, 0}, {glm::vec3(0.0f, 0.0f, -4.0f), 1.0f, 0}};
  rows.push_back(leftOutRow(context, options, scene, start,
                            "spheres made in code: radius 0, a NaN centre, radius inf, radius -2, and one good one", 4));
  return rows;
}

/// Rays re-spawned off a curve segment (a round cone of radii r and r/2,
/// 4 r long: convex whatever its float joints) at elevations from 1e-4 to
/// 1.2 rad: outwards nothing may be hit, inwards the segment must be met
/// again.
StressRow curveSelfIntersection(Context& context, const StressOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> s(-1.0f, 1.0f), u(0.0f, 1.0f);
  auto randomUnit = [&] {
    glm::vec3 d;
    do d = glm::vec3(s(rng), s(rng), s(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-3f);
    return glm::normalize(d);
  };
  std::uint64_t rays = 0, outHits = 0, inLost = 0, undecidable = 0;
  std::string first;
  const int hitsPer = options.quick ? 300 : 4000;
  for (float radius : {1e-4f, 1.0f, 1e4f})
    for (float offset : {0.0f, 1e2f, 1e4f}) {
      const glm::vec3 center = offset * radius * glm::normalize(glm::vec3(1.0f, -0.6f, 0.8f));
      const glm::vec3 axis = glm::normalize(glm::vec3(0.3f, 1.0f, -0.4f));
      Scene scene;
      scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
      const glm::vec3 a = center - 2.0f * radius * axis, b = center + 2.0f * radius * axis;
      scene.curvePoints = {{a.x, a.y, a.z, radius}, {b.x, b.y, b.z, 0.5f * radius}};
      scene.curves = {{0, 2, 0, CurveBasis::kLinear}};
      const PrimitiveRows gathered = gatherPrimitives(scene);
      Tracer tracer(context, scene);
      std::vector<Ray> firstRays(static_cast<std::size_t>(hitsPer));
      for (Ray& r : firstRays) {
        r.origin = center + radius * 6.0f * randomUnit();
        r.direction = glm::normalize(center + (4.0f * u(rng) - 2.0f) * radius * axis + 0.45f * radius * randomUnit() - r.origin);
      }
      const std::vector<RayHit> hits = tracer.traceClosest(firstRays);
      std::vector<Ray> out, in;
      std::vector<float> elevationOf;
      for (std::size_t i = 0; i < hits.size(); ++i) {
        if (hits[i].prim == RayHit::kNoHit) continue;
        glm::vec3 error, n;
        const glm::vec3 p = curvePoint(curveSegment(gathered, primIndex(hits[i].prim)), firstRays[i].origin,
                                       firstRays[i].direction, hits[i].t, &error, &n);
        for (float elevation : {1e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.2f}) {
          const glm::vec3 tangent = glm::normalize(glm::cross(n, randomUnit()));
          Ray r;
          r.skip = hits[i].prim;
          r.origin = offsetRayOrigin(p, error, n);
          r.direction = glm::normalize(std::cos(elevation) * tangent + std::sin(elevation) * n);
          out.push_back(r);
          r.origin = offsetRayOrigin(p, error, -n);
          r.direction = glm::normalize(std::cos(elevation) * tangent - std::sin(elevation) * n);
          in.push_back(r);
          elevationOf.push_back(elevation);
        }
      }
      const std::vector<RayHit> again = tracer.traceClosest(out), across = tracer.traceClosest(in);
      const std::vector<std::uint8_t> blocked = tracer.traceOccluded(out, Traversal::kStream);
      std::uint64_t bad = 0;
      for (std::size_t i = 0; i < out.size(); ++i) {
        outHits += (again[i].prim != RayHit::kNoHit) + (blocked[i] != 0);
        // an inward chord is at least 2 (r/2) sin(elevation); one within 16
        // float spacings of the coordinates is below what the origin's own
        // rounding can tell (not counted)
        const float spacing = 1.1920929e-7f * (glm::length(center) + radius);
        const bool decidable = radius * std::sin(elevationOf[i]) > 16.0f * spacing;
        const bool lost = decidable && across[i].prim == RayHit::kNoHit;
        inLost += lost;
        undecidable += !decidable;
        bad += lost + (again[i].prim != RayHit::kNoHit) + (blocked[i] != 0);
      }
      rays += 3 * out.size();
      if (bad && first.empty())
        first = "; first at radius " + stressFormat("%.0e", radius) + ", " + stressFormat("%.0e", offset) + " radii out";
    }
  StressRow row;
  row.group = "primitives";
  row.name = "curve segments (round cones) left at elevations 1e-4 to 1.2 rad, radii 1e-4 to 1e4, up to 1e4 radii "
             "from the origin";
  row.figure = std::to_string(outHits) + " hits (closest + any) leaving outwards and " + std::to_string(inLost) +
               " misses leaving inwards, in " + std::to_string(rays) + " rays (" + std::to_string(undecidable) +
               " inward chords within 16 float spacings of the coordinates not counted)" + first;
  row.criterion = "0 of each";
  row.pass = outHits == 0 && inLost == 0 && rays > 0;
  row.seconds = secondsSince(start);
  return row;
}

std::vector<StressRow> curveDegenerate(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  // in a scene file: refused, naming the field
  struct FileCase {
    const char* name;
    const char* object;
  };
  const FileCase files[] = {
      {"radius 0", R"({"type": "curves", "strands": [[[0, 0, 0], [1, 0, 0]]], "radius": 0})"},
      {"a point of radius -1", R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, -1]]]})"},
      {"a point at 1e39 (past float)", R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1e39, 0, 0, 1]]]})"},
      {"a strand of one point", R"({"type": "curves", "strands": [[[0, 0, 0, 1]]]})"}};
  for (const FileCase& c : files) rows.push_back(refusedObjectRow(std::string("curves with ") + c.name, c.object));
  // made in code (no validator in the way): left out, the rest renders
  const auto start = std::chrono::steady_clock::now();
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(1.0f)));
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  auto add = [&](std::initializer_list<WtVec4> points, CurveBasis basis = CurveBasis::kLinear) {
    scene.curves.push_back({std::uint32_t(scene.curvePoints.size()), std::uint32_t(points.size()), 0, basis});
    scene.curvePoints.insert(scene.curvePoints.end(), points.begin(), points.end());
  };
  add({{-1, 0, 0, 0}, {1, 0, 0, 0}});                        // radius 0 at both ends
  add({{-1, 0, 0, 0.5f}, {0, nan, 0, 0.5f}, {1, 0, 0, 0.5f}});  // a NaN point
  add({{-1, 0, 0, 0.5f}, {1, 0, 0, -2.0f}});                 // a negative radius
  add({{-1, 0, 0, inf}, {1, 0, 0, 0.5f}});                   // an infinite radius
  add({{0, 0, 0, 0.5f}, {0, 0, 0, 0.7f}, {0, 0, 0, 0.2f}});  // one point thrice
  add({{0, 0, 0, 0.5f}, {nan, 0, 0, 0.5f}, {0, 0, 1, 0.5f}, {0, 1, 1, 0.5f}}, CurveBasis::kBSpline);
  add({{-1, 0, -4, 1.0f}, {-1, 0, -4, 1.0f}, {1, 0, -4, 1.0f}});  // coincident points, then a good segment
  StressRow row = leftOutRow(context, options, scene, start,
                             "curves made in code: radius 0, a NaN point, radius -2, radius inf, one point thrice, a "
                             "B-spline with a NaN point, coincident points before a good segment",
                             6);
  rows.push_back(row);
  return rows;
}

/// An SDF torus and a noisy SDF sphere (64^3 cells, one sparse, one dense)
/// on a ground sphere under a sphere light, scaled by `scale` and moved by
/// `translate` on every axis, as a scene file; `instanced`: the torus placed
/// twice by "instances", the second copy 20 units behind the camera.
std::string sdfSceneJson(double translate, double scale, bool instanced = false) {
  const stress_rows::ScaledJson json{translate, scale};
  auto p = [&](double x, double y, double z) { return json.point(x, y, z); };
  auto r = [&](double v) { return json.length(v); };
  const std::string copies =
      instanced ? R"(, "instances": [{"translate": [0, 0, 0]}, {"translate": [0, 0, )" + r(20) + "]}]" : "";
  return json.stage(R"(    "metal": {"base_color": [0.9, 0.6, 0.3], "metallic": 1, "roughness": 0.3},
    "white": {"type": "lambert", "base_color": [0.8, 0.8, 0.8]},
)",
                    R"(    {"type": "sdf", "shape": "torus", "resolution": 64, "storage": "sparse", "material": "metal",
     "transform": {"translate": )" + p(-0.6, 0.3, 0) + R"(, "scale": )" + r(0.6) + "}" + copies + R"(},
    {"type": "sdf", "shape": "noisy_sphere", "resolution": 64, "storage": "dense", "material": "white",
     "transform": {"translate": )" + p(0.6, 0.45, 0.2) + R"(, "scale": )" + r(0.5) + R"(}},
)");
}

/// The SDF scene translated to 1e6 and scaled from 1e-4 to 1e4 renders the
/// untransformed image within noise.
std::vector<StressRow> sdfTransforms(Context& context, const StressOptions& options) {
  const stress_rows::TransformStudy study = stress_rows::transformStudy(options, 4);
  std::vector<StressRow> rows = stress_rows::transformRows(
      "SDF grids (a sparse torus, a dense noisy sphere, 64^3)", options, study, [&](double translate, double scale) {
        return render(context, loadSceneFileFromMemory(sdfSceneJson(translate, scale), "sdf (stress)", ".").scene,
                      study.settings);
      });
  // as an instance: the full suite only (the quick one's budget; CTest's instancing tests cover the copies)
  if (options.quick) return rows;
  for (StressRow& row : stress_rows::instancedTransformRows(
           context, "SDF grids, the torus as an instance (two copies, one behind the camera)", options, study, 2,
           [&](double translate, double scale) {
             return loadSceneFileFromMemory(sdfSceneJson(translate, scale, true), "sdf (stress)", ".").scene;
           }))
    rows.push_back(std::move(row));
  return rows;
}

/// SDF grids with NaN, no surface, or an unusable shape: a NaN in a .vol
/// file is refused naming the file; a constant grid in a scene file loads
/// with a warning; grids made in code (constant, all negative, NaN, no
/// cells, a singular placement) are left out or draw nothing, never a crash
/// or a NaN, while a good emitter renders.
std::vector<StressRow> sdfDegenerate(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  {
    const auto start = std::chrono::steady_clock::now();
    const std::string path = (std::filesystem::temp_directory_path() / "wt-stress-nan.vol").string();
    std::vector<float> values(4 * 4 * 4, 1.0f);
    values[21] = nan;
    writeVolFile(path, glm::uvec3(4), values, glm::dvec3(0.0), glm::dvec3(1.0));
    std::string error;
    try {
      loadSceneFileFromMemory(R"({"version": 1, "objects": [{"type": "sdf", "file": ")" + path + R"("}]})", "nan.json", ".");
    } catch (const SceneError& e) {
      error = e.what();
    }
    std::filesystem::remove(path);
    StressRow row;
    row.group = "primitives";
    row.name = "scene file, an SDF .vol grid with a NaN value";
    row.figure = error.empty() ? "loaded" : "error: " + error;
    row.criterion = "an error naming the scene file, objects[0].file, the .vol file and the value";
    row.pass = error.find("nan.json") != std::string::npos && error.find("objects[0].file") != std::string::npos &&
               error.find("wt-stress-nan.vol") != std::string::npos && error.find("NaN") != std::string::npos;
    row.seconds = secondsSince(start);
    rows.push_back(row);
  }
  {
    const auto start = std::chrono::steady_clock::now();
    std::string warnings, error;
    try {
      const SceneFile f = loadSceneFileFromMemory(
          R"({"version": 1, "objects": [{"type": "sdf", "shape": "sphere", "radius": 5, "resolution": 8}]})",
          "constant.json", ".");
      for (const std::string& w : f.scene.warnings) warnings += w;
    } catch (const SceneError& e) {
      error = e.what();
    }
    StressRow row;
    row.group = "primitives";
    row.name = "scene file, an SDF grid all inside (a sphere larger than its box)";
    row.figure = error.empty() ? "warnings: " + warnings : "error: " + error;
    row.criterion = "loads, warning that objects[0] has no surface";
    row.pass = error.empty() && warnings.find("objects[0]") != std::string::npos &&
               warnings.find("no surface") != std::string::npos;
    row.seconds = secondsSince(start);
    rows.push_back(row);
  }
  const auto start = std::chrono::steady_clock::now();
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(1.0f)));
  auto grid = [](float value) {
    SdfGrid g;
    g.cells = glm::uvec3(4);
    g.values.assign(5 * 5 * 5, value);
    g.latticeToScene = glm::translate(glm::dmat4(1.0), glm::dvec3(-2.0, -2.0, -3.0));
    return g;
  };
  scene.sdfGrids.push_back(grid(0.0f));
  scene.sdfGrids.push_back(grid(-1.0f));
  scene.sdfGrids.push_back(grid(2.0f));
  scene.sdfGrids.push_back(grid(nan));
  SdfGrid empty = grid(1.0f);
  empty.cells = glm::uvec3(0);
  scene.sdfGrids.push_back(empty);
  SdfGrid flat = grid(-1.0f);
  flat.values[0] = 1.0f;
  flat.latticeToScene[2] = glm::dvec4(0.0);  // singular
  scene.sdfGrids.push_back(flat);
  scene.spheres.push_back({glm::vec3(0.0f, 0.0f, -6.0f), 1.0f, 0});
  rows.push_back(leftOutRow(context, options, scene, start,
                            "SDF grids made in code: constant 0, all inside, all outside, all NaN (no bricks), no cells and a "
                            "singular placement (left out), behind them a good emitter",
                            2));
  return rows;
}

}  // namespace

std::vector<StressRow> stressPrimitives(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows = sphereTransforms(context, options);
  rows.push_back(sphereSelfIntersection(context, options));
  for (StressRow& row : sphereDegenerate(context, options)) rows.push_back(std::move(row));
  rows.push_back(curveSelfIntersection(context, options));
  for (StressRow& row : curveDegenerate(context, options)) rows.push_back(std::move(row));
  for (StressRow& row : sdfTransforms(context, options)) rows.push_back(std::move(row));
  for (StressRow& row : sdfDegenerate(context, options)) rows.push_back(std::move(row));
  for (StressRow& row : stressDisplaced(context, options)) rows.push_back(std::move(row));
  return rows;
}

}  // namespace wt
