#include "bench/bench.h"
#include "core/embedded.h"

#include "bench/embree_reference.h"
#include "bench/generated_scenes.h"
#include "bvh/builders.h"
#include "bvh/bvh4.h"
#include "bvh/lbvh.h"
#include "core/log.h"
#include "core/spawn.h"
#include "device/context.h"
#include "device/program.h"
#include "device/scene_buffers.h"
#include "device/tracer.h"
#include "geometry/primitives.h"
#include "render/renderer.h"
#include "scene/default_scene.h"
#include "scene/generators.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

#ifdef WT_HAVE_EMBREE
constexpr bool kHaveEmbree = true;
#else
constexpr bool kHaveEmbree = false;
#endif

// ---- ray sets ----------------------------------------------------------------------

/// Uniform floats in [0,1) from a counter: the ray sets do not depend on the
/// order or thread they are made in.
struct Rng {
  std::uint64_t state;
  explicit Rng(std::uint64_t seed) : state(seed * 0x9e3779b97f4a7c15ull + 0x632be59bd9b4e019ull) {}
  float next() {
    // splitmix64
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return float(z >> 40) * 0x1p-24f;
  }
};

glm::vec3 position(const Scene& scene, std::uint32_t v) {
  return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z);
}

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

/// Where a camera ray hit: the point from the barycentrics and the unit
/// geometric normal turned towards the camera, the origin offset along it.
struct SurfacePoint {
  glm::vec3 origin;  ///< offset off the surface, camera side
  glm::vec3 normal;  ///< unit, camera side
  glm::vec3 point, error;  ///< on the surface, and its rounding error bound
};

/// `rows`: the scene's other primitives as gathered (gatherPrimitives), for curves.
std::optional<SurfacePoint> surfacePoint(const Scene& scene, const PrimitiveRows& rows, const Ray& ray,
                                         const RayHit& hit) {
  if (hit.prim == RayHit::kNoHit) return std::nullopt;
  if (primType(hit.prim) == WT_PRIM_CURVE) {
    glm::vec3 error, n;
    glm::vec3 p = curvePoint(curveSegment(rows, primIndex(hit.prim)), ray.origin, ray.direction, hit.t, &error, &n);
    if (glm::dot(n, ray.direction) > 0.0f) n = -n;
    return SurfacePoint{offsetRayOrigin(p, error, n), n, p, error};
  }
  if (primType(hit.prim) == WT_PRIM_SPHERE) {
    const Sphere& sphere = scene.spheres[primIndex(hit.prim)];
    glm::vec3 error, n;
    glm::vec3 p = spherePoint(sphere.center, sphere.radius, ray.origin, ray.direction, hit.t, &error, &n);
    if (glm::dot(n, ray.direction) > 0.0f) n = -n;
    return SurfacePoint{offsetRayOrigin(p, error, n), n, p, error};
  }
  if (primType(hit.prim) == WT_PRIM_SDF_GRID) {
    glm::vec3 error, n;
    glm::vec3 p = sdfGridPoint(rows, primIndex(hit.prim), ray.origin, ray.direction, hit.t, hit.b1, &error, &n);
    if (!(glm::dot(n, n) > 0.0f)) return std::nullopt;
    if (glm::dot(n, ray.direction) > 0.0f) n = -n;
    return SurfacePoint{offsetRayOrigin(p, error, n), n, p, error};
  }
  if (primType(hit.prim) == WT_PRIM_DISPLACED) {
    const DisplacedTriangleRef ref = displacedTriangle(rows, primIndex(hit.prim));
    glm::vec3 error, n;
    glm::vec3 p = displacedPoint(scene.displacedMeshes[ref.mesh], ref.triangle, hit.b1, hit.b2, &error, &n);
    if (!(glm::dot(n, n) > 0.0f)) return std::nullopt;
    if (glm::dot(n, ray.direction) > 0.0f) n = -n;
    return SurfacePoint{offsetRayOrigin(p, error, n), n, p, error};
  }
  if (primType(hit.prim) != WT_PRIM_TRIANGLE) return std::nullopt;
  const WtTriangle& tri = scene.triangles[hit.triangle];
  glm::vec3 p0 = position(scene, tri.v0), p1 = position(scene, tri.v1), p2 = position(scene, tri.v2);
  glm::vec3 error;
  glm::vec3 p = trianglePoint(p0, p1, p2, hit.b1, hit.b2, &error);
  glm::vec3 n = glm::cross(p1 - p0, p2 - p0);
  float len = glm::length(n);
  if (!(len > 0.0f)) return std::nullopt;
  n /= len;
  if (glm::dot(n, ray.direction) > 0.0f) n = -n;
  return SurfacePoint{offsetRayOrigin(p, error, n), n, p, error};
}

/// Cosine-distributed directions about the camera-side normal at every
/// camera hit (misses make no ray).
std::vector<Ray> diffuseRays(const Scene& scene, const PrimitiveRows& rows, std::span<const Ray> primary,
                             std::span<const RayHit> hits) {
  std::vector<Ray> rays;
  rays.reserve(primary.size());
  for (std::size_t i = 0; i < primary.size(); ++i) {
    std::optional<SurfacePoint> s = surfacePoint(scene, rows, primary[i], hits[i]);
    if (!s) continue;
    Rng rng(2 * i + 1);
    float u1 = rng.next(), u2 = rng.next();
    float r = std::sqrt(u1), phi = 6.2831853f * u2;
    glm::vec3 n = s->normal;
    // orthonormal basis (Duff et al. 2017)
    float sign = std::copysign(1.0f, n.z), a = -1.0f / (sign + n.z), c = n.x * n.y * a;
    glm::vec3 t(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x), b(c, sign + n.y * n.y * a, -n.y);
    glm::vec3 d = r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0f, 1.0f - u1)) * n;
    Ray ray;
    ray.origin = s->origin;
    ray.direction = glm::normalize(d);
    ray.tmin = 0.0f;
    ray.tmax = 1e30f;
    ray.skip = hits[i].prim;  // as the renderer spawns: never the primitive left (Embree has no such test)
    rays.push_back(ray);
  }
  return rays;
}

/// From every camera hit to a random point on an emissive triangle (by area),
/// or in the scene's bounds when nothing emits; tmax stops a relative 1e-4
/// short of the target, so the target's own surface never counts.
std::vector<Ray> shadowRays(const Scene& scene, const PrimitiveRows& rows, std::span<const Ray> primary,
                            std::span<const RayHit> hits,
                            bool* toEmitters) {
  std::vector<std::uint32_t> emitters;
  std::vector<double> cdf;
  double total = 0.0;
  for (std::uint32_t i = 0; i < scene.triangles.size(); ++i) {
    const WtTriangle& tri = scene.triangles[i];
    const WtVec4& e = scene.materials[tri.material].emission;
    if (!(e.x > 0.0f || e.y > 0.0f || e.z > 0.0f)) continue;
    glm::vec3 p0 = position(scene, tri.v0), p1 = position(scene, tri.v1), p2 = position(scene, tri.v2);
    double area = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    if (!(area > 0.0) || !std::isfinite(area)) continue;
    total += area;
    emitters.push_back(i);
    cdf.push_back(total);
  }
  // emissive spheres after the triangles (index past the triangles), by area
  for (std::uint32_t i = 0; i < scene.spheres.size(); ++i) {
    const Sphere& sphere = scene.spheres[i];
    const WtVec4& e = scene.materials[sphere.material].emission;
    if (!(e.x > 0.0f || e.y > 0.0f || e.z > 0.0f)) continue;
    double area = 4.0 * 3.14159265358979 * double(sphere.radius) * sphere.radius;
    if (!(area > 0.0) || !std::isfinite(area)) continue;
    total += area;
    emitters.push_back(std::uint32_t(scene.triangles.size()) + i);
    cdf.push_back(total);
  }
  *toEmitters = !emitters.empty();
  Aabb bounds = scene.bounds();
  glm::vec3 lo(bounds.lo.x, bounds.lo.y, bounds.lo.z), hi(bounds.hi.x, bounds.hi.y, bounds.hi.z);

  std::vector<Ray> rays;
  rays.reserve(primary.size());
  for (std::size_t i = 0; i < primary.size(); ++i) {
    std::optional<SurfacePoint> s = surfacePoint(scene, rows, primary[i], hits[i]);
    if (!s) continue;
    Rng rng(2 * i + 2);
    glm::vec3 target;
    if (!emitters.empty()) {
      double pick = rng.next() * total;
      std::size_t k = std::min<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), pick) - cdf.begin(),
                                            emitters.size() - 1);
      if (emitters[k] >= scene.triangles.size()) {
        // a point of the sphere's half that faces the shading point
        const Sphere& sphere = scene.spheres[emitters[k] - scene.triangles.size()];
        glm::vec3 w;
        do w = 2.0f * glm::vec3(rng.next(), rng.next(), rng.next()) - 1.0f;
        while (glm::dot(w, w) > 1.0f || glm::dot(w, w) < 1e-4f);
        w = glm::normalize(w);
        if (glm::dot(w, s->point - sphere.center) < 0.0f) w = -w;
        target = sphere.center + sphere.radius * w;
      } else {
        const WtTriangle& tri = scene.triangles[emitters[k]];
        float u1 = std::sqrt(rng.next()), u2 = rng.next();
        target = (1.0f - u1) * position(scene, tri.v0) + u1 * (1.0f - u2) * position(scene, tri.v1) +
                 u1 * u2 * position(scene, tri.v2);
      }
    } else {
      target = lo + glm::vec3(rng.next(), rng.next(), rng.next()) * (hi - lo);
    }
    // Leave on the target's side of the surface, as a renderer spawns any ray
    // (pbrt's OffsetRayOrigin): a target behind the surface is reached
    // through it, the way light reaches a thin translucent sheet. From the
    // camera side instead, such a ray would start within rounding error of
    // the surface it must cross, which neither tracer can decide.
    glm::vec3 origin = glm::dot(s->normal, target - s->point) >= 0.0f ? s->origin
                                                                       : offsetRayOrigin(s->point, s->error, -s->normal);
    glm::vec3 d = target - origin;
    float distance = glm::length(d);
    if (!(distance > 0.0f) || !std::isfinite(distance)) continue;
    Ray ray;
    ray.skip = hits[i].prim;
    ray.origin = origin;
    ray.direction = d / distance;
    ray.tmin = 0.0f;
    ray.tmax = (1.0f - 1e-4f) * distance;
    rays.push_back(ray);
  }
  return rays;
}

// ---- agreement ---------------------------------------------------------------------

/// Why wavetrace and Embree disagree on a ray, judged in double precision
/// the way tests/brute_force.h judges the kernels.
enum class Disagreement {
  kTie,            ///< both hit, different triangles at the same t (shared edges, overlaps)
  kEdge,           ///< the nearer reported hit lies within 1e-5 (barycentric) of an edge
  kRange,          ///< the nearer reported hit lies within 1e-5 (relative) of tmin or tmax
  kWavetraceMiss,  ///< Embree's hit is clearly inside its triangle and the range; wavetrace missed it
  kEmbreeMiss,     ///< the converse
  kWavetraceFalse, ///< wavetrace reported a hit clearly outside its triangle
  kEmbreeFalse,    ///< the converse
  kInconsistent,   ///< occlusion only: a tracer's any-hit answer contradicts its own closest hit
  kSelf,           ///< Embree hit the triangle the ray leaves, which wavetrace never tests (Ray::skip): a ray grazing its own plane, e.g. from a point on an emitter to another on the same triangle
  kCount
};
const char* kDisagreementNames[] = {"t_tie", "edge_graze", "range_end", "wavetrace_missed",
                                    "embree_missed", "wavetrace_false_hit", "embree_false_hit",
                                    "anyhit_vs_closest", "embree_hit_the_triangle_left"};
constexpr double kTie = 1e-5, kEdge = 1e-5;

/// Ray-plane distance and the crossing's minimum barycentric, in double; false when parallel.
bool crossing(const Scene& scene, std::uint32_t tri, const Ray& ray, double& t, double& minB) {
  const WtTriangle& tr = scene.triangles[tri];
  glm::dvec3 p0(position(scene, tr.v0)), p1(position(scene, tr.v1)), p2(position(scene, tr.v2));
  glm::dvec3 o(ray.origin), d(ray.direction);
  glm::dvec3 e1 = p1 - p0, e2 = p2 - p0, pv = glm::cross(d, e2);
  double det = glm::dot(e1, pv);
  if (det == 0.0) return false;
  double inv = 1.0 / det;
  glm::dvec3 tv = o - p0, qv = glm::cross(tv, e1);
  double b1 = glm::dot(tv, pv) * inv, b2 = glm::dot(d, qv) * inv;
  t = glm::dot(e2, qv) * inv;
  minB = std::min({1.0 - b1 - b2, b1, b2});
  return true;
}

/// A sphere crossing in double: the nearer root in (tmin, ...) and how far
/// the line passes inside the silhouette, relative to the radius (< 0: outside).
bool sphereCrossing(const Sphere& sphere, const Ray& ray, double& t, double& inside) {
  glm::dvec3 f = glm::dvec3(ray.origin) - glm::dvec3(sphere.center), d(ray.direction);
  double a = glm::dot(d, d), b = glm::dot(f, d), r = sphere.radius;
  double line = std::sqrt(std::max(0.0, glm::dot(f, f) - b * b / a));
  inside = (r - line) / r;
  double disc = b * b - a * (glm::dot(f, f) - r * r);
  if (disc < 0.0) return true;
  double t0 = (-b - std::sqrt(disc)) / a, t1 = (-b + std::sqrt(disc)) / a;
  t = t0 > ray.tmin ? t0 : t1;
  return true;
}

Disagreement classify(const Scene& scene, const PrimitiveRows& rows, const Ray& ray, const RayHit& wt,
                      const RayHit& em) {
  const bool wtHit = wt.prim != RayHit::kNoHit, emHit = em.prim != RayHit::kNoHit;
  auto close = [](double a, double b) { return std::abs(a - b) <= kTie * std::max(1.0, std::abs(b)); };
  if (wtHit && emHit && close(wt.t, em.t)) return Disagreement::kTie;
  if (emHit && em.prim == ray.skip && (!wtHit || em.t < wt.t)) return Disagreement::kSelf;
  // the nearer of the two reported hits is the one the other tracer missed
  const bool wtNearer = wtHit && (!emHit || wt.t < em.t);
  const RayHit& nearer = wtNearer ? wt : em;
  double t = 0.0, minB;
  if (primType(nearer.prim) == WT_PRIM_CURVE) {
    // the ray's line against the segment's axis: the radius at the closest
    // approach (the hull's silhouette to first order)
    const CurveSegment c = curveSegment(rows, primIndex(nearer.prim));
    const glm::dvec3 a(c.p0), e = glm::dvec3(c.p1) - a, o(ray.origin), d = glm::normalize(glm::dvec3(ray.direction));
    const double ee = glm::dot(e, e), ed = glm::dot(e, d);
    const glm::dvec3 w = a - o;
    const double denom = ee - ed * ed;
    double u = denom > 1e-30 ? std::clamp((ed * glm::dot(w, d) - glm::dot(w, e)) / denom, 0.0, 1.0) : 0.0;
    const glm::dvec3 q = a + u * e;
    const double along = glm::dot(q - o, d);
    const double distance = glm::length(q - o - along * d);
    const double radius = c.p0.w + u * (c.p1.w - c.p0.w);
    const double inside = radius > 0.0 ? (radius - distance) / radius : -1.0;
    if (std::abs(inside) < 1e-3) return Disagreement::kEdge;  // the silhouette grazed
    if (inside < 0.0) return wtNearer ? Disagreement::kWavetraceFalse : Disagreement::kEmbreeFalse;
    if (close(nearer.t, ray.tmin) || close(nearer.t, ray.tmax)) return Disagreement::kRange;
    return wtNearer ? Disagreement::kEmbreeMiss : Disagreement::kWavetraceMiss;
  }
  if (primType(nearer.prim) == WT_PRIM_SPHERE) {
    double inside;
    sphereCrossing(scene.spheres[primIndex(nearer.prim)], ray, t, inside);
    if (std::abs(inside) < kEdge) return Disagreement::kEdge;  // the silhouette grazed
    if (inside < 0.0) return wtNearer ? Disagreement::kWavetraceFalse : Disagreement::kEmbreeFalse;
    if (close(t, ray.tmin) || close(t, ray.tmax)) return Disagreement::kRange;
    return wtNearer ? Disagreement::kEmbreeMiss : Disagreement::kWavetraceMiss;
  }
  if (!crossing(scene, nearer.triangle, ray, t, minB)) return Disagreement::kEdge;  // parallel: a graze
  if (std::abs(minB) < kEdge) return Disagreement::kEdge;
  if (minB < 0.0) return wtNearer ? Disagreement::kWavetraceFalse : Disagreement::kEmbreeFalse;
  if (close(t, ray.tmin) || close(t, ray.tmax)) return Disagreement::kRange;
  return wtNearer ? Disagreement::kEmbreeMiss : Disagreement::kWavetraceMiss;
}

struct Agreement {
  std::size_t disagreements = 0;
  std::size_t byClass[std::size_t(Disagreement::kCount)] = {};
  std::size_t explained() const {
    return byClass[std::size_t(Disagreement::kTie)] + byClass[std::size_t(Disagreement::kEdge)] +
           byClass[std::size_t(Disagreement::kRange)] + byClass[std::size_t(Disagreement::kSelf)];
  }
};

// ---- timing ------------------------------------------------------------------------

/// The reference tracer as the bench calls it (Embree when the build has it);
/// plain functions, so this file links without Embree.
struct Reference {
  std::function<std::vector<RayHit>(std::span<const Ray>, bool coherent)> closest;
  std::function<std::vector<std::uint8_t>(std::span<const Ray>, bool coherent)> occluded;
  /// The ways of handing rays over that a set is timed with (the fastest is
  /// compared), and the one later calls use.
  std::vector<std::string> apis;
  std::function<void(const std::string&)> setApi;
  /// The last call's tracing time alone (EmbreeReference::lastTraceSeconds).
  std::function<double()> lastTraceSeconds;
};

struct SetResult {
  std::string name;
  bool occlusion = false;
  std::size_t rays = 0;
  double hitFraction = 0.0;  ///< wavetrace: hit or occluded
  double wallSeconds = 0.0, kernelSeconds = 0.0;
  bool embree = false;
  double embreeSeconds = 0.0;      ///< Embree's tracing alone (EmbreeReference::lastTraceSeconds), the fastest API's median
  double embreeWallSeconds = 0.0;  ///< the same API's whole calls: the rays put in its layout, traced, the answers read out
  std::string embreeApi;  ///< the API embreeSeconds was measured with (the fastest of Reference::apis)
  double embreeHitFraction = 0.0;
  Agreement agreement;
  Traversal traversal = Traversal::kSingle;
  double coherence = 0.0;  ///< packetCoherence of the set's rays
  double octantShare = 0.0;   ///< RayBatchStats::octantShare of a sample of its packets
  double originSpread = 0.0;  ///< RayBatchStats::originSpread of that sample, in primitive scales (primitiveScale)
};

/// One builder's tree of a scene, traced on the same rays as the others.
struct TreeResult {
  BvhBuilder builder = BvhBuilder::Auto;
  double buildSeconds = 0.0;  ///< median of the repetitions, whole build (PLOC: LBVH + PLOC)
  std::size_t nodes = 0, nodes4 = 0;
  double sah = 0.0, sah4 = 0.0;
  double bytesPerTriangle = 0.0;
  std::string kernelDir;  ///< --ab-kernel-dir for that row; empty: the kernels every other row traces
  int packetWidth = 0;    ///< --ab-packet-width for that row; 0: the width every other row traces
  std::string traversal;  ///< --ab-traversal for that row; empty: each set's own (benchSet's choice)
  bool ab() const { return !kernelDir.empty() || packetWidth != 0 || !traversal.empty(); }
  std::vector<double> kernelSeconds;  ///< per ray set, median, interleaved with the other trees
  std::vector<double> hitFraction;    ///< per ray set
};

struct SceneResult {
  std::string name;
  std::size_t triangles = 0;
  double buildSeconds = 0.0;
  std::size_t nodes = 0;
  double sah = 0.0;
  std::size_t nodes4 = 0;  ///< the 4-wide tree the kernels traverse
  double collapseSeconds = 0.0;  ///< binary to 4-wide and the leaves packed in blocks (median), not in buildSeconds
  double sah4 = 0.0;
  double bytesPerTriangle = 0.0;  ///< SceneBuffers::triangleBytes per scene triangle (instances' rows and tree included)
  std::size_t instances = 0;     ///< copies stored as instances (--instancing)
  std::size_t leafMisfits = 0;  ///< leaves taking one more four-lane test than their size needs
  std::size_t copiesPlaced = 0;  ///< copies given their geometry's shared tree (--bvh auto)
  std::size_t flatRegions = 0;   ///< regions the LBVH keyed with their thin axis last
  bool shadowToEmitters = false;
  int packetWidth = 0;  ///< rays per packet for this scene (packetWidthFor, by the device and the triangles)
  bool streamPrefetch = false;  ///< the streams ask for a node's children early (streamPrefetchFor)
  double embreeBuildSeconds = 0.0;
  /// The other geometry types (host/geometry/primitives.h): primitives per
  /// WT_PRIM_* type, their BVH's build and collapse (median) and the bytes
  /// uploaded for them (nodes, typed ids, rows) per primitive.
  std::array<std::size_t, WT_PRIM_TYPES> primitives{};
  double primitiveBuildSeconds = 0.0;
  double primitiveGatherSeconds = 0.0;  ///< gatherPrimitives: boxes and rows (an SDF grid's bricks found and packed)
  double bytesPerPrimitive = 0.0;
  double tessellateSeconds = 0.0;  ///< --tessellate: making the triangles (before the BVH build)
  std::vector<SetResult> sets;
  double pathMrays = 0.0;
  /// Time per path sample with the scene's specialised program and with the
  /// general one (every switch on), samples interleaved; their builds
  double pathMsPerSample = 0.0, pathMsPerSampleGeneral = 0.0;
  double programSeconds = 0.0, programSecondsGeneral = 0.0;
  std::vector<TreeResult> trees;  ///< --compare-bvh, in that order
};

/// Primitives per second of the whole traversable build: binary tree and collapse.
double traversableRate(const SceneResult& r) {
  const double seconds = r.buildSeconds + r.collapseSeconds;
  return seconds > 0.0 ? double(r.triangles) / seconds * 1e-6 : 0.0;
}

/// The traversal --traversal picks for a set of rays: as asked, or (auto)
/// chooseTraversal's choice from the rays' measured statistics
/// (host/device/tracer.h). Streams are for any hit only: a closest-hit set
/// given "stream" is traced one ray per work-item.
Traversal setTraversal(const BenchOptions& options, const Tracer& tracer, const RayBatchStats& stats, bool occlusion) {
  if (options.traversal == "single") return Traversal::kSingle;
  if (options.traversal == "packet") return Traversal::kPacket;
  if (options.traversal == "stream") return occlusion ? Traversal::kStream : Traversal::kSingle;
  return chooseTraversal(stats, tracer.primitiveScale(), occlusion, tracer.context().info().isCpu);
}

const char* traversalName(Traversal t) {
  return t == Traversal::kPacket ? "packet" : t == Traversal::kStream ? "stream" : "single";
}

/// Each run's wall time: `repetitions` runs, then more while they add up
/// to less than minSeconds (--min-time), at most kMaxRunsPerRepetition per
/// repetition: a stall of a shared machine can hit most of five runs of a
/// set that traces in a few milliseconds (docs/lab/2026-12-05-bench-full-runs.md).
constexpr int kMaxRunsPerRepetition = 20;
template <typename Fn>
std::vector<double> timeRuns(int repetitions, double minSeconds, Fn&& fn) {
  std::vector<double> seconds;
  double total = 0.0;
  for (int r = 0; r < repetitions || (total < minSeconds && r < kMaxRunsPerRepetition * repetitions); ++r) {
    auto start = Clock::now();
    fn();
    seconds.push_back(secondsSince(start));
    total += seconds.back();
  }
  return seconds;
}

/// Trace one ray set with wavetrace (and Embree): warm-up, then the median
/// of the repetitions. Returns wavetrace's closest hits (empty for shadow rays).
std::vector<RayHit> benchSet(const Scene& scene, const PrimitiveRows& rows, Tracer& tracer, const Reference* embree, const std::string& name,
                             const std::vector<Ray>& rays, bool occlusion, bool coherent,
                             const BenchOptions& options, SetResult& result) {
  result.name = name;
  result.occlusion = occlusion;
  result.rays = rays.size();
  const RayBatchStats stats = measureRays(rays, std::size_t(tracer.packetWidth()));
  result.coherence = packetCoherence(rays, std::size_t(tracer.packetWidth()));
  result.octantShare = stats.octantShare;
  result.originSpread = stats.originSpread / tracer.primitiveScale();
  const Traversal traversal = result.traversal = setTraversal(options, tracer, stats, occlusion);
  if (rays.empty()) return {};
  std::vector<RayHit> hits;
  std::vector<std::uint8_t> blocked;
  std::vector<double> kernel;
  std::vector<double> wall;
  // warm-up (and the first launch's compile), then timed runs
  if (occlusion) {
    blocked = tracer.traceOccluded(rays, traversal);
    wall = timeRuns(options.repetitions, options.minSeconds, [&] {
      tracer.traceOccluded(rays, traversal);
      kernel.push_back(tracer.lastKernelSeconds());
    });
  } else {
    hits = tracer.traceClosest(rays, traversal);
    wall = timeRuns(options.repetitions, options.minSeconds, [&] {
      tracer.traceClosest(rays, traversal);
      kernel.push_back(tracer.lastKernelSeconds());
    });
  }
  result.wallSeconds = median(wall);
  result.kernelSeconds = median(kernel);
  std::size_t hitCount = 0;
  for (std::size_t i = 0; i < rays.size(); ++i)
    hitCount += occlusion ? blocked[i] != 0 : hits[i].prim != RayHit::kNoHit;
  result.hitFraction = double(hitCount) / rays.size();
  if (!embree) return hits;

  result.embree = true;
  std::vector<RayHit> refHits;
  std::vector<std::uint8_t> refBlocked;
  // every API in turn (a warm-up, which gives the answers, then the timed
  // runs); the fastest median is the one compared
  for (const std::string& api : embree->apis) {
    embree->setApi(api);
    std::vector<std::uint8_t> blockedBy;
    std::vector<RayHit> hitsBy;
    double seconds = 0.0;
    // timed as wavetrace's kernels are: the tracing alone, not the rays put
    // in Embree's layout or the answers read out
    std::vector<double> traces, calls;
    if (occlusion) {
      blockedBy = embree->occluded(rays, coherent);
      calls = timeRuns(options.repetitions, options.minSeconds, [&] {
        embree->occluded(rays, coherent);
        traces.push_back(embree->lastTraceSeconds());
      });
    } else {
      hitsBy = embree->closest(rays, coherent);
      calls = timeRuns(options.repetitions, options.minSeconds, [&] {
        embree->closest(rays, coherent);
        traces.push_back(embree->lastTraceSeconds());
      });
    }
    seconds = median(traces);
    if (!result.embreeApi.empty() && seconds >= result.embreeSeconds) continue;
    result.embreeSeconds = seconds;
    result.embreeWallSeconds = median(calls);
    result.embreeApi = api;
    refBlocked = std::move(blockedBy);
    refHits = std::move(hitsBy);
  }

  // agreement: closest hits by triangle; occlusion by flag, classified
  // through both tracers' closest hits on the rays that differ
  Agreement& agreement = result.agreement;
  std::size_t refCount = 0;
  if (occlusion) {
    std::vector<Ray> differ;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      refCount += refBlocked[i] != 0;
      if ((blocked[i] != 0) != (refBlocked[i] != 0)) differ.push_back(rays[i]);
    }
    if (!differ.empty()) {
      std::vector<RayHit> a = tracer.traceClosest(differ), b = embree->closest(differ, false);
      for (std::size_t i = 0; i < differ.size(); ++i) {
        Disagreement why = a[i].prim == b[i].prim ? Disagreement::kInconsistent
                                                          : classify(scene, rows, differ[i], a[i], b[i]);
        ++agreement.byClass[std::size_t(why)];
      }
    }
    agreement.disagreements = differ.size();
  } else {
    for (std::size_t i = 0; i < rays.size(); ++i) {
      refCount += refHits[i].prim != RayHit::kNoHit;
      if (hits[i].prim == refHits[i].prim) continue;
      ++agreement.disagreements;
      ++agreement.byClass[std::size_t(classify(scene, rows, rays[i], hits[i], refHits[i]))];
    }
  }
  result.embreeHitFraction = double(refCount) / rays.size();
  return hits;
}

BvhBuildOptions benchBvhOptions(BvhBuilder builder, const BenchOptions& options) {
  BvhBuildOptions bvhOptions;
  bvhOptions.builder = builder;
  bvhOptions.plocRadius = options.plocRadius;
  bvhOptions.maxLeafSize = options.maxLeafSize;
  bvhOptions.plocTopPrims = options.plocTopPrims;
  bvhOptions.instancing = *parseInstancing(options.instancing);
  return bvhOptions;
}

/// The tree over `bounds` and the median wall time of `repetitions` builds
/// after one warm-up.
std::pair<Bvh, double> timedBuild(std::span<const Aabb> bounds, std::span<const BvhInstance> instances,
                                  const BvhBuildOptions& bvhOptions, int repetitions) {
  std::vector<double> builds;
  Bvh bvh;
  for (int r = 0; r < repetitions + 1; ++r) {
    bvh = buildBvh(bounds, bvhOptions, instances);
    if (r > 0) builds.push_back(bvh.stats.buildSeconds);
  }
  return {std::move(bvh), median(builds)};
}

/// The row an --ab-* row is compared with: the same builder's tree traced
/// without the change; null for any other row.
const TreeResult* abBaseline(const std::vector<TreeResult>& trees, const TreeResult& tree) {
  if (!tree.ab()) return nullptr;
  for (const TreeResult& t : trees)
    if (t.builder == tree.builder && !t.ab()) return &t;
  return nullptr;
}

/// Build each --compare-bvh tree (median of the repetitions), then trace
/// the same ray sets through all of them, the trees taking turns within each
/// repetition so that a change in the machine's load hits them alike.
void compareTrees(Context& context, const Scene& scene, std::span<const Aabb> bounds,
                  std::span<const BvhInstance> instances, Tracer& defaultTracer,
                  BvhBuilder defaultBuilder, std::array<const std::vector<Ray>*, 3> sets,
                  std::array<Traversal, 3> traversals, const BenchOptions& options, std::vector<TreeResult>& trees) {
  std::vector<std::unique_ptr<Tracer>> owned;
  std::vector<Tracer*> tracers;
  std::vector<std::string> names = options.compareBvh;
  // an --ab-* row is compared with the same tree traced without the change
  const bool ab = !options.abKernelDir.empty() || options.abPacketWidth != 0 || !options.abTraversal.empty();
  if (ab &&
      std::find(names.begin(), names.end(), std::string(bvhBuilderName(defaultBuilder))) == names.end())
    names.insert(names.begin(), bvhBuilderName(defaultBuilder));
  for (const std::string& name : names) {
    if (name == "none") continue;
    // no triangles: no tree to compare, only the --ab-* baseline (the scene's tracer)
    if (bounds.empty() && name != bvhBuilderName(defaultBuilder)) continue;
    TreeResult tree;
    tree.builder = *parseBvhBuilder(name);
    BvhBuildOptions bvhOptions = benchBvhOptions(tree.builder, options);
    if (!bounds.empty()) {
      auto [bvh, seconds] =
          timedBuild(bounds, instances, binaryBuildOptions(bvhOptions, bounds.size()), options.repetitions);
      tree.buildSeconds = seconds;
      tree.nodes = bvh.stats.nodeCount;
      tree.sah = bvh.stats.sahCost;
      Bvh4 bvh4 = collapseToBvh4(bvh, bvh4Options(bvhOptions));
      tree.nodes4 = bvh4.stats.nodeCount;
      tree.sah4 = bvh4.stats.sahCost;
    }
    if (tree.builder == defaultBuilder) {
      tracers.push_back(&defaultTracer);
    } else {
      owned.push_back(std::make_unique<Tracer>(context, scene, bvhOptions, defaultTracer.packetWidth()));
      tracers.push_back(owned.back().get());
    }
    tree.bytesPerTriangle = scene.triangles.empty() ? 0.0
                                                    : double(tracers.back()->sceneBuffers().triangleBytes()) /
                                                          scene.triangles.size();
    trees.push_back(tree);
  }
  if (ab) {
    // the --bvh tree once more, traced by the kernels from that folder, in
    // packets of that width; a row per --ab-traversal, all on one tracer
    const std::optional<std::filesystem::path> before = kernelDirectory();
    if (!options.abKernelDir.empty()) setKernelDirectory(std::filesystem::path(options.abKernelDir));
    try {
      owned.push_back(std::make_unique<Tracer>(context, scene, benchBvhOptions(defaultBuilder, options),
                                               options.abPacketWidth ? options.abPacketWidth
                                                                     : defaultTracer.packetWidth()));
    } catch (...) {
      setKernelDirectory(before);
      throw;
    }
    setKernelDirectory(before);
    std::vector<std::string> rows = options.abTraversal;
    if (rows.empty()) rows.emplace_back();
    for (const std::string& traversal : rows) {
      TreeResult tree;
      tree.builder = defaultBuilder;
      tree.kernelDir = options.abKernelDir;
      tree.packetWidth = options.abPacketWidth;
      tree.traversal = traversal;
      tracers.push_back(owned.back().get());
      tree.nodes4 = tracers.back()->sceneBuffers().nodeCount;
      tree.bytesPerTriangle =
          defaultTracer.sceneBuffers().triangleBytes() / std::max<double>(1.0, scene.triangles.size());
      trees.push_back(tree);
    }
  }
  for (std::size_t set = 0; set < sets.size(); ++set) {
    const std::vector<Ray>& rays = *sets[set];
    const bool occlusion = set == 2;
    std::vector<std::vector<double>> kernel(tracers.size());
    // as benchSet chose for that set, but on an --ab-traversal row
    std::vector<Traversal> traversal(tracers.size(), traversals[set]);
    for (std::size_t t = 0; t < tracers.size(); ++t)
      if (!trees[t].traversal.empty()) {
        BenchOptions forced = options;
        forced.traversal = trees[t].traversal;
        traversal[t] = setTraversal(forced, *tracers[t], RayBatchStats{}, occlusion);
      }
    for (std::size_t t = 0; t < tracers.size(); ++t) {
      // warm-up, and the answers
      std::size_t hits = 0;
      if (occlusion) {
        for (std::uint8_t b : tracers[t]->traceOccluded(rays, traversal[t])) hits += b != 0;
      } else {
        for (const RayHit& h : tracers[t]->traceClosest(rays, traversal[t])) hits += h.prim != RayHit::kNoHit;
      }
      trees[t].hitFraction.push_back(rays.empty() ? 0.0 : double(hits) / rays.size());
    }
    for (int r = 0; r < options.repetitions; ++r)
      for (std::size_t t = 0; t < tracers.size(); ++t) {
        if (occlusion)
          tracers[t]->traceOccluded(rays, traversal[t]);
        else
          tracers[t]->traceClosest(rays, traversal[t]);
        kernel[t].push_back(tracers[t]->lastKernelSeconds());
      }
    for (std::size_t t = 0; t < tracers.size(); ++t) trees[t].kernelSeconds.push_back(median(kernel[t]));
  }
}

SceneResult benchScene(Context& context, const std::string& name, const Scene& scene,
                       const BenchOptions& options) {
  SceneResult result;
  result.name = name;
  result.triangles = scene.triangles.size();

  // BVH build, median of several
  std::vector<Aabb> bounds(scene.triangles.size());
  for (std::size_t i = 0; i < bounds.size(); ++i) bounds[i] = scene.triangleBounds(std::uint32_t(i));
  // The scene's placed copies, for --bvh auto. The bench keeps every triangle in
  // its build (degenerate ones too), so the BVH's input is the scene's triangles.
  std::vector<std::uint32_t> allTriangles(scene.triangles.size());
  for (std::size_t i = 0; i < allTriangles.size(); ++i) allTriangles[i] = std::uint32_t(i);
  const std::vector<BvhInstance> instances = bvhInstances(scene, allTriangles);
  BvhBuildOptions bvhOptions = benchBvhOptions(*parseBvhBuilder(options.bvh), options);
  // the other geometry types' tree, built as the renderer builds it
  const auto gatherStart = Clock::now();
  const PrimitiveRows rows = gatherPrimitives(scene);
  result.primitiveGatherSeconds = std::chrono::duration<double>(Clock::now() - gatherStart).count();
  std::size_t otherPrimitives = 0;
  for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type) {
    result.primitives[type] = type == WT_PRIM_TRIANGLE ? scene.triangles.size() : rows.count[type];
    if (type != WT_PRIM_TRIANGLE) otherPrimitives += rows.count[type];
  }
  if (otherPrimitives > 0) {
    std::vector<double> builds;
    for (int r = 0; r < options.repetitions + 1; ++r) {
      const double seconds = buildPrimitiveTree(rows, bvhOptions).seconds;
      if (r > 0) builds.push_back(seconds);
    }
    result.primitiveBuildSeconds = median(builds);
  }
  auto [bvh, seconds] =
      timedBuild(bounds, instances, binaryBuildOptions(bvhOptions, bounds.size()), options.repetitions);
  result.buildSeconds = seconds;
  result.nodes = bvh.stats.nodeCount;
  result.sah = bvh.stats.sahCost;
  result.copiesPlaced = bvh.stats.copiesPlaced;
  result.flatRegions = bvh.stats.flatRegions;
  // the collapse and the leaves' layout in blocks as the build: median of
  // the repetitions after a warm-up
  Bvh4 bvh4;
  std::vector<double> collapses;
  for (int r = 0; r < options.repetitions + 1; ++r) {
    const auto start = Clock::now();
    bvh4 = collapseToBvh4(bvh, bvh4Options(bvhOptions));
    packLeavesIntoBlocks(bvh4, bvh.primIndices.size());
    orderChildSlots(bvh4);
    if (r > 0) collapses.push_back(std::chrono::duration<double>(Clock::now() - start).count());
  }
  result.nodes4 = bvh4.stats.nodeCount;
  result.sah4 = bvh4.stats.sahCost;
  result.collapseSeconds = median(collapses);
  bvh = {};
  bvh4 = {};

  // packets of 16 only on scenes of few enough triangles (as the renderer)
  result.packetWidth = packetWidthFor(context.info(), options.packetWidth, scene.triangles.size());
  Tracer tracer(context, scene, bvhOptions, result.packetWidth);
  result.streamPrefetch = tracer.streamPrefetch();
  result.bytesPerTriangle =
      scene.triangles.empty() ? 0.0 : double(tracer.sceneBuffers().triangleBytes()) / scene.triangles.size();
  result.instances = tracer.sceneBuffers().instanceCount();
  result.leafMisfits = tracer.sceneBuffers().leafMisfits();
  std::size_t others = 0;
  for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type)
    if (type != WT_PRIM_TRIANGLE) others += tracer.sceneBuffers().primitiveCount(type);
  result.bytesPerPrimitive = others ? double(tracer.sceneBuffers().primitiveBytes) / double(others) : 0.0;
  std::unique_ptr<Reference> embree;
#ifdef WT_HAVE_EMBREE
  // Embree has no SDF grid: a scene with one is not compared
  if (!scene.sdfGrids.empty()) log::info("bench: " + name + ": Embree has no SDF grid primitive; not compared");
  else if (!scene.displacedMeshes.empty())
    log::info("bench: " + name + ": Embree's displaced meshes tessellate; not compared (--tessellate gives that row)");
  else {
  EmbreeOptions embreeOptions;
  const bool fastest = options.embreeApi == "fastest";
  if (!fastest) embreeOptions.api = parseEmbreeApi(options.embreeApi);
  embreeOptions.quality = options.embreeQuality;
  embreeOptions.robust = options.embreeRobust;
  auto reference = std::make_shared<EmbreeReference>(scene, embreeOptions);
  result.embreeBuildSeconds = reference->buildSeconds();
  embree = std::make_unique<Reference>();
  embree->closest = [reference](std::span<const Ray> rays, bool coherent) {
    return reference->traceClosest(rays, coherent);
  };
  embree->occluded = [reference](std::span<const Ray> rays, bool coherent) {
    return reference->traceOccluded(rays, coherent);
  };
  if (fastest)
    for (EmbreeApi api : kEmbreeApis) embree->apis.push_back(embreeApiName(api));
  else
    embree->apis.push_back(options.embreeApi);
  embree->setApi = [reference](const std::string& api) { reference->setApi(parseEmbreeApi(api)); };
  embree->lastTraceSeconds = [reference] { return reference->lastTraceSeconds(); };
  }
#endif

  // the three ray sets, made once from the camera rays' hits
  std::vector<Ray> primary = primaryRays(scene, options.primaryWidth);
  result.sets.resize(3);
  std::vector<RayHit> primaryHits = benchSet(scene, rows, tracer, embree.get(), "primary", primary, false, true,
                                             options, result.sets[0]);
  std::vector<Ray> diffuse = diffuseRays(scene, rows, primary, primaryHits);
  std::vector<Ray> shadow = shadowRays(scene, rows, primary, primaryHits, &result.shadowToEmitters);
  benchSet(scene, rows, tracer, embree.get(), "diffuse", diffuse, false, false, options, result.sets[1]);
  benchSet(scene, rows, tracer, embree.get(), "shadow", shadow, true, false, options, result.sets[2]);
  embree.reset();
  // the tree comparison is the triangle builders'; a scene without triangles has only the --ab-* rows
  const bool abRows = !options.abKernelDir.empty() || options.abPacketWidth != 0 || !options.abTraversal.empty();
  if (!scene.triangles.empty() || abRows)
    compareTrees(context, scene, bounds, instances, tracer, bvhOptions.builder, {&primary, &diffuse, &shadow},
               {result.sets[0].traversal, result.sets[1].traversal, result.sets[2].traversal}, options, result.trees);
  primary = {};
  diffuse = {};
  shadow = {};

  // whole paths: the wavefront renderer, rays of every bounce
  RenderSettings settings;
  settings.width = settings.height = options.pathWidth;
  settings.samplesPerPixel = options.pathSamples;
  settings.bvhBuilder = bvhOptions.builder;
  settings.instancing = bvhOptions.instancing;
  settings.packetWidth = options.packetWidth;
  Renderer renderer(context, scene, settings);
  std::optional<Renderer> general;
  if (options.compareProgram == "general") {
    RenderSettings generalSettings = settings;
    generalSettings.generalProgram = true;
    general.emplace(context, scene, generalSettings);
    result.programSecondsGeneral = general->stats().programSeconds;
  }
  result.programSeconds = renderer.stats().programSeconds;
  renderer.renderSample();  // warm-up
  if (general) general->renderSample();
  std::uint64_t raysBefore = renderer.stats().raysTraced;
  double secondsBefore = renderer.stats().seconds, generalBefore = general ? general->stats().seconds : 0.0;
  // interleaved, so that both programs see the same machine load; on for
  // twice --min-time at least (a second by default; 0: exactly --path-spp),
  // since a few samples of a small scene are milliseconds that one busy
  // moment of the machine can double
  const double pathMinSeconds = 2.0 * options.minSeconds;
  int samples = 0;
  while (samples < options.pathSamples ||
         (renderer.stats().seconds - secondsBefore < pathMinSeconds && samples < 64 * options.pathSamples)) {
    renderer.renderSample();
    if (general) general->renderSample();
    ++samples;
  }
  result.pathMrays = double(renderer.stats().raysTraced - raysBefore) /
                     (renderer.stats().seconds - secondsBefore) * 1e-6;
  result.pathMsPerSample = (renderer.stats().seconds - secondsBefore) / samples * 1e3;
  if (general) result.pathMsPerSampleGeneral = (general->stats().seconds - generalBefore) / samples * 1e3;
  return result;
}

// ---- scenes ------------------------------------------------------------------------

/// The asset folder: --assets, else ../shared/assets beside the source tree,
/// else ../shared/assets from the current directory; empty when none exists.
std::string findAssets(const std::string& option) {
  namespace fs = std::filesystem;
  if (!option.empty()) {
    if (!fs::is_directory(option)) throw std::invalid_argument("--assets " + option + ": no such folder");
    return option;
  }
  for (fs::path candidate : {wt::embedded::sourceDirectory() / ".." / "shared" / "assets", fs::path("..") / "shared" / "assets"})
    if (fs::is_directory(candidate)) return fs::weakly_canonical(candidate).string();
  return {};
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) continue;
    out += c;
  }
  return out + "\"";
}

double mrays(std::size_t rays, double seconds) { return seconds > 0.0 ? rays / seconds * 1e-6 : 0.0; }

}  // namespace

int runBench(const BenchOptions& options) {
  DeviceInfo device = selectDevice(options.device);
  Context context(device, /*profiling=*/true);
  const int packetWidth = packetWidthFor(device, options.packetWidth);
#ifdef WT_HAVE_EMBREE
  if (options.embreeApi != "fastest") parseEmbreeApi(options.embreeApi);  // a bad name fails before any work
#endif
  for (const std::string& name : options.compareBvh)
    if (name != "none" && !parseBvhBuilder(name)) throw std::invalid_argument("unknown BVH builder '" + name + "'");
  if (!parseBvhBuilder(options.bvh)) throw std::invalid_argument("unknown BVH builder '" + options.bvh + "'");

  // scenes: loaded one at a time, so a 1M-triangle scene is freed before the next
  struct SceneSource {
    std::string name, path;  ///< path empty: built in or generated
  };
  std::vector<SceneSource> sources;
  std::vector<std::pair<std::string, std::string>> skipped;  ///< name, reason
  if (options.scenes.empty()) {
    sources.push_back({"cornell (default)", ""});
    std::string assets = findAssets(options.assetsDir);
    for (const char* rel : {"gltf/MetalRoughSpheresNoTextures/glTF/MetalRoughSpheresNoTextures.gltf",
                            "gltf/DamagedHelmet/glTF/DamagedHelmet.gltf"}) {
      std::string stem = std::filesystem::path(rel).stem().string();
      if (assets.empty())
        skipped.emplace_back(stem, "no asset folder (../shared/assets absent; see --assets)");
      else if (!std::filesystem::exists(std::filesystem::path(assets) / rel))
        skipped.emplace_back(stem, "absent from " + assets);
      else
        sources.push_back({stem, (std::filesystem::path(assets) / rel).string()});
    }
    sources.push_back({"bumpy grid " + std::to_string(options.meshTriangles / 1000) + "k", "<grid>"});
    if (options.sphereCount > 0)
      sources.push_back({"sphere field " + std::to_string(options.sphereCount / 1000) + "k", "<spheres>"});
    if (options.hairGuides > 0)
      sources.push_back({"head of hair " + std::to_string(options.hairGuides) + "x101 strands", "<hair>"});
  } else {
    for (const std::string& path : options.scenes) {
      // gen:NAME, or gen:all for every one (generated_scenes.h)
      if (path == "gen:all") {
        for (const std::string& name : generatedSceneNames()) sources.push_back({"gen:" + name, "gen:" + name});
      } else {
        sources.push_back({path, path});
      }
    }
  }

  std::vector<SceneResult> results;
  for (const SceneSource& source : sources) {
    Scene scene;
    try {
      std::optional<Scene> generated;
      if (source.path.rfind("gen:", 0) == 0) {
        generated = makeGeneratedScene(std::string_view(source.path).substr(4), std::uint32_t(options.meshTriangles));
        if (!generated) throw std::invalid_argument("bench: no generated scene '" + source.path + "' (gen:all, gen:" +
                                                    [] {
                                                      std::string list;
                                                      for (const std::string& n : generatedSceneNames())
                                                        list += (list.empty() ? "" : ", gen:") + n;
                                                      return list;
                                                    }() + ")");
      }
      scene = generated                 ? std::move(*generated)
              : source.path.empty()       ? loadDefaultScene()
              : source.path == "<grid>"    ? makeBumpyGrid(std::uint32_t(options.meshTriangles))
              : source.path == "<spheres>" ? makeSphereField(std::uint32_t(options.sphereCount))
              : source.path == "<hair>"    ? makeHairScene(std::uint32_t(options.hairGuides), 100)
                                           : loadScene(source.path);
    } catch (const SceneError& e) {
      if (!options.scenes.empty()) throw;  // a scene the user named must load
      skipped.emplace_back(source.name, e.what());
      continue;
    }
    log::info("bench: " + source.name + " (" + std::to_string(scene.triangles.size()) + " triangles, " +
              std::to_string(scene.spheres.size()) + " spheres, " + std::to_string(scene.curves.size()) + " curves, " +
              std::to_string(scene.sdfGrids.size()) + " SDF grids, " + std::to_string(scene.displacedMeshes.size()) +
              " displaced meshes)");
    results.push_back(benchScene(context, source.name, scene, options));
    if (options.tessellate > 0 && !scene.displacedMeshes.empty()) {
      // the same meshes pre-tessellated, in the same run: the ratios compare like with like
      const auto start = Clock::now();
      const std::size_t made = tessellateDisplaced(scene, options.tessellate);
      const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
      log::info("bench: " + source.name + ": --tessellate " + std::to_string(options.tessellate) + " made " +
                std::to_string(made) + " triangles in " + std::to_string(seconds * 1e3) + " ms");
      results.push_back(benchScene(context, source.name + " tess" + std::to_string(options.tessellate), scene, options));
      results.back().tessellateSeconds = seconds;
    }
  }
  std::string embreeText = "Embree not found at build time; no comparison";
#ifdef WT_HAVE_EMBREE
  {
    EmbreeOptions o;
    o.fastestPerSet = options.embreeApi == "fastest";
    if (!o.fastestPerSet) o.api = parseEmbreeApi(options.embreeApi);
    o.quality = options.embreeQuality;
    o.robust = options.embreeRobust;
    embreeText = EmbreeReference(Scene{}, o).description();
  }
#endif

  if (options.json) {
    std::printf("{\"device\": %s, \"platform\": %s, \"embree\": %s, \"embree_available\": %s,\n",
                jsonString(device.name).c_str(), jsonString(device.platformName).c_str(),
                jsonString(embreeText).c_str(), kHaveEmbree ? "true" : "false");
    std::printf(" \"primary_width\": %d, \"repetitions\": %d, \"min_time_s\": %g, \"path_width\": %d, "
                "\"path_samples\": %d,\n",
                options.primaryWidth, options.repetitions, options.minSeconds, options.pathWidth,
                options.pathSamples);
    std::printf(" \"bvh\": \"%s\", \"ploc_radius\": %d, \"ploc_top_prims\": %d, \"traversal\": \"%s\", "
                "\"packet_width\": %d, \"max_leaf_size\": %d,\n",
                options.bvh.c_str(), options.plocRadius, options.plocTopPrims, options.traversal.c_str(),
                packetWidth, options.maxLeafSize);
    std::printf(" \"skipped\": [");
    for (std::size_t i = 0; i < skipped.size(); ++i)
      std::printf("%s{\"name\": %s, \"reason\": %s}", i ? ", " : "", jsonString(skipped[i].first).c_str(),
                  jsonString(skipped[i].second).c_str());
    std::printf("],\n \"scenes\": [\n");
    // the general program's figures: null where --compare-program none left it out
    const auto generalFigure = [&](double v) {
      char text[32] = "null";
      if (options.compareProgram == "general") std::snprintf(text, sizeof text, "%.3f", v);
      return std::string(text);
    };
    for (std::size_t i = 0; i < results.size(); ++i) {
      const SceneResult& r = results[i];
      std::printf("  {\"name\": %s, \"triangles\": %zu, \"bvh_build_s\": %.6f, \"bvh_mtris_per_s\": %.3f, "
                  "\"bvh_nodes\": %zu, \"bvh_sah\": %.3f, \"bvh4_nodes\": %zu, \"bvh4_sah\": %.3f, \"bvh4_collapse_s\": %.6f, "
                  "\"bvh4_mtris_per_s\": %.3f, \"bytes_per_triangle\": %.1f, \"instances\": %zu, \"leaf_misfits\": %zu, \"bvh_copies_placed\": %zu, "
                  "\"bvh_flat_regions\": %zu, \"packet_width\": %d, \"stream_prefetch\": %s, \"embree_build_s\": %.6f, "
                  "\"shadow_targets\": \"%s\", \"path_mrays\": %.3f, \"path_ms_per_sample\": %.3f, "
                  "\"path_ms_per_sample_general\": %s, \"program_build_s\": %.3f, \"program_build_general_s\": %s,\n",
                  jsonString(r.name).c_str(), r.triangles, r.buildSeconds,
                  r.buildSeconds > 0 ? r.triangles / r.buildSeconds * 1e-6 : 0.0, r.nodes, r.sah,
                  r.nodes4, r.sah4, r.collapseSeconds, traversableRate(r), r.bytesPerTriangle, r.instances, r.leafMisfits,
                  r.copiesPlaced, r.flatRegions, r.packetWidth, r.streamPrefetch ? "true" : "false", r.embreeBuildSeconds, r.shadowToEmitters ? "emitters" : "bounds", r.pathMrays,
                  r.pathMsPerSample, generalFigure(r.pathMsPerSampleGeneral).c_str(), r.programSeconds,
                  generalFigure(r.programSecondsGeneral).c_str());
      std::printf("   \"primitives\": {");
      for (std::uint32_t type = 0, n = 0; type < WT_PRIM_TYPES; ++type)
        if (*primTypeName(type)) std::printf("%s\"%s\": %zu", n++ ? ", " : "", primTypeName(type), r.primitives[type]);
      std::printf("}, \"primitive_gather_s\": %.6f", r.primitiveGatherSeconds);
      std::printf(", \"primitive_bvh_build_s\": %.6f, \"bytes_per_primitive\": %.1f, \"tessellate_s\": %.6f,\n",
                  r.primitiveBuildSeconds, r.bytesPerPrimitive, r.tessellateSeconds);
      std::printf("   \"bvh_builder\": \"%s\", \"trees\": [", options.bvh.c_str());
      const TreeResult* sahTree = nullptr;
      for (const TreeResult& t : r.trees)
        if (t.builder == BvhBuilder::Sah && !t.ab()) sahTree = &t;
      for (std::size_t t = 0; t < r.trees.size(); ++t) {
        const TreeResult& tree = r.trees[t];
        std::printf("%s\n    {\"builder\": \"%s\", \"build_s\": %.6f, \"mtris_per_s\": %.3f, \"nodes\": %zu, "
                    "\"sah\": %.3f, \"bvh4_nodes\": %zu, \"bvh4_sah\": %.3f, \"bytes_per_triangle\": %.1f, ",
                    t ? "," : "", bvhBuilderName(tree.builder), tree.buildSeconds,
                    tree.buildSeconds > 0 ? r.triangles / tree.buildSeconds * 1e-6 : 0.0, tree.nodes, tree.sah,
                    tree.nodes4, tree.sah4, tree.bytesPerTriangle);
        if (!tree.kernelDir.empty()) std::printf("\"kernel_dir\": %s, ", jsonString(tree.kernelDir).c_str());
        if (tree.packetWidth) std::printf("\"packet_width\": %d, ", tree.packetWidth);
        if (!tree.traversal.empty()) std::printf("\"traversal\": \"%s\", ", tree.traversal.c_str());
        std::printf("\"ray_sets\": [");
        const TreeResult* builtIn = abBaseline(r.trees, tree);
        for (std::size_t k = 0; k < tree.kernelSeconds.size(); ++k) {
          std::printf("%s{\"name\": \"%s\", \"kernel_s\": %.6f, \"mrays_kernel\": %.3f, \"hit_fraction\": %.6f",
                      k ? ", " : "", r.sets[k].name.c_str(), tree.kernelSeconds[k],
                      mrays(r.sets[k].rays, tree.kernelSeconds[k]), tree.hitFraction[k]);
          if (sahTree && tree.kernelSeconds[k] > 0 && !tree.ab())
            std::printf(", \"throughput_vs_sah\": %.4f", sahTree->kernelSeconds[k] / tree.kernelSeconds[k]);
          if (builtIn && tree.kernelSeconds[k] > 0)
            std::printf(", \"throughput_vs_baseline\": %.4f", builtIn->kernelSeconds[k] / tree.kernelSeconds[k]);
          std::printf("}");
        }
        std::printf("]}");
      }
      std::printf("],\n   \"ray_sets\": [\n");
      for (std::size_t k = 0; k < r.sets.size(); ++k) {
        const SetResult& s = r.sets[k];
        std::printf("    {\"name\": \"%s\", \"query\": \"%s\", \"rays\": %zu, \"hit_fraction\": %.6f, "
                    "\"traversal\": \"%s\", \"coherence\": %.4f, \"octant_share\": %.4f, \"origin_spread\": %.3f, \"wall_s\": %.6f, \"kernel_s\": %.6f, \"mrays_wall\": %.3f, \"mrays_kernel\": %.3f",
                    s.name.c_str(), s.occlusion ? "any_hit" : "closest_hit", s.rays, s.hitFraction,
                    traversalName(s.traversal), s.coherence, s.octantShare, s.originSpread, s.wallSeconds, s.kernelSeconds, mrays(s.rays, s.wallSeconds), mrays(s.rays, s.kernelSeconds));
        if (s.embree) {
          std::printf(", \"embree_api\": \"%s\", \"embree_s\": %.6f, \"embree_mrays\": %.3f, \"embree_wall_s\": %.6f, "
                      "\"embree_mrays_wall\": %.3f, \"embree_hit_fraction\": %.6f, "
                      "\"ratio_kernel\": %.4f, \"ratio_wall\": %.4f, \"agreement\": %.8f, \"disagreements\": %zu, "
                      "\"disagreements_explained\": %zu, \"disagreement_classes\": {",
                      s.embreeApi.c_str(), s.embreeSeconds, mrays(s.rays, s.embreeSeconds), s.embreeWallSeconds,
                      mrays(s.rays, s.embreeWallSeconds), s.embreeHitFraction,
                      s.kernelSeconds > 0 ? s.embreeSeconds / s.kernelSeconds : 0.0,
                      s.wallSeconds > 0 ? s.embreeWallSeconds / s.wallSeconds : 0.0,
                      s.rays ? 1.0 - double(s.agreement.disagreements) / s.rays : 1.0, s.agreement.disagreements,
                      s.agreement.explained());
          for (std::size_t c = 0; c < std::size_t(Disagreement::kCount); ++c)
            std::printf("%s\"%s\": %zu", c ? ", " : "", kDisagreementNames[c], s.agreement.byClass[c]);
          std::printf("}");
        }
        std::printf("}%s\n", k + 1 < r.sets.size() ? "," : "");
      }
      std::printf("  ]}%s\n", i + 1 < results.size() ? "," : "");
    }
    std::printf("]}\n");
    return 0;
  }

  char rule[96];
  std::snprintf(rule, sizeof rule, " (8 for a scene of more than %zu triangles)", kWidePacketMaxTriangles);
  const std::string widePacketRule = rule;
  std::printf("device: %s (%s); reference: %s; bvh: %s; instancing: %s; packets of %d rays%s\n", device.name.c_str(),
              device.platformName.c_str(), embreeText.c_str(), options.bvh.c_str(), options.instancing.c_str(), packetWidth,
              options.packetWidth == 0 && packetWidth == 16 ? widePacketRule.c_str() : "");
  std::printf("rays: primary %dx%d through pixel centres; diffuse and shadow rays from their hits; "
              "median of %d or more runs (%g s at least) after a warm-up\npaths: %dx%d, %d spp (%s), up to 8 bounces, "
              "extend rays counted\n",
              options.primaryWidth, options.primaryWidth, options.repetitions, options.minSeconds, options.pathWidth,
              options.pathWidth, options.pathSamples,
              options.minSeconds > 0 ? "more, for 2 x --min-time" : "exactly");
  for (const auto& [name, reason] : skipped) std::printf("skipped %s: %s\n", name.c_str(), reason.c_str());

  // nodes and SAH: the binary tree (--bvh), then the 4-wide tree collapsed from it (what the kernels traverse)
  // (collapse ms and the rate with it: the 4-wide tree is what the kernels need)
  std::printf("\n%-28s %10s %9s %8s %9s %7s %11s %8s %9s %7s %6s %10s %9s\n", "scene", "triangles", "build ms", "Mtris/s",
              "nodes", "SAH", "collapse ms", "Mtris/s", "nodes4", "SAH4", "B/tri", "Embree ms", "path Mr/s");
  for (const SceneResult& r : results) {
    char embreeMs[32] = "-";
    if (kHaveEmbree) std::snprintf(embreeMs, sizeof embreeMs, "%.2f", r.embreeBuildSeconds * 1e3);
    std::printf("%-28s %10zu %9.2f %8.2f %9zu %7.2f %11.2f %8.2f %9zu %7.2f %6.1f %10s %9.2f\n", r.name.c_str(),
                r.triangles, r.buildSeconds * 1e3, r.buildSeconds > 0 ? r.triangles / r.buildSeconds * 1e-6 : 0.0,
                r.nodes, r.sah, r.collapseSeconds * 1e3, traversableRate(r), r.nodes4, r.sah4, r.bytesPerTriangle,
                embreeMs, r.pathMrays);
  }

  // the scene's specialised program against the general one (every switch on), same samples
  if (options.compareProgram == "general") {
    std::printf("\n%-28s %14s %14s %8s %10s %10s\n", "scene", "special ms/spl", "general ms/spl", "speed-up",
                "build s", "general s");
    for (const SceneResult& r : results)
      std::printf("%-28s %14.2f %14.2f %8.3f %10.2f %10.2f\n", r.name.c_str(), r.pathMsPerSample,
                  r.pathMsPerSampleGeneral, r.pathMsPerSample > 0 ? r.pathMsPerSampleGeneral / r.pathMsPerSample : 0.0,
                  r.programSeconds, r.programSecondsGeneral);
  }

  // the other geometry types: their one BVH (leaves of typed ids), built and collapsed
  bool anyPrimitives = false;
  for (const SceneResult& r : results) anyPrimitives |= r.primitiveBuildSeconds > 0.0;
  if (anyPrimitives) {
    std::printf("\n%-28s %10s %10s %10s %10s %10s %9s %9s %9s %8s\n", "scene", "spheres", "curve segs", "SDF bricks",
                "displaced", "triangles", "gather ms", "build ms", "Mprims/s", "B/prim");
    for (const SceneResult& r : results) {
      if (!(r.primitiveBuildSeconds > 0.0)) continue;
      std::size_t others = 0;
      for (std::uint32_t type = 0; type < WT_PRIM_TYPES; ++type)
        if (type != WT_PRIM_TRIANGLE) others += r.primitives[type];
      std::printf("%-28s %10zu %10zu %10zu %10zu %10zu %9.2f %9.2f %9.2f %8.1f\n", r.name.c_str(),
                  r.primitives[WT_PRIM_SPHERE], r.primitives[WT_PRIM_CURVE], r.primitives[WT_PRIM_SDF_GRID],
                  r.primitives[WT_PRIM_DISPLACED], r.triangles,
                  r.primitiveGatherSeconds * 1e3, r.primitiveBuildSeconds * 1e3, double(others) / r.primitiveBuildSeconds * 1e-6, r.bytesPerPrimitive);
    }
  }

  // tree quality: each builder's tree on the same rays, throughput relative to the SAH tree's
  bool anyTrees = false;
  for (const SceneResult& r : results) anyTrees |= !r.trees.empty();
  if (anyTrees) {
    if (!options.abKernelDir.empty() || options.abPacketWidth || !options.abTraversal.empty()) {
      std::string what;
      if (!options.abKernelDir.empty()) what += "the kernels in " + options.abKernelDir;
      if (options.abPacketWidth) what += (what.empty() ? "" : ", ") + std::string("packets of ") + std::to_string(options.abPacketWidth);
      if (!options.abTraversal.empty()) what += (what.empty() ? "" : ", ") + std::string("a row per --ab-traversal, named after the *");
      std::printf("\n*: %s; (x) = throughput / the same tree's without", what.c_str());
    }
    std::printf("\ntree quality: kernel Mrays/s per builder on the same rays, interleaved; (x) = throughput / the sah "
                "tree's\n%-28s %-12s %9s %8s %9s %7s %9s %7s %6s %16s %16s %16s\n",
                "scene", "bvh", "build ms", "Mtris/s", "nodes", "SAH", "nodes4", "SAH4", "B/tri", "primary", "diffuse",
                "shadow");
    for (const SceneResult& r : results) {
      const TreeResult* sahTree = nullptr;
      for (const TreeResult& t : r.trees)
        if (t.builder == BvhBuilder::Sah && !t.ab()) sahTree = &t;
      for (const TreeResult& t : r.trees) {
        const TreeResult* reference = t.ab() ? abBaseline(r.trees, t) : sahTree;
        std::printf("%-28s %-12s %9.2f %8.2f %9zu %7.2f %9zu %7.2f %6.1f", r.name.c_str(),
                    (std::string(bvhBuilderName(t.builder)) + (t.ab() ? "* " + t.traversal : "")).c_str(),
                    t.buildSeconds * 1e3, t.buildSeconds > 0 ? r.triangles / t.buildSeconds * 1e-6 : 0.0, t.nodes,
                    t.sah, t.nodes4, t.sah4, t.bytesPerTriangle);
        for (std::size_t k = 0; k < t.kernelSeconds.size(); ++k) {
          char cell[32];
          if (reference && t.kernelSeconds[k] > 0)
            std::snprintf(cell, sizeof cell, "%.2f (%.3f)", mrays(r.sets[k].rays, t.kernelSeconds[k]),
                          reference->kernelSeconds[k] / t.kernelSeconds[k]);
          else
            std::snprintf(cell, sizeof cell, "%.2f", mrays(r.sets[k].rays, t.kernelSeconds[k]));
          std::printf(" %16s", cell);
        }
        std::printf("\n");
      }
    }
  }

  // Mrays/s; ratio = wavetrace kernel throughput / Embree throughput
  std::printf("\n%-28s %-8s %-8s %8s %6s %9s %9s %9s %-8s %7s %10s %s\n", "scene", "rays", "trav", "count", "hit %",
              "wt wall", "wt kernel", "Embree", "API", "ratio", "agree %", "disagreements (tie/edge/range/self/other)");
  for (const SceneResult& r : results)
    for (const SetResult& s : r.sets) {
      const std::string trav = s.traversal == Traversal::kPacket ? "packet" + std::to_string(r.packetWidth)
                                                                 : traversalName(s.traversal);
      std::printf("%-28s %-8s %-8s %8zu %6.1f %9.2f %9.2f", r.name.c_str(), s.name.c_str(), trav.c_str(),
                  s.rays, 100.0 * s.hitFraction,
                  mrays(s.rays, s.wallSeconds), mrays(s.rays, s.kernelSeconds));
      if (s.embree) {
        const Agreement& a = s.agreement;
        std::size_t other = a.disagreements - a.explained();
        std::printf(" %9.2f %-8s %7.3f %10.4f %zu (%zu/%zu/%zu/%zu/%zu)", mrays(s.rays, s.embreeSeconds),
                    s.embreeApi.c_str(), s.kernelSeconds > 0 ? s.embreeSeconds / s.kernelSeconds : 0.0,
                    s.rays ? 100.0 * (1.0 - double(a.disagreements) / s.rays) : 100.0, a.disagreements,
                    a.byClass[std::size_t(Disagreement::kTie)], a.byClass[std::size_t(Disagreement::kEdge)],
                    a.byClass[std::size_t(Disagreement::kRange)], a.byClass[std::size_t(Disagreement::kSelf)], other);
      }
      std::printf("\n");
    }
  return 0;
}

}  // namespace wt
