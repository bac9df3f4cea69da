// Stress rows that trace rays straight through the kernels' traversal
// (wt::Tracer): cracks between the triangles of closed meshes, and rays
// re-spawned from hits at grazing angles, for meshes of every size from 1e-4
// to 1e4 placed up to 1e4 of their own widths from the world origin.
#include "stress/stress.h"

#include "core/spawn.h"
#include "device/tracer.h"
#include "scene/generators.h"

#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

namespace wt {
namespace {

std::string format(const char* fmt, double v) { return stressFormat(fmt, v); }

glm::vec3 position(const Scene& scene, std::uint32_t v) {
  return glm::vec3(scene.positions[v].x, scene.positions[v].y, scene.positions[v].z);
}

/// Where a mesh is put: `size` its radius or half-width, its centre `offset`
/// sizes from the world origin along a fixed diagonal.
struct Placement {
  float size;
  float offset;
  glm::vec3 center() const { return offset * size * glm::normalize(glm::vec3(1.0f, -0.6f, 0.8f)); }
  std::string label() const { return "size " + format("%.0e", size) + ", " + format("%.0e", offset) + " sizes out"; }
};

std::vector<Placement> placements(bool quick) {
  std::vector<Placement> out;
  for (float size : quick ? std::vector<float>{1e-4f, 1e4f} : std::vector<float>{1e-4f, 1.0f, 1e4f})
    for (float offset : quick ? std::vector<float>{0.0f, 1e4f} : std::vector<float>{0.0f, 1e2f, 1e4f})
      out.push_back({size, offset});
  return out;
}

// ---------------------------------------------------------------------------
// cracks

}  // namespace

std::vector<glm::vec3> edgeTargets(const Scene& scene, int perEdge, std::uint32_t seed,
                                   const glm::vec3* visibleFrom) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  auto faces = [&](std::uint32_t v) {
    if (!visibleFrom) return true;
    glm::vec3 n(scene.normals[v].x, scene.normals[v].y, scene.normals[v].z);
    glm::vec3 to = *visibleFrom - position(scene, v);
    return glm::dot(n, to) > 0.3f * glm::length(to);
  };
  std::vector<glm::vec3> targets;
  std::set<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::uint32_t v = 0; v < scene.positions.size(); ++v)
    if (faces(v)) targets.push_back(position(scene, v));
  for (const WtTriangle& t : scene.triangles)
    for (auto [a, b] : {std::pair{t.v0, t.v1}, std::pair{t.v1, t.v2}, std::pair{t.v2, t.v0}})
      if (faces(a) && faces(b)) edges.insert(std::minmax(a, b));
  for (auto [a, b] : edges) {
    glm::vec3 pa = position(scene, a), pb = position(scene, b);
    targets.push_back(0.5f * (pa + pb));
    for (int k = 0; k < perEdge; ++k) {
      float s = u(rng);
      targets.push_back((1.0f - s) * pa + s * pb);
    }
  }
  return targets;
}


std::uint64_t countLeaks(Tracer& tracer, const std::vector<glm::vec3>& origins, const std::vector<glm::vec3>& targets,
                         std::uint64_t* rayCount) {
  std::vector<Ray> rays;
  rays.reserve(origins.size() * targets.size());
  for (const glm::vec3& o : origins)
    for (const glm::vec3& t : targets) {
      Ray r;
      r.origin = o;
      r.direction = glm::normalize(t - o);
      rays.push_back(r);
    }
  std::uint64_t leaks = 0;
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    for (const RayHit& h : tracer.traceClosest(rays, traversal)) leaks += h.triangle == RayHit::kNoHit;
    for (std::uint8_t o : tracer.traceOccluded(rays, traversal)) leaks += o == 0;
  }
  // streams answer any-hit queries only
  for (std::uint8_t o : tracer.traceOccluded(rays, Traversal::kStream)) leaks += o == 0;
  *rayCount += 5 * rays.size();
  return leaks;
}

std::vector<StressRow> stressCracks(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  const WtMaterial grey = makeMaterial(glm::vec3(0.5f));
  for (const char* meshName : {"icosphere", "box"}) {
    auto start = std::chrono::steady_clock::now();
    std::uint64_t leaks = 0, rays = 0;
    std::string worst;
    for (const Placement& at : placements(options.quick)) {
      glm::vec3 c = at.center();
      const bool sphere = meshName == std::string("icosphere");
      Scene scene = sphere ? makeIcosphere(options.quick ? 3 : 4, c, at.size, grey)
                           : makeBox(c - glm::vec3(at.size), c + glm::vec3(at.size), grey);
      Tracer tracer(context, scene);
      // from inside, at every shared vertex and edge
      std::vector<glm::vec3> inside = {c, c + at.size * glm::vec3(0.3f, -0.2f, 0.1f),
                                       c + at.size * glm::vec3(-0.45f, 0.5f, 0.2f)};
      if (options.quick) inside.resize(1);
      const int perEdge = sphere ? (options.quick ? 2 : 16) : (options.quick ? 32 : 512);
      std::uint64_t found = countLeaks(tracer, inside, edgeTargets(scene, perEdge, 7), &rays);
      // from outside, at edges between two faces turned towards the eye
      if (sphere) {
        glm::vec3 eye = c + 3.0f * at.size * glm::normalize(glm::vec3(0.3f, 0.5f, 0.8f));
        found += countLeaks(tracer, {eye}, edgeTargets(scene, perEdge, 8, &eye), &rays);
      } else {
        glm::vec3 eye = c + at.size * glm::vec3(3.0f, 2.0f, 2.5f);
        std::vector<glm::vec3> visible;
        for (const glm::vec3& t : edgeTargets(scene, perEdge, 9)) {
          glm::vec3 q = (t - c) / at.size;  // edges shared by two faces the eye sees
          if ((q.x > 0.99f) + (q.y > 0.99f) + (q.z > 0.99f) >= 2 && glm::all(glm::greaterThan(q, glm::vec3(-0.99f))))
            visible.push_back(t);
        }
        found += countLeaks(tracer, {eye}, visible, &rays);
      }
      if (found > 0 && worst.empty()) worst = "; first leaks at " + at.label();
      leaks += found;
    }
    StressRow row;
    row.group = "cracks";
    row.name = std::string(meshName) + " (closed, shared vertices), " + std::to_string(placements(options.quick).size()) +
               " placements: sizes 1e-4 to 1e4, up to 1e4 sizes from the origin";
    row.figure = std::to_string(leaks) + " leaks in " + std::to_string(rays) +
                 " rays at vertices and edges (closest and any hit, from inside and outside)" + worst;
    row.criterion = "0 leaks";
    row.pass = leaks == 0;
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------
// self-intersection

namespace {

enum class SelfCase {
  kPlane,         ///< axis-aligned grid: every triangle in one exact plane, so any hit is a self-hit
  kTiltedPlane,   ///< rotated grid: its float vertices leave the plane, only the triangle left is checked
  kSphereOutside, ///< convex icosphere left outwards: any hit is a self-hit
  kSphereInside,  ///< the same left inwards: hits across are real, only the triangle left is checked
  kBoxInside,     ///< a closed box left inwards near its (concave) edges, towards the adjacent face: every ray must hit, none the triangle left
};

struct SelfCount {
  std::uint64_t rays = 0, selfHits = 0, anyHits = 0, occluded = 0, skipped = 0;
  std::uint64_t leaks = 0;  ///< inside a closed mesh: rays that found nothing (closest or any hit)
  std::uint64_t nearRays = 0, nearLeaks = 0;  ///< the same from within kNearUlps of another face (not a failure)
};

/// Closer than this many float spacings (of the largest coordinate) to a
/// face, a point's own rounding error may put it on the face's far side: a
/// ray from there can leak whatever the tracer does.
constexpr double kNearUlps = 16.0;

/// Hit the mesh with rays from random origins, then re-spawn from every hit
/// (the renderer's ray_offset_origin, bit-identical on the host) at each
/// elevation above the triangle's plane, on the side the ray came from.
SelfCount selfIntersect(Context& context, SelfCase kind, const Placement& at, int hitsPerPlacement,
                        std::uint32_t seed) {
  const glm::vec3 c = at.center();
  const WtMaterial grey = makeMaterial(glm::vec3(0.5f));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), s(-1.0f, 1.0f);
  auto randomUnit = [&] {
    glm::vec3 d;
    do d = glm::vec3(s(rng), s(rng), s(rng));
    while (glm::dot(d, d) > 1.0f || glm::dot(d, d) < 1e-3f);
    return glm::normalize(d);
  };

  Scene scene;
  glm::vec3 axisU(1, 0, 0), axisV(0, 0, 1);
  if (kind == SelfCase::kTiltedPlane) {
    axisU = randomUnit();
    axisV = glm::normalize(glm::cross(axisU, randomUnit()));
  }
  const bool plane = kind == SelfCase::kPlane || kind == SelfCase::kTiltedPlane;
  const bool box = kind == SelfCase::kBoxInside;
  scene = plane ? makeGrid(32, c, at.size, axisU, axisV, grey)
          : box ? makeBox(c - glm::vec3(at.size), c + glm::vec3(at.size), grey)
                : makeIcosphere(3, c, at.size, grey);
  Tracer tracer(context, scene);
  const glm::vec3 planeNormal = glm::normalize(glm::cross(axisU, axisV));

  // first rays: at the surface from one side or the other (planes), from
  // outside (convex outwards) or from inside (inwards); grazing ones included
  std::vector<Ray> first(static_cast<std::size_t>(hitsPerPlacement));
  for (Ray& r : first) {
    glm::vec3 target, origin;
    if (plane) {
      target = c + at.size * (0.9f * s(rng) * axisU + 0.9f * s(rng) * axisV);
      float height = at.size * std::pow(10.0f, -3.0f + 3.3f * u(rng)) * (u(rng) < 0.5f ? 1.0f : -1.0f);
      origin = target + height * planeNormal + at.size * (s(rng) * axisU + s(rng) * axisV);
    } else if (kind == SelfCase::kSphereOutside) {
      target = c + at.size * randomUnit();
      origin = c + at.size * (1.5f + 2.0f * u(rng)) * randomUnit();
    } else if (box) {
      // a point on a face at 1e-6 to 1e-1 of the size from one of its edges
      int axis = int(u(rng) * 3.0f) % 3, edgeAxis = (axis + 1 + int(u(rng) * 2.0f) % 2) % 3;
      glm::vec3 q(s(rng), s(rng), s(rng));
      q[axis] = u(rng) < 0.5f ? -1.0f : 1.0f;
      q[edgeAxis] = (u(rng) < 0.5f ? -1.0f : 1.0f) * (1.0f - std::pow(10.0f, -6.0f + 5.0f * u(rng)));
      target = c + at.size * q;
      origin = c + 0.5f * at.size * glm::vec3(s(rng), s(rng), s(rng));
    } else {
      origin = c + 0.6f * at.size * u(rng) * randomUnit();
      target = c + at.size * randomUnit();
    }
    r.origin = origin;
    r.direction = glm::normalize(target - origin);
  }
  std::vector<RayHit> hits = tracer.traceClosest(first);

  const float elevations[] = {1e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.2f};
  std::vector<Ray> spawned;
  std::vector<std::uint32_t> from;
  SelfCount count;
  for (std::size_t i = 0; i < hits.size(); ++i) {
    const RayHit& h = hits[i];
    if (h.triangle == RayHit::kNoHit) continue;
    const WtTriangle& t = scene.triangles[h.triangle];
    glm::vec3 p0 = position(scene, t.v0), p1 = position(scene, t.v1), p2 = position(scene, t.v2);
    glm::vec3 error;
    glm::vec3 p = trianglePoint(p0, p1, p2, h.b1, h.b2, &error);
    glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    if (glm::dot(n, first[i].direction) > 0.0f) n = -n;  // the side the ray came from
    glm::vec3 origin = offsetRayOrigin(p, error, n);
    // the exact plane's normal, same orientation, to check each direction's side
    glm::dvec3 exact = glm::normalize(glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0)));
    if (glm::dot(exact, glm::dvec3(n)) < 0.0) exact = -exact;
    // in the box, towards the nearest edge of the face (the concave corner)
    glm::vec3 towardsEdge(0.0f);
    if (box) {
      glm::vec3 q = (p - c) / at.size;
      int faceAxis = 0;
      for (int a = 1; a < 3; ++a)
        if (std::abs(q[a]) > std::abs(q[faceAxis])) faceAxis = a;
      int nearest = -1;
      for (int a = 0; a < 3; ++a)
        if (a != faceAxis && (nearest < 0 || std::abs(q[a]) > std::abs(q[nearest]))) nearest = a;
      towardsEdge[nearest] = q[nearest] > 0.0f ? 1.0f : -1.0f;
    }
    for (float elevation : elevations) {
      glm::vec3 tangent = box ? glm::normalize(towardsEdge + 0.3f * glm::cross(n, randomUnit()))
                              : glm::normalize(glm::cross(n, randomUnit()));
      glm::vec3 d = glm::normalize(std::cos(elevation) * tangent + std::sin(elevation) * n);
      if (!(glm::dot(glm::dvec3(d), exact) > 0.0)) {  // rounding turned it below the surface
        ++count.skipped;
        continue;
      }
      Ray r;
      r.origin = origin;
      r.direction = d;
      r.skip = h.triangle;  // as the renderer's spawned rays skip the triangle they leave
      spawned.push_back(r);
      from.push_back(h.triangle);
    }
  }
  std::vector<RayHit> again = tracer.traceClosest(spawned);
  std::vector<std::uint8_t> occluded = tracer.traceOccluded(spawned);
  const bool anyHitIsSelf = kind == SelfCase::kPlane || kind == SelfCase::kSphereOutside;
  for (std::size_t i = 0; i < spawned.size(); ++i) {
    count.selfHits += again[i].triangle == from[i];
    count.anyHits += again[i].triangle != RayHit::kNoHit;
    count.occluded += occluded[i] != 0;
    if (box) {
      // the origin's distance to the nearest face other than the one left, in
      // float spacings of its largest coordinate
      glm::dvec3 o(spawned[i].origin), lo(c - glm::vec3(at.size)), hi(c + glm::vec3(at.size));
      glm::dvec3 q = (o - glm::dvec3(c)) / double(at.size);
      int face = 0;
      for (int a = 1; a < 3; ++a)
        if (std::abs(q[a]) > std::abs(q[face])) face = a;
      double nearest = INFINITY, largest = 0.0;
      for (int a = 0; a < 3; ++a) {
        largest = std::max(largest, std::abs(o[a]));
        if (a != face) nearest = std::min({nearest, o[a] - lo[a], hi[a] - o[a]});
      }
      std::uint64_t leaked = (again[i].triangle == RayHit::kNoHit) + (occluded[i] == 0);
      if (nearest < kNearUlps * largest * 1.1920929e-7) {
        ++count.nearRays;
        count.nearLeaks += leaked;
      } else {
        count.leaks += leaked;
      }
    }
  }
  if (!anyHitIsSelf) count.anyHits = count.occluded = 0;
  count.rays += spawned.size();
  return count;
}

}  // namespace

std::vector<StressRow> stressSelfIntersection(Context& context, const StressOptions& options) {
  struct Kind {
    SelfCase kind;
    const char* name;
    const char* criterion;
  };
  const Kind kinds[] = {
      {SelfCase::kPlane, "axis-aligned grid (one exact plane)", "0 hits of any kind, closest or any hit"},
      {SelfCase::kTiltedPlane, "tilted grid (float vertices off the ideal plane)", "0 hits on the triangle left"},
      {SelfCase::kSphereOutside, "icosphere, leaving outwards (convex)", "0 hits of any kind, closest or any hit"},
      {SelfCase::kSphereInside, "icosphere, leaving inwards", "0 hits on the triangle left"},
      {SelfCase::kBoxInside, "inside a closed box, leaving faces 1e-6 to 1e-1 from an edge towards the adjacent face",
       "0 hits on the triangle left, 0 leaks (every ray must hit) but from within 16 float spacings of the other face"},
  };
  const int hitsPerPlacement = options.quick ? 400 : 6000;
  std::vector<StressRow> rows;
  for (const Kind& k : kinds) {
    auto start = std::chrono::steady_clock::now();
    SelfCount total;
    std::string worst;
    std::uint32_t seed = 11;
    for (const Placement& at : placements(options.quick)) {
      SelfCount c = selfIntersect(context, k.kind, at, hitsPerPlacement, seed++);
      if ((c.selfHits || c.anyHits || c.occluded || c.leaks) && worst.empty()) worst = "; first at " + at.label();
      total.rays += c.rays, total.selfHits += c.selfHits, total.anyHits += c.anyHits;
      total.occluded += c.occluded, total.skipped += c.skipped, total.leaks += c.leaks;
      total.nearRays += c.nearRays, total.nearLeaks += c.nearLeaks;
    }
    StressRow row;
    row.group = "self-intersection";
    row.name = std::string(k.name) + ", elevations 1e-4 to 1.2 rad, " +
               std::to_string(placements(options.quick).size()) + " placements";
    row.figure = std::to_string(total.selfHits) + " hits on the triangle left, " + std::to_string(total.anyHits) +
                 " closest hits and " + std::to_string(total.occluded) + " any hits where none may be, " +
                 std::to_string(total.leaks) + " leaks, in " + std::to_string(total.rays) + " re-spawned rays" + worst;
    if (total.nearRays)
      row.figure += "; from within 16 float spacings of the other face: " + std::to_string(total.nearLeaks) +
                    " leaks (closest + any hit) in " + std::to_string(total.nearRays) + " rays";
    row.criterion = k.criterion;
    row.pass = total.selfHits == 0 && total.anyHits == 0 && total.occluded == 0 && total.leaks == 0 && total.rays > 0;
    row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    rows.push_back(row);
  }
  return rows;
}

}  // namespace wt
