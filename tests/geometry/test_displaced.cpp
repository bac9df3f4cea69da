// Displaced meshes (kernels/geometry/displaced.cl) against a long-double
// reference of the same micro-mesh on random rays (hit or miss, t, normal),
// on a displaced icosphere with a procedural map (no assets); every base
// triangle tested without the BVH, then through every traversal; any hit
// against closest hit; rays spawned from a hit; micro-vertices on shared
// edges bit for bit; rays aimed at the seams between base triangles'
// shells; zero displacement against the base mesh's triangles; the
// slab along each face normal against every micro-vertex and in the kernel.
#include "device/tracer.h"
#include "device_fixture.h"
#include "geometry/primitives.h"
#include "scene/generators.h"
#include "core/spawn.h"
#include "primitive_checks.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>

namespace wt {
namespace {

using Real = long double;
using RVec = glm::vec<3, Real>;

/// The test sphere: radius 1 at `center`, displaced by scale h + offset.
Scene testSphere(int level, float scale = 0.2f, float offset = -0.1f, glm::vec3 center = glm::vec3(0.3f, -0.2f, 0.1f),
                 int subdivisions = 1, std::uint32_t mapSize = 48) {
  return makeDisplacedSphere(subdivisions, center, 1.0f, mapSize, scale, offset, level, makeMaterial(glm::vec3(0.5f)));
}

Real mapAt(const DisplacedMesh& m, int x, int y) {
  const float v = m.map[std::size_t(y) * m.mapWidth + std::size_t(x)];
  return std::isnan(v) ? 0 : Real(v);
}

/// The map at uv, bilinear between texel centres, repeating, in long double.
Real sample(const DisplacedMesh& m, Real u, Real v) {
  const Real x = u * m.mapWidth - 0.5L, y = v * m.mapHeight - 0.5L;
  const Real fx0 = std::floor(x), fy0 = std::floor(y);
  const Real fx = x - fx0, fy = y - fy0;
  auto wrap = [](Real c, int size) { return int(c - size * std::floor(c / size)); };
  const int x0 = wrap(fx0, int(m.mapWidth)), y0 = wrap(fy0, int(m.mapHeight));
  const int x1 = (x0 + 1) % int(m.mapWidth), y1 = (y0 + 1) % int(m.mapHeight);
  return (mapAt(m, x0, y0) * (1 - fx) + mapAt(m, x1, y0) * fx) * (1 - fy) +
         (mapAt(m, x0, y1) * (1 - fx) + mapAt(m, x1, y1) * fx) * fy;
}

/// Micro-vertex (i, j) of base triangle `tri`, 2^L per edge, in long double.
RVec microVertex(const DisplacedMesh& m, const std::array<std::uint32_t, 3>& t, int n, int i, int j) {
  const Real w[3] = {Real(n - i - j) / n, Real(i) / n, Real(j) / n};
  RVec p(0), nrm(0);
  Real u = 0, v = 0;
  for (int k = 0; k < 3; ++k) {
    p += w[k] * RVec(m.positions[t[k]]);
    nrm += w[k] * RVec(m.normals[t[k]]);
    u += w[k] * Real(m.texcoords[t[k]].x);
    v += w[k] * Real(m.texcoords[t[k]].y);
  }
  return p + (Real(m.scale) * sample(m, u, v) + Real(m.offset)) * nrm;
}

struct MicroTriangle {
  RVec a, b, c;
};

/// Every micro-triangle of the mesh, wound as the base triangle.
std::vector<MicroTriangle> microMesh(const DisplacedMesh& m) {
  const int n = 1 << displacedLevel(m);
  std::vector<MicroTriangle> out;
  for (const auto& t : m.triangles)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i + j < n; ++i) {
        out.push_back({microVertex(m, t, n, i, j), microVertex(m, t, n, i + 1, j), microVertex(m, t, n, i, j + 1)});
        if (i + j + 2 <= n)
          out.push_back({microVertex(m, t, n, i + 1, j), microVertex(m, t, n, i + 1, j + 1), microVertex(m, t, n, i, j + 1)});
      }
  return out;
}

struct RefHit {
  bool hit = false;
  Real t = 0;
  glm::dvec3 normal{0.0};  ///< unit, the micro-triangle's winding side
  bool nearEdge = false;   ///< some micro-triangle's edge passes within kEdge (barycentric) of the ray in (tmin, tmax)
  Real cosine = 0;
};

constexpr Real kEdge = 2e-5L;

RefHit reference(const std::vector<MicroTriangle>& mesh, const Ray& ray) {
  const RVec o(ray.origin), d(ray.direction);
  RefHit r;
  Real best = ray.tmax;
  for (const MicroTriangle& m : mesh) {
    const RVec e1 = m.b - m.a, e2 = m.c - m.a;
    const RVec pv = glm::cross(d, e2);
    const Real det = glm::dot(e1, pv);
    if (det == 0) continue;
    const RVec tv = o - m.a;
    const Real u = glm::dot(tv, pv) / det;
    const RVec qv = glm::cross(tv, e1);
    const Real v = glm::dot(d, qv) / det;
    const Real t = glm::dot(e2, qv) / det;
    if (!(t > Real(ray.tmin) * (1 - 1e-6L) && t < Real(ray.tmax) * (1 + 1e-6L))) continue;
    const Real margin = std::min(std::min(u, v), 1 - u - v);
    if (std::abs(margin) < kEdge) r.nearEdge = true;
    if (margin < 0 || !(t > ray.tmin && t < best)) continue;
    best = t;
    r.hit = true;
    r.t = t;
    const RVec g = glm::cross(e1, e2);
    r.normal = glm::normalize(glm::dvec3(g));
    r.cosine = std::abs(glm::dot(glm::dvec3(glm::normalize(d)), r.normal));
  }
  return r;
}

/// Rays from around the sphere aimed into it, a fifth from inside, some with a short tmax.
std::vector<Ray> raysAtSphere(glm::vec3 center, std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::vector<Ray> rays(count);
  for (std::size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    const float reach = i % 5 == 0 ? 0.5f : 2.5f;
    r.origin = center + reach * glm::vec3(unit(rng), unit(rng), unit(rng));
    const glm::vec3 target = center + 1.05f * glm::vec3(unit(rng), unit(rng), unit(rng));
    r.direction = glm::normalize(target - r.origin);
    if (!(glm::dot(r.direction, r.direction) > 0.5f)) r.direction = glm::vec3(0, 1, 0);
    r.tmin = 0.0f;
    r.tmax = i % 4 == 1 ? 3.0f * u01(rng) : 1e30f;
  }
  return rays;
}

struct KernelHit {
  float t = -1.0f;
  glm::vec3 normal{0.0f}, error{0.0f}, shading{0.0f};
  std::uint32_t triangle = RayHit::kNoHit;
};

struct TypeRows {
  std::vector<WtVec4> data;
  std::vector<std::array<std::uint32_t, 4>> info;
  std::uint32_t count = 0;
};

/// The type's rows as gatherPrimitives lays them out, or with boxes stored to level maxDepth at most.
TypeRows typeRows(const Scene& scene, int maxDepth = -1) {
  PrimitiveRows rows;
  if (maxDepth < 0) rows = gatherPrimitives(scene);
  else gatherDisplacedTo(scene, rows, std::uint32_t(maxDepth));
  TypeRows t;
  t.count = std::uint32_t(rows.count[WT_PRIM_DISPLACED]);
  t.data.assign(rows.data.begin() + rows.dataFirst[WT_PRIM_DISPLACED], rows.data.end());
  t.info.assign(rows.info.begin() + rows.infoFirst[WT_PRIM_DISPLACED], rows.info.end());
  return t;
}

template <class V>
cl::Buffer input(const V& v) {
  return cl::Buffer(test::deviceContext().context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, v.size() * sizeof(v[0]),
                    const_cast<void*>(static_cast<const void*>(v.data())));
}

std::vector<KernelHit> kernelClosest(const Scene& scene, const std::vector<Ray>& rays, int maxDepth = -1) {
  const TypeRows rows = typeRows(scene, maxDepth);
  EXPECT_GT(rows.count, 0u);
  Context& ctx = test::deviceContext();
  std::vector<cl_float4> o(rays.size()), d(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    o[i] = {{rays[i].origin.x, rays[i].origin.y, rays[i].origin.z, rays[i].tmin}};
    d[i] = {{rays[i].direction.x, rays[i].direction.y, rays[i].direction.z, rays[i].tmax}};
  }
  cl::Buffer dataBuf = input(rows.data), infoBuf = input(rows.info), oBuf = input(o), dBuf = input(d);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 3 * rays.size() * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("displaced_tests.cl"), "test_displaced_closest");
  k.setArg(0, cl_uint(rays.size())), k.setArg(1, rows.count), k.setArg(2, dataBuf), k.setArg(3, infoBuf);
  k.setArg(4, oBuf), k.setArg(5, dBuf), k.setArg(6, out);
  ctx.launch("test_displaced_closest", k, rays.size());
  std::vector<cl_float4> got(3 * rays.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(cl_float4), got.data());
  std::vector<KernelHit> hits(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const cl_float4 a = got[3 * i], b = got[3 * i + 1], c = got[3 * i + 2];
    if (a.s[0] < 0.0f) continue;
    hits[i].t = a.s[0];
    hits[i].normal = glm::vec3(a.s[1], a.s[2], a.s[3]);
    hits[i].error = glm::vec3(b.s[0], b.s[1], b.s[2]);
    hits[i].shading = glm::vec3(c.s[0], c.s[1], c.s[2]);
    std::memcpy(&hits[i].triangle, &b.s[3], 4);
  }
  return hits;
}

/// Closest hits on `rays` against the long-double reference of every micro-triangle; returns how many the reference hits.
int expectKernelMatchesReferenceOn(const Scene& scene, const std::vector<Ray>& rays, int maxDepth = -1) {
  const DisplacedMesh& mesh = scene.displacedMeshes[0];
  const std::vector<MicroTriangle> micro = microMesh(mesh);
  const std::vector<KernelHit> got = kernelClosest(scene, rays, maxDepth);
  int bad = 0, hits = 0, ambiguous = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RefHit want = reference(micro, rays[i]);
    const bool hit = got[i].t >= 0.0f;
    hits += want.hit;
    std::string problem;
    if (hit != want.hit) {
      // a ray through an edge of the outline, or ending on the surface, may go either way
      if (want.nearEdge || (want.hit && want.t >= Real(rays[i].tmax) * (1 - 1e-5L))) {
        ++ambiguous;
        continue;
      }
      problem = hit ? "kernel hit, reference missed" : "kernel missed, reference hit";
    } else if (hit) {
      // float micro-vertices against long double: a few ulps of the coordinates, over the slant
      const Real dt = std::abs(Real(got[i].t) - want.t);
      const Real tol = 1e-5L / std::max(want.cosine, Real(1e-2)) + 1e-6L * want.t;
      if (dt > tol) problem = "t differs by " + std::to_string(double(dt));
      else if (!want.nearEdge && glm::length(glm::dvec3(got[i].normal) - want.normal) > 1e-3)
        problem = "normal differs by " + std::to_string(glm::length(glm::dvec3(got[i].normal) - want.normal));
    }
    if (!problem.empty() && ++bad <= 8)
      ADD_FAILURE() << "ray " << i << ": " << problem << " (kernel t " << got[i].t << ", reference "
                    << (want.hit ? std::to_string(double(want.t)) : "miss") << ")";
  }
  EXPECT_EQ(bad, 0);
  EXPECT_LT(ambiguous, int(rays.size() / 100) + 1);
  return hits;
}

/// Closest hits on random rays at the sphere against the long-double reference of every micro-triangle.
void expectKernelMatchesReference(const Scene& scene, std::uint32_t seed, int maxDepth = -1, std::size_t count = 3000) {
  const std::vector<Ray> rays = raysAtSphere(glm::vec3(0.3f, -0.2f, 0.1f), test::testSize(count, count / 10), seed);
  EXPECT_GT(expectKernelMatchesReferenceOn(scene, rays, maxDepth), int(rays.size() / 3));
}

TEST(DisplacedMeshes, KernelMatchesLongDoubleReference) {
  // level 3 over a 48^2 map: micro-edges span several texels
  expectKernelMatchesReference(testSphere(3), 21);
}

TEST(DisplacedMeshes, GrazingRaysMatchTheReference) {
  // rays skimming the shell: each passes nearest the centre at 0.85-1.12,
  // around the displaced surface (radius 1 moved by -0.06 to 0.09 over
  // flat faces), so they meet the bumps at a slant or just miss them
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  std::mt19937 rng(33);
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  std::vector<Ray> rays(test::testSize(1500, 150));
  for (Ray& r : rays) {
    const glm::vec3 a = glm::normalize(glm::vec3(gauss(rng), gauss(rng), gauss(rng)));
    glm::vec3 d = glm::vec3(gauss(rng), gauss(rng), gauss(rng));
    d = glm::normalize(d - glm::dot(d, a) * a);
    r.origin = center + (0.85f + 0.27f * u01(rng)) * a - 3.0f * d;
    r.direction = d;
    r.tmin = 0.0f;
    r.tmax = 1e30f;
  }
  const int hits = expectKernelMatchesReferenceOn(testSphere(3), rays);
  EXPECT_GT(hits, int(rays.size() / 10));
  EXPECT_LT(hits, int(rays.size() * 9 / 10));
}

TEST(DisplacedMeshes, LevelsBelowTheStoredBoxesMatchTheReference) {
  // boxes stored to level D < L - 1: the sub-triangles below D are walked
  // untested inside their level-D ancestor's box, which bounds them by the
  // map's range over their texels; D = 0 keeps the whole triangle's box only
  for (int depth : {1, 0}) {
    SCOPED_TRACE("stored depth " + std::to_string(depth));
    expectKernelMatchesReference(testSphere(3), 30 + std::uint32_t(depth), depth, 1500);
  }
}

/// The test sphere at level L with a map of a float per texel (every texel
/// its own value) and one of an 8-bit image's values (stored as bytes).
std::pair<Scene, Scene> floatAndByteSpheres(int level) {
  Scene floats = testSphere(level), bytes = floats;
  std::vector<float>& fine = floats.displacedMeshes[0].map;
  for (std::size_t i = 0; i < fine.size(); ++i) fine[i] += float(i) * 0x1p-20f;
  std::vector<float>& coarse = bytes.displacedMeshes[0].map;
  for (float& v : coarse) v = std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
  return {floats, bytes};
}

TEST(DisplacedMeshes, EightBitMapsAreStoredAsBytesAndDrawTheSameSurface) {
  // a map of at most 256 distinct values (an 8-bit image's) is stored as
  // a byte a texel and a palette of the values, a map of more as floats:
  // both draw the surface the reference samples from the values themselves
  auto [floats, bytes] = floatAndByteSpheres(3);
  const std::vector<float>& fine = floats.displacedMeshes[0].map;
  const std::vector<float>& coarse = bytes.displacedMeshes[0].map;
  std::vector<float> distinct(coarse);
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  ASSERT_GT(distinct.size(), 32u);  // a map with many values, not a handful
  // the texels' rows: a float each, or a byte each in 8 x 8 tiles after the palette
  const std::size_t texels = fine.size(), floatRows = typeRows(floats).data.size(), byteRows = typeRows(bytes).data.size();
  const std::size_t tiled = 64 * ((bytes.displacedMeshes[0].mapWidth + 7) / 8) * ((bytes.displacedMeshes[0].mapHeight + 7) / 8);
  EXPECT_EQ(floatRows - byteRows, (texels + 3) / 4 - (tiled + 4 * distinct.size() + 15) / 16);
  for (const Scene* scene : {&floats, &bytes}) {
    SCOPED_TRACE(scene == &floats ? "float texels" : "byte texels");
    expectKernelMatchesReference(*scene, 33, -1, 1500);
  }
}

TEST(DisplacedMeshes, StoredDisplacementsAreTheKernelsMapSamplesBitForBit) {
  // where the boxes are exact (L <= D + 1) the host stores d at every
  // micro-vertex and the walk reads no map: every micro-vertex of every
  // base triangle from the stored d is the one the kernel's own sample of
  // the map gives, bit for bit, for float and byte texels. Where the boxes
  // stop above L - 1 nothing is stored.
  auto [floats, bytes] = floatAndByteSpheres(4);
  for (const Scene* scene : {&floats, &bytes}) {
    SCOPED_TRACE(scene == &floats ? "float texels" : "byte texels");
    const TypeRows rows = typeRows(*scene);
    const int n = 1 << displacedLevel(scene->displacedMeshes[0]);
    std::vector<cl_uint4> queries;
    for (std::uint32_t t = 0; t < rows.count; ++t) {
      EXPECT_NE(rows.info[WT_DISP_INFO_ROWS * t][3], ~0u) << "base triangle " << t;
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i + j <= n; ++i)
          for (cl_uint fromMap : {0u, 1u}) queries.push_back({{t, cl_uint(i), cl_uint(j), fromMap}});
    }
    ASSERT_EQ(queries.size(), std::size_t(rows.count) * (n + 1) * (n + 2));
    Context& ctx = test::deviceContext();
    cl::Buffer dataBuf = input(rows.data), infoBuf = input(rows.info), qBuf = input(queries);
    cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, queries.size() * sizeof(cl_float4));
    cl::Kernel k(test::testProgram("displaced_tests.cl"), "test_displaced_vertex");
    k.setArg(0, cl_uint(queries.size())), k.setArg(1, dataBuf), k.setArg(2, infoBuf), k.setArg(3, qBuf),
        k.setArg(4, out);
    ctx.launch("test_displaced_vertex", k, queries.size());
    std::vector<cl_float4> got(queries.size());
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(cl_float4), got.data());
    int differ = 0;
    for (std::size_t q = 0; q < got.size(); q += 2)
      if (std::memcmp(got[q].s, got[q + 1].s, 3 * sizeof(float)) != 0 && ++differ <= 5)
        ADD_FAILURE() << "base triangle " << queries[q].s[0] << " vertex (" << queries[q].s[1] << ", "
                      << queries[q].s[2] << "): stored (" << got[q].s[0] << ", " << got[q].s[1] << ", " << got[q].s[2]
                      << ") against the map's (" << got[q + 1].s[0] << ", " << got[q + 1].s[1] << ", "
                      << got[q + 1].s[2] << ")";
    EXPECT_EQ(differ, 0);
  }
  const TypeRows shallow = typeRows(floats, 1);
  for (std::uint32_t t = 0; t < shallow.count; ++t)
    EXPECT_EQ(shallow.info[WT_DISP_INFO_ROWS * t][3], ~0u) << "base triangle " << t << " at D 1 < L - 1";
}

/// A base triangle's stored boxes decoded as shared/types.h lays them out
/// (WT_PRIM_DISPLACED), this file's own reading: per node in level order
/// (node k's children 4k + 1 .. 4k + 4) its box, level D the deepest.
struct DecodedBoxes {
  std::uint32_t level = 0, depth = 0;
  std::vector<glm::vec3> lo, hi;
  glm::vec3 slabNormal{0.0f};  ///< the slab's direction, and its heights lo <= dot(slabNormal, p) <= hi
  float slabLo = 0.0f, slabHi = 0.0f;
};

DecodedBoxes decodeBoxes(const TypeRows& rows, std::uint32_t triangle) {
  const std::array<std::uint32_t, 4> info = rows.info[WT_DISP_INFO_ROWS * triangle];
  DecodedBoxes out;
  std::memcpy(&out.level, &rows.data[info[1] + 1].x, 4);
  std::memcpy(&out.depth, &rows.data[info[1] + 1].y, 4);
  const WtVec4 lo = rows.data[info[2]], hi = rows.data[info[2] + 1];
  out.lo.push_back({lo.x, lo.y, lo.z});
  out.hi.push_back({hi.x, hi.y, hi.z});
  const WtVec4 slab = rows.data[info[2] - 1];
  out.slabNormal = {slab.x, slab.y, slab.z};
  out.slabLo = lo.w, out.slabHi = hi.w;
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(&rows.data[info[2] + 2]);
  std::size_t nodes = 0;
  for (std::uint32_t l = 0; l <= out.depth; ++l) nodes += std::size_t(1) << (2 * l);
  for (std::size_t child = 1; child < nodes; ++child) {
    const std::size_t parent = (child - 1) / 4, k = (child - 1) % 4;
    const std::uint8_t* block = bytes + 24 * parent;
    glm::vec3 clo, chi;
    for (int a = 0; a < 3; ++a) {
      const float plo = out.lo[parent][a], phi = out.hi[parent][a], step = (phi - plo) * (1.0f / 255.0f);
      clo[a] = plo + float(block[4 * a + k]) * step;
      chi[a] = phi - (255.0f - float(block[12 + 4 * a + k])) * step;
    }
    out.lo.push_back(clo);
    out.hi.push_back(chi);
  }
  return out;
}

/// Every micro-vertex of every base triangle as the kernel displaces it,
/// base triangle by base triangle, each lattice row j after row j - 1.
std::vector<glm::vec3> kernelVertices(const TypeRows& rows, int n) {
  std::vector<cl_uint4> queries;
  for (std::uint32_t b = 0; b < rows.count; ++b)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i + j <= n; ++i) queries.push_back({{b, cl_uint(i), cl_uint(j), 0}});
  Context& ctx = test::deviceContext();
  cl::Buffer dataBuf = input(rows.data), infoBuf = input(rows.info), qBuf = input(queries);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, queries.size() * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("displaced_tests.cl"), "test_displaced_vertex");
  k.setArg(0, cl_uint(queries.size())), k.setArg(1, dataBuf), k.setArg(2, infoBuf), k.setArg(3, qBuf), k.setArg(4, out);
  ctx.launch("test_displaced_vertex", k, queries.size());
  std::vector<cl_float4> got(queries.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(cl_float4), got.data());
  std::vector<glm::vec3> verts(got.size());
  for (std::size_t q = 0; q < got.size(); ++q) verts[q] = glm::vec3(got[q].s[0], got[q].s[1], got[q].s[2]);
  return verts;
}

TEST(DisplacedMeshes, BoxesBuildTheSameOnAnyThreadCount) {
  // 1280 base triangles (more than a chunk of the threaded build), one with
  // a non-finite corner among them (left out in its place); boxes stored to
  // the deepest level the micro-vertices bound exactly (D = L - 1) and
  // shallower (D = 2 < L - 1: the deepest from the map's range)
  Scene scene = testSphere(4, 0.2f, -0.1f, glm::vec3(0.3f, -0.2f, 0.1f), 3);
  DisplacedMesh& mesh = scene.displacedMeshes[0];
  ASSERT_GT(mesh.triangles.size(), 1024u);
  mesh.positions.push_back(glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f));
  mesh.normals.push_back(glm::vec3(0.0f, 1.0f, 0.0f));
  mesh.texcoords.push_back(glm::vec2(0.5f));
  mesh.triangles[700][1] = std::uint32_t(mesh.positions.size() - 1);
  for (std::uint32_t depth : {std::uint32_t(WT_DISP_MAX_DEPTH), 2u}) {
    PrimitiveRows one, many;
    gatherDisplacedTo(scene, one, depth, 1);
    gatherDisplacedTo(scene, many, depth, 5);
    EXPECT_EQ(one.skipped, 1u);
    EXPECT_EQ(many.skipped, one.skipped);
    EXPECT_EQ(many.ids, one.ids);
    EXPECT_EQ(many.info, one.info);
    ASSERT_EQ(many.data.size(), one.data.size());
    EXPECT_EQ(std::memcmp(many.data.data(), one.data.data(), one.data.size() * sizeof(WtVec4)), 0) << "depth " << depth;
    ASSERT_EQ(many.bounds.size(), one.bounds.size());
    EXPECT_EQ(std::memcmp(many.bounds.data(), one.bounds.data(), one.bounds.size() * sizeof(Aabb)), 0);
  }
}

TEST(DisplacedMeshes, StoredBoxesHoldEveryMicroTriangleAndStayTight) {
  // every stored box holds the micro-vertices (as the kernel displaces
  // them) of its sub-triangle, so the micro-triangles, flat between them;
  // and the deepest boxes are no wider than those vertices' own box by
  // more than the eight-bit step of their parent's box (the walk prunes)
  for (int depth : {-1, 1}) {
    SCOPED_TRACE("box depth " + std::to_string(depth));
    const Scene scene = testSphere(4, 0.3f, -0.15f);
    const TypeRows rows = typeRows(scene, depth);
    const int levelL = int(displacedLevel(scene.displacedMeshes[0])), n = 1 << levelL;
    // the kernel's micro-vertices, every lattice point of every base triangle
    const std::vector<glm::vec3> verts = kernelVertices(rows, n);
    const std::size_t perTriangle = std::size_t(n + 1) * std::size_t(n + 2) / 2;
    int outside = 0, loose = 0, leaves = 0;
    for (std::uint32_t b = 0; b < rows.count; ++b) {
      const DecodedBoxes boxes = decodeBoxes(rows, b);
      ASSERT_EQ(boxes.level, std::uint32_t(levelL));
      ASSERT_EQ(boxes.depth, depth < 0 ? std::uint32_t(levelL - 1) : std::uint32_t(depth));
      auto vertex = [&](int i, int j) {
        std::size_t at = b * perTriangle;
        for (int r = 0; r < j; ++r) at += std::size_t(n + 1 - r);
        return verts[at + std::size_t(i)];
      };
      // nodes in level order with their corners in the level-L lattice: child k of corners (A, B, C) takes
      // (A, AB, AC), (AB, B, BC), (AC, BC, C), (AB, AC, BC)
      std::vector<std::array<glm::ivec2, 3>> corners{{glm::ivec2(0, 0), glm::ivec2(n, 0), glm::ivec2(0, n)}};
      for (std::size_t node = 0; node < boxes.lo.size(); ++node) {
        const auto [A, B, C] = corners[node];
        const glm::ivec2 ab = (A + B) / 2, ac = (A + C) / 2, bc = (B + C) / 2;
        corners.push_back({A, ab, ac});
        corners.push_back({ab, B, bc});
        corners.push_back({ac, bc, C});
        corners.push_back({ab, ac, bc});
        // the lattice points of the sub-triangle: A + (a (B - A) + c (C - A)) / s
        const int s = std::max(std::abs(B.x - A.x), std::abs(B.y - A.y));
        glm::vec3 vlo(std::numeric_limits<float>::infinity()), vhi(-vlo.x);
        for (int c = 0; c <= s; ++c)
          for (int a = 0; a + c <= s; ++a) {
            const glm::ivec2 p = A + (a * (B - A) + c * (C - A)) / s;
            const glm::vec3 v = vertex(p.x, p.y);
            vlo = glm::min(vlo, v);
            vhi = glm::max(vhi, v);
          }
        if (glm::any(glm::lessThan(vlo, boxes.lo[node])) || glm::any(glm::greaterThan(vhi, boxes.hi[node])))
          if (++outside <= 5) ADD_FAILURE() << "triangle " << b << " node " << node << ": a micro-vertex outside its box";
        // tight where the deepest boxes come from the micro-vertices (level D the micro-triangles' parents)
        if (boxes.depth + 1 != boxes.level || node == 0 || node < boxes.lo.size() - (std::size_t(1) << (2 * boxes.depth)))
          continue;
        ++leaves;
        const std::size_t parent = (node - 1) / 4;
        const glm::vec3 step = (boxes.hi[parent] - boxes.lo[parent]) / 255.0f;
        const glm::vec3 pad = step + 1e-5f * (1.0f + glm::abs(vlo) + glm::abs(vhi));
        if (glm::any(glm::greaterThan(vlo - boxes.lo[node], pad)) || glm::any(glm::greaterThan(boxes.hi[node] - vhi, pad)))
          if (++loose <= 5) ADD_FAILURE() << "triangle " << b << " node " << node << ": box wider than its vertices need";
      }
    }
    EXPECT_EQ(outside, 0);
    EXPECT_EQ(loose, 0);
    if (depth < 0) {
      EXPECT_GT(leaves, 0);
    }
  }
}

TEST(DisplacedMeshes, StoredSlabsHoldEveryMicroVertexAndStayThin) {
  // each base triangle's slab (its unit face normal, and the least and the
  // largest height along it) holds every micro-vertex as the kernel
  // displaces it, so the flat micro-triangles between them; where the
  // micro-vertices are stored (L <= D + 1) it is no thicker than their own
  // heights and the host's rounding margin (2 (4e-6 |p|max + 1e-6 extent) a
  // side); deeper it comes from the map's range over each level-D sub-triangle
  for (int depth : {-1, 1}) {
    SCOPED_TRACE("box depth " + std::to_string(depth));
    const Scene scene = testSphere(4, 0.3f, -0.15f);
    const DisplacedMesh& mesh = scene.displacedMeshes[0];
    const TypeRows rows = typeRows(scene, depth);
    const int n = 1 << displacedLevel(mesh);
    const std::vector<glm::vec3> verts = kernelVertices(rows, n);
    const std::size_t perTriangle = std::size_t(n + 1) * std::size_t(n + 2) / 2;
    int outside = 0, thick = 0, tilted = 0;
    for (std::uint32_t b = 0; b < rows.count; ++b) {
      const DecodedBoxes boxes = decodeBoxes(rows, b);
      const std::array<std::uint32_t, 3>& t = mesh.triangles[b];
      const glm::dvec3 nrm(boxes.slabNormal);
      const glm::dvec3 e1 = glm::dvec3(mesh.positions[t[1]] - mesh.positions[t[0]]);
      const glm::dvec3 e2 = glm::dvec3(mesh.positions[t[2]] - mesh.positions[t[0]]);
      // the face normal: unit, across both base edges
      if ((std::abs(glm::length(nrm) - 1.0) > 1e-6 || std::abs(glm::dot(nrm, e1)) > 1e-6 * glm::length(e1) ||
           std::abs(glm::dot(nrm, e2)) > 1e-6 * glm::length(e2)) &&
          ++tilted <= 5)
        ADD_FAILURE() << "triangle " << b << ": the slab's direction is not the unit face normal";
      Real lo = std::numeric_limits<Real>::infinity(), hi = -lo;
      glm::vec3 vlo(std::numeric_limits<float>::infinity()), vhi(-vlo.x);
      for (std::size_t v = 0; v < perTriangle; ++v) {
        const glm::vec3 p = verts[b * perTriangle + v];
        const Real h = Real(nrm.x) * p.x + Real(nrm.y) * p.y + Real(nrm.z) * p.z;
        lo = std::min(lo, h), hi = std::max(hi, h);
        vlo = glm::min(vlo, p), vhi = glm::max(vhi, p);
      }
      if ((lo < Real(boxes.slabLo) || hi > Real(boxes.slabHi)) && ++outside <= 5)
        ADD_FAILURE() << "triangle " << b << ": heights [" << double(lo) << ", " << double(hi) << "] outside the slab ["
                      << boxes.slabLo << ", " << boxes.slabHi << "]";
      if (depth >= 0) continue;
      const glm::dvec3 mag = glm::max(glm::abs(glm::dvec3(vlo)), glm::abs(glm::dvec3(vhi))), ext = glm::dvec3(vhi - vlo);
      const double big = std::max({mag.x, mag.y, mag.z}), extent = std::max({ext.x, ext.y, ext.z});
      // the host's margin is from the root box, a little wider than the vertices' own (its boxes' margin)
      const double pad = 2.0 * (4e-6 * (big + 1e-3) + 1e-6 * 2.0 * extent) + 1e-7;
      if ((Real(boxes.slabLo) < lo - pad || Real(boxes.slabHi) > hi + pad) && ++thick <= 5)
        ADD_FAILURE() << "triangle " << b << ": slab [" << boxes.slabLo << ", " << boxes.slabHi
                      << "] thicker than its heights [" << double(lo) << ", " << double(hi) << "] need";
    }
    EXPECT_EQ(tilted, 0);
    EXPECT_EQ(outside, 0);
    EXPECT_EQ(thick, 0);
  }
}

TEST(DisplacedMeshes, SlabIntervalHoldsTheExactOneAndStaysNear) {
  // disp_slab_interval against long double for the stored floats: the
  // interval it gives holds the exact part of the ray inside the slab
  // (enter no later, leave no earlier), is finite wherever the ray is not
  // close to parallel, and stays within its error terms' size of the exact
  // ends; rays near the origin, a thousand units away, and nearly parallel
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), u01(0.0f, 1.0f);
  const std::size_t count = 4000;
  std::vector<cl_float4> slab(count), o(count), d(count);
  std::vector<cl_float2> bounds(count);
  for (std::size_t k = 0; k < count; ++k) {
    const glm::vec3 nrm = glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
    const float far = k % 3 == 0 ? 1000.0f : 1.0f;
    const glm::vec3 origin = far * glm::vec3(unit(rng), unit(rng), unit(rng));
    const float lo = far * unit(rng), hi = lo + (k % 5 == 0 ? 1e-4f : 0.5f) * u01(rng);
    glm::vec3 dir = glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
    // every fourth nearly along the slab: its normal component removed, then a little put back
    if (k % 4 == 0) dir = glm::normalize(dir - glm::dot(dir, nrm) * nrm + std::ldexp(unit(rng), -int(k % 24)) * nrm);
    slab[k] = {{nrm.x, nrm.y, nrm.z, 0.0f}};
    bounds[k] = {{lo, hi}};
    o[k] = {{origin.x, origin.y, origin.z, 0.0f}};
    d[k] = {{dir.x, dir.y, dir.z, 0.0f}};
  }
  Context& ctx = test::deviceContext();
  cl::Buffer sBuf = input(slab), bBuf = input(bounds), oBuf = input(o), dBuf = input(d);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, count * sizeof(cl_float2));
  cl::Kernel kern(test::testProgram("displaced_tests.cl"), "test_displaced_slab");
  kern.setArg(0, cl_uint(count)), kern.setArg(1, sBuf), kern.setArg(2, bBuf), kern.setArg(3, oBuf),
      kern.setArg(4, dBuf), kern.setArg(5, out);
  ctx.launch("test_displaced_slab", kern, count);
  std::vector<cl_float2> got(count);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, count * sizeof(cl_float2), got.data());
  int loose = 0, wrong = 0, open = 0, finite = 0;
  for (std::size_t k = 0; k < count; ++k) {
    Real s = 0, ds = 0, as = 0, ad = 0;
    for (int a = 0; a < 3; ++a) {
      s += Real(slab[k].s[a]) * Real(o[k].s[a]), ds += Real(slab[k].s[a]) * Real(d[k].s[a]);
      as += std::abs(Real(slab[k].s[a]) * Real(o[k].s[a])), ad += std::abs(Real(slab[k].s[a]) * Real(d[k].s[a]));
    }
    const Real lo = bounds[k].s[0], hi = bounds[k].s[1], enter = got[k].s[0], leave = got[k].s[1];
    if (ds == 0) {
      if (!(std::isinf(enter) && std::isinf(leave)) && (s >= lo && s <= hi) && ++wrong <= 5)
        ADD_FAILURE() << "case " << k << ": a ray inside and along the slab cut short";
      continue;
    }
    const Real a = (lo - s) / ds, b = (hi - s) / ds, want0 = std::min(a, b), want1 = std::max(a, b);
    if ((enter > want0 || leave < want1) && ++wrong <= 5)
      ADD_FAILURE() << "case " << k << ": [" << double(enter) << ", " << double(leave) << "] does not hold the exact ["
                    << double(want0) << ", " << double(want1) << "]";
    // unbounded only where the direction's part along the normal is within ~1e-6 of its size
    if (std::isinf(enter) || std::isinf(leave)) {
      ++open;
      if (std::abs(ds) > 1e-5L * ad && ++loose <= 5)
        ADD_FAILURE() << "case " << k << ": unbounded though |dot(n, d)| " << double(std::abs(ds));
      continue;
    }
    ++finite;
    // the error terms, first order: a few ulps of the heights over |dot(n, d)|, and the ends scaled by the
    // relative error of dot(n, d) (a few ulps of its terms' magnitudes over its size)
    const Real slack = 1e-5L * ((as + std::max(std::abs(lo), std::abs(hi))) + (std::abs(want0) + std::abs(want1)) * ad) /
                       std::abs(ds);
    if ((want0 - enter > slack || leave - want1 > slack) && ++loose <= 5)
      ADD_FAILURE() << "case " << k << ": [" << double(enter) << ", " << double(leave) << "] far wider than ["
                    << double(want0) << ", " << double(want1) << "]";
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(loose, 0);
  EXPECT_GT(finite, int(count / 2));
  EXPECT_GT(open, 0);
}

TEST(DisplacedMeshes, ShadingNormalsFaceOutAndFollowTheBumps) {
  // the shading normal is the displaced surface's: unit, on the side of
  // the vertex normals (outward) whichever way the triangles wind, and
  // tilted from the base sphere's normal where the map slopes
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  for (bool reversed : {false, true}) {
    Scene scene = testSphere(4, 0.3f, -0.15f, center);
    if (reversed)
      for (auto& t : scene.displacedMeshes[0].triangles) std::swap(t[1], t[2]);
    const std::vector<Ray> rays = raysAtSphere(center, test::testSize(2000, 200), 22);
    const std::vector<KernelHit> got = kernelClosest(scene, rays);
    int tilted = 0, hits = 0, inward = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (got[i].t < 0.0f) continue;
      ++hits;
      const glm::vec3 p = rays[i].origin + got[i].t * rays[i].direction;
      const glm::vec3 radial = glm::normalize(p - center);
      EXPECT_NEAR(glm::length(got[i].shading), 1.0f, 1e-4f) << "ray " << i;
      inward += glm::dot(got[i].shading, radial) <= 0.0f;
      tilted += glm::dot(got[i].shading, radial) < 0.99f;
    }
    EXPECT_EQ(inward, 0) << (reversed ? "reversed winding" : "winding as made");
    EXPECT_GT(tilted, hits / 4);
  }
}

TEST(DisplacedMeshes, TraversalsFindWhatEveryTriangleFinds) {
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene scene = testSphere(-1, 0.2f, -0.1f, center, 2);
  const std::vector<Ray> rays = raysAtSphere(center, test::testSize(3000, 300), 23);
  test::expectTraversalsFindWhatBruteForceFinds(scene, rays, kernelClosest(scene, rays), WT_PRIM_DISPLACED,
                                                "every triangle");
}

TEST(DisplacedMeshes, AnyHitAgreesWithClosestHitInEveryTraversal) {
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene scene = testSphere(3, 0.2f, -0.1f, center);
  const std::vector<MicroTriangle> micro = microMesh(scene.displacedMeshes[0]);
  const std::vector<Ray> rays = raysAtSphere(center, test::testSize(3000, 300), 24);
  test::expectAnyHitAgreesWithClosestHit(scene, rays, [&](std::size_t i) {
    const RefHit want = reference(micro, rays[i]);
    return want.nearEdge || (want.hit && std::abs(want.t - Real(rays[i].tmax)) <= 1e-5L * rays[i].tmax);
  });
}

TEST(DisplacedMeshes, AnyHitAgreesWithClosestHitOnRaysLeavingTheSurface) {
  // shadow rays as a renderer makes them: from points on a rough surface
  // (320 base triangles whose shells overlap their neighbours', so a ray
  // starts inside several) to targets outside the sphere or beyond its far
  // side, ending short of the target. Any hit and closest hit run the same
  // micro-triangle tests, so they must agree exactly, however the walks
  // cull boxes and stop early.
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene scene = testSphere(3, 0.2f, -0.1f, center, 2);
  const std::vector<Ray> at = raysAtSphere(center, test::testSize(3000, 300), 27);
  const std::vector<KernelHit> hits = kernelClosest(scene, at);
  std::mt19937 rng(28);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < at.size(); ++i) {
    if (hits[i].t < 0.0f) continue;
    const glm::vec3 p = at[i].origin + hits[i].t * at[i].direction;
    glm::vec3 w;
    do w = glm::vec3(unit(rng), unit(rng), unit(rng));
    while (glm::dot(w, w) > 1.0f || glm::dot(w, w) < 1e-3f);
    const glm::vec3 target = center + (i % 2 ? 3.0f : 1.3f) * glm::normalize(w);
    const glm::vec3 n = glm::dot(hits[i].normal, target - p) >= 0.0f ? hits[i].normal : -hits[i].normal;
    Ray r;
    r.origin = offsetRayOrigin(p, hits[i].error, n);
    const float distance = glm::length(target - r.origin);
    r.direction = (target - r.origin) / distance;
    r.tmin = 0.0f;
    r.tmax = (1.0f - 1e-4f) * distance;
    rays.push_back(r);
  }
  ASSERT_GT(rays.size(), at.size() / 12);
  Tracer tracer(test::deviceContext(), scene);
  const std::vector<RayHit> closest = tracer.traceClosest(rays);
  std::size_t blocked = 0;
  for (const RayHit& h : closest) blocked += h.prim != RayHit::kNoHit;
  // both answers common, or agreement would prove little
  EXPECT_GT(blocked, rays.size() / 10);
  EXPECT_LT(blocked, rays.size() - rays.size() / 10);
  test::expectAnyHitAgreesWithClosestHit(scene, rays, [](std::size_t) { return false; });
}

TEST(DisplacedMeshes, SpawnedRaysLeaveTheSurfaceOrCrossIt) {
  // gentle bumps (amplitude 0.02 on radius 1) far from the origin: rays
  // spawned outward within 45 degrees of the micro-triangle's normal meet
  // nothing (the bumps' slopes stay far below 45 degrees); rays spawned
  // inward meet the far side, a chord well over 0.7 away
  const glm::vec3 center(3.0f, -2.0f, 1.0f);
  const Scene scene = testSphere(4, 0.02f, -0.01f, center);
  const std::vector<Ray> rays = raysAtSphere(center, test::testSize(3000, 300), 25);
  test::expectSpawnedRaysLeaveOrCross(scene, rays, kernelClosest(scene, rays), 26, 0.71f);
}

TEST(DisplacedMeshes, SharedEdgesGiveTheSameMicroVerticesBitForBit) {
  // every edge two base triangles share, every micro-vertex on it, computed
  // by the kernel from each side: the same bits (the watertightness the
  // seams rely on)
  const Scene scene = testSphere(4, 0.3f, -0.15f, glm::vec3(0.3f, -0.2f, 0.1f), 2);
  const DisplacedMesh& mesh = scene.displacedMeshes[0];
  const int n = 1 << displacedLevel(mesh);
  // the lattice point at fraction s/n from corner slot a to corner slot b
  auto lattice = [&](int a, int b, int s) {
    int w[3] = {0, 0, 0};
    w[a] += n - s;
    w[b] += s;
    return glm::ivec2(w[1], w[2]);
  };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::uint32_t, std::array<int, 2>>> firstSide;
  std::vector<cl_uint4> queries;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t va = mesh.triangles[t][e], vb = mesh.triangles[t][(e + 1) % 3];
      const auto key = std::minmax(va, vb);
      auto it = firstSide.find(key);
      if (it == firstSide.end()) {
        firstSide[key] = {t, {e, (e + 1) % 3}};
        continue;
      }
      // the other triangle's slots for the same two vertices, from the lower index on both sides
      const std::uint32_t t0 = it->second.first;
      const int a0 = mesh.triangles[t0][it->second.second[0]] == key.first ? it->second.second[0] : it->second.second[1];
      const int b0 = a0 == it->second.second[0] ? it->second.second[1] : it->second.second[0];
      const int a1 = va == key.first ? e : (e + 1) % 3, b1 = a1 == e ? (e + 1) % 3 : e;
      for (int s = 0; s <= n; ++s) {
        const glm::ivec2 p0 = lattice(a0, b0, s), p1 = lattice(a1, b1, s);
        queries.push_back({{t0, cl_uint(p0.x), cl_uint(p0.y), 0}});
        queries.push_back({{t, cl_uint(p1.x), cl_uint(p1.y), 0}});
      }
    }
  ASSERT_GT(queries.size(), 100u);
  const TypeRows rows = typeRows(scene);
  Context& ctx = test::deviceContext();
  cl::Buffer dataBuf = input(rows.data), infoBuf = input(rows.info), qBuf = input(queries);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, queries.size() * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("displaced_tests.cl"), "test_displaced_vertex");
  k.setArg(0, cl_uint(queries.size())), k.setArg(1, dataBuf), k.setArg(2, infoBuf), k.setArg(3, qBuf), k.setArg(4, out);
  ctx.launch("test_displaced_vertex", k, queries.size());
  std::vector<cl_float4> got(queries.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(cl_float4), got.data());
  int differ = 0;
  for (std::size_t q = 0; q < got.size(); q += 2)
    if (std::memcmp(got[q].s, got[q + 1].s, 3 * sizeof(float)) != 0 && ++differ <= 5)
      ADD_FAILURE() << "edge point " << q / 2 << ": (" << got[q].s[0] << ", " << got[q].s[1] << ", " << got[q].s[2]
                    << ") against (" << got[q + 1].s[0] << ", " << got[q + 1].s[1] << ", " << got[q + 1].s[2] << ")";
  EXPECT_EQ(differ, 0);
}

TEST(DisplacedMeshes, NoLeaksThroughTheSeamsBetweenShells) {
  // the displaced sphere is closed and encloses its centre: every ray from
  // near the centre leaves it through the surface, and every ray from far
  // outside aimed at the centre meets it. Aimed at the base mesh's
  // vertices and at points along its edges, where two shells meet.
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene scene = testSphere(-1, 0.3f, -0.15f, center, 2);
  const DisplacedMesh& mesh = scene.displacedMeshes[0];
  std::mt19937 rng(27);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f), unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < int(test::testSize(4000, 400)); ++i) {
    const auto& t = mesh.triangles[std::size_t(i) % mesh.triangles.size()];
    const int e = i % 3;
    const glm::vec3 a = mesh.positions[t[e]], b = mesh.positions[t[(e + 1) % 3]];
    // a vertex, or a point along an edge
    const glm::vec3 aim = i % 7 == 0 ? a : a + u01(rng) * (b - a);
    Ray r;
    const glm::vec3 inner = center + 0.1f * glm::vec3(unit(rng), unit(rng), unit(rng));
    if (i % 2 == 0) {
      r.origin = inner;
      r.direction = glm::normalize(aim - inner);
    } else {
      r.origin = center + 3.0f * glm::normalize(aim - center) + 0.05f * glm::vec3(unit(rng), unit(rng), unit(rng));
      r.direction = glm::normalize(inner - r.origin);
    }
    rays.push_back(r);
  }
  Tracer tracer(test::deviceContext(), scene);
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    const std::vector<RayHit> hits = tracer.traceClosest(rays, traversal);
    int leaks = 0;
    for (std::size_t i = 0; i < rays.size(); ++i)
      if (hits[i].prim == RayHit::kNoHit && ++leaks <= 5)
        ADD_FAILURE() << "ray " << i << " traversal " << int(traversal) << " passed through";
    EXPECT_EQ(leaks, 0);
    const std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, traversal);
    int through = 0;
    for (std::uint8_t b : blocked) through += b == 0;
    EXPECT_EQ(through, 0) << "traversal " << int(traversal);
  }
}

TEST(DisplacedMeshes, ZeroDisplacementIsTheBaseMesh) {
  // scale 0 and offset 0: the micro-triangles tile the base triangles, so
  // every ray meets the displaced mesh where it meets the base mesh traced
  // as triangles (bar rays through the base edges)
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene displaced = testSphere(3, 0.0f, 0.0f, center);
  Scene base = makeIcosphere(1, center, 1.0f, makeMaterial(glm::vec3(0.5f)));
  const std::vector<Ray> rays = raysAtSphere(center, test::testSize(3000, 300), 28);
  const std::vector<KernelHit> got = kernelClosest(displaced, rays);
  Tracer tracer(test::deviceContext(), base);
  const std::vector<RayHit> want = tracer.traceClosest(rays);
  int bad = 0, hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const bool a = got[i].t >= 0.0f, b = want[i].prim != RayHit::kNoHit;
    hits += b;
    bool ok = a == b;
    if (ok && a) {
      ok = std::abs(got[i].t - want[i].t) <= 2e-6f * (1.0f + want[i].t);
      const WtTriangle& tri = base.triangles[want[i].triangle];
      auto pos = [&](std::uint32_t v) { return glm::vec3(base.positions[v].x, base.positions[v].y, base.positions[v].z); };
      const glm::vec3 n = glm::normalize(glm::cross(pos(tri.v1) - pos(tri.v0), pos(tri.v2) - pos(tri.v0)));
      ok = ok && glm::length(got[i].normal - n) < 1e-3f;
    }
    // a ray through a base edge may take either triangle: the same t, maybe the other normal
    if (!ok && a == b && a && std::abs(got[i].t - want[i].t) <= 2e-6f * (1.0f + want[i].t)) {
      const glm::vec2 bary(want[i].b1, want[i].b2);
      if (std::min(std::min(bary.x, bary.y), 1.0f - bary.x - bary.y) < 1e-3f) continue;
    }
    if (!ok && ++bad <= 5)
      ADD_FAILURE() << "ray " << i << ": displaced t " << got[i].t << ", base t " << want[i].t;
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(hits, int(rays.size() / 3));
}

TEST(DisplacedMeshes, TessellationAtTheSameRateIsTheSameSurface) {
  // --tessellate 2^L makes the kernel's micro-triangles as triangles
  const glm::vec3 center(0.3f, -0.2f, 0.1f);
  const Scene displaced = testSphere(3, 0.2f, -0.1f, center);
  Scene tessellated = displaced;
  EXPECT_EQ(tessellateDisplaced(tessellated, 8), displaced.displacedMeshes[0].triangles.size() * 64);
  EXPECT_TRUE(tessellated.displacedMeshes.empty());
  const std::vector<Ray> rays = raysAtSphere(center, test::testSize(3000, 300), 29);
  Tracer a(test::deviceContext(), displaced), b(test::deviceContext(), tessellated);
  const std::vector<RayHit> ha = a.traceClosest(rays), hb = b.traceClosest(rays);
  int bad = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const bool x = ha[i].prim != RayHit::kNoHit, y = hb[i].prim != RayHit::kNoHit;
    const bool ok = x == y && (!x || std::abs(ha[i].t - hb[i].t) <= 1e-5f * (1.0f + hb[i].t));
    if (!ok && ++bad <= 5) ADD_FAILURE() << "ray " << i << ": displaced t " << ha[i].t << ", tessellated t " << hb[i].t;
  }
  // rays through a micro-edge may go either way where the host's and the kernel's roundings differ
  EXPECT_LE(bad, int(rays.size() / 500));
}

}  // namespace
}  // namespace wt
