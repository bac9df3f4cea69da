// SDF grids (kernels/geometry/sdf_grid.cl) against a long-double reference of
// the same trilinear interpolant on random rays (hit or miss, t, normal),
// on an uneven lattice whose bricks end short of 8 cells, every brick tested
// without the BVH and then through every traversal;
// dense against sparse storage; any hit against closest hit; rays spawned
// from a hit; and rays aimed at the faces and edges between cells and bricks.
#include "device/tracer.h"
#include "device_fixture.h"
#include "geometry/primitives.h"
#include "scene/generators.h"
#include "scene/sdf_volume.h"
#include "core/spawn.h"
#include "primitive_checks.h"
#include "test_util.h"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace wt {
namespace {

using Real = long double;

/// A grid scene: one shape at `resolution` cells over [-1, 1]^3, placed by `place`.
Scene sdfScene(SdfShape shape, std::uint32_t resolution, const glm::dmat4& place, SdfStorage storage,
               const SdfShapeParams& params = {}) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  scene.materialNames.push_back("grey");
  SdfVolume v = makeSdfShape(shape, params, resolution);
  SdfGrid g;
  g.cells = v.cells;
  g.values = std::move(v.values);
  g.latticeToScene = place * v.latticeToObject();
  g.storage = storage;
  scene.sdfGrids.push_back(std::move(g));
  return scene;
}

/// A shape sampled on an uneven lattice of `cells` over [-1, 1]^3 (cells
/// of different edges per axis, bricks cut short at the far faces), values
/// in units of the shortest edge.
Scene unevenSdfScene(SdfShape shape, glm::uvec3 cells, const glm::dmat4& place, SdfStorage storage) {
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  SdfGrid g;
  g.cells = cells;
  const glm::dvec3 edge = 2.0 / glm::dvec3(cells);
  const double unit = std::min(edge.x, std::min(edge.y, edge.z));
  for (std::uint32_t z = 0; z <= cells.z; ++z)
    for (std::uint32_t y = 0; y <= cells.y; ++y)
      for (std::uint32_t x = 0; x <= cells.x; ++x) {
        const glm::dvec3 p = glm::dvec3(-1.0) + edge * glm::dvec3(x, y, z);
        g.values.push_back(float(sdfShapeDistance(shape, SdfShapeParams{}, p) / unit));
      }
  g.latticeToScene = place * glm::scale(glm::translate(glm::dmat4(1.0), glm::dvec3(-1.0)), edge);
  g.storage = storage;
  scene.sdfGrids.push_back(std::move(g));
  return scene;
}

/// A rotated, unevenly scaled, moved placement: the lattice is not the scene's frame.
glm::dmat4 skewedPlacement() {
  glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(0.3, -0.2, 0.1));
  m = glm::rotate(m, 0.7, glm::normalize(glm::dvec3(1.0, 2.0, -0.5)));
  return glm::scale(m, glm::dvec3(1.3, 0.9, 1.1));
}

/// The grid's interpolant in long double at lattice point p (the cell's
/// polynomial; p may lie a little outside the cell it names).
Real interpolate(const SdfGrid& g, const Real p[3], Real grad[3] = nullptr) {
  std::size_t c[3];
  Real q[3];
  const std::uint32_t cells[3] = {g.cells.x, g.cells.y, g.cells.z};
  for (int a = 0; a < 3; ++a) {
    const Real f = std::floor(p[a]);
    c[a] = std::size_t(std::clamp<Real>(f, 0, Real(cells[a] - 1)));
    q[a] = p[a] - Real(c[a]);
  }
  const std::size_t sx = g.cells.x + 1, sxy = sx * (g.cells.y + 1);
  auto s = [&](int x, int y, int z) { return Real(g.values[(c[0] + x) + (c[1] + y) * sx + (c[2] + z) * sxy]); };
  Real v = 0;
  if (grad) grad[0] = grad[1] = grad[2] = 0;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        const Real wx = x ? q[0] : 1 - q[0], wy = y ? q[1] : 1 - q[1], wz = z ? q[2] : 1 - q[2];
        v += s(x, y, z) * wx * wy * wz;
        if (grad) {
          grad[0] += s(x, y, z) * (x ? 1 : -1) * wy * wz;
          grad[1] += s(x, y, z) * wx * (y ? 1 : -1) * wz;
          grad[2] += s(x, y, z) * wx * wy * (z ? 1 : -1);
        }
      }
  return v;
}

struct RefHit {
  bool hit = false;
  Real t = 0;
  glm::dvec3 normal{0.0};
  Real cosine = 0;     ///< |cos| between the ray and the normal at the hit
  bool grazes = false; ///< the interpolant comes within kGraze of 0 without crossing, or the hit is nearly tangent
};

/// Where the reference may differ from a float test: the ray passes within
/// this many voxel units of the surface without crossing it, or meets it
/// at a cosine below kGrazeCosine.
constexpr Real kGraze = 2e-3L;
constexpr Real kGrazeCosine = 2e-3L;

/// The first sign change of the interpolant along the ray in the grid's box
/// and (tmin, tmax): steps of 1/32 lattice unit, then bisection, all in long double.
RefHit reference(const SdfGrid& g, const Ray& ray) {
  const glm::dmat4 inv = glm::inverse(g.latticeToScene);
  Real o[3], d[3];
  for (int a = 0; a < 3; ++a) {
    o[a] = Real(inv[3][a]);
    d[a] = 0;
    for (int k = 0; k < 3; ++k) {
      o[a] += Real(inv[k][a]) * Real(ray.origin[k]);
      d[a] += Real(inv[k][a]) * Real(ray.direction[k]);
    }
  }
  const Real hi[3] = {Real(g.cells.x), Real(g.cells.y), Real(g.cells.z)};
  Real ta = ray.tmin, tb = ray.tmax;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0) {
      if (o[a] < 0 || o[a] > hi[a]) return {};
      continue;
    }
    Real t0 = (0 - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    ta = std::max(ta, std::min(t0, t1));
    tb = std::min(tb, std::max(t0, t1));
  }
  RefHit r;
  if (!(ta < tb)) return r;
  const Real len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const int steps = std::max(2, int(std::ceil((tb - ta) * len * 32)));
  auto at = [&](Real t, Real* grad = nullptr) {
    const Real p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    return interpolate(g, p, grad);
  };
  Real prevT = ta, prev = at(ta);
  Real least = std::abs(prev);
  for (int i = 1; i <= steps; ++i) {
    const Real t = ta + (tb - ta) * i / steps, f = at(t);
    least = std::min(least, std::abs(f));
    if ((f < 0) != (prev < 0)) {
      Real lo = prevT, hiT = t;
      const bool insideLo = prev < 0;
      for (int k = 0; k < 80; ++k) {
        const Real m = 0.5L * (lo + hiT);
        ((at(m) < 0) == insideLo ? lo : hiT) = m;
      }
      r.hit = true;
      r.t = 0.5L * (lo + hiT);
      Real grad[3];
      at(r.t, grad);
      // the scene's gradient: the inverse map's transpose applied
      glm::dvec3 n(0.0);
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) n[k] += double(inv[k][a] * grad[a]);
      r.normal = glm::normalize(n);
      const glm::dvec3 dir = glm::normalize(glm::dvec3(ray.direction));
      r.cosine = std::abs(glm::dot(r.normal, dir));
      r.grazes = r.cosine < kGrazeCosine;
      return r;
    }
    prevT = t;
    prev = f;
  }
  r.grazes = least < kGraze;
  return r;
}

/// Rays from around the grid's box aimed into it (many near the surface), some
/// from inside it, some with a short tmax. The box is [-1, 1]^3 before the
/// grid's placement, whatever its cells.
std::vector<Ray> raysAtGrid(const SdfGrid& g, std::size_t count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), u01(0.0, 1.0);
  auto toScene = [&](glm::dvec3 objectPoint) {
    // object [-1, 1]^3 -> lattice [0, cells] -> scene
    const glm::dvec3 lattice = (objectPoint + 1.0) * 0.5 * glm::dvec3(g.cells);
    return glm::vec3(glm::dvec3(g.latticeToScene * glm::dvec4(lattice, 1.0)));
  };
  std::vector<Ray> rays(count);
  for (std::size_t i = 0; i < count; ++i) {
    Ray& r = rays[i];
    const double reach = i % 5 == 0 ? 0.6 : 2.5;  // a fifth start inside the box
    r.origin = toScene(reach * glm::dvec3(unit(rng), unit(rng), unit(rng)));
    const glm::vec3 target = toScene(0.95 * glm::dvec3(unit(rng), unit(rng), unit(rng)));
    r.direction = glm::normalize(target - r.origin);
    if (!(glm::dot(r.direction, r.direction) > 0.5f)) r.direction = glm::vec3(0, 1, 0);
    r.tmin = 0.0f;
    r.tmax = i % 4 == 1 ? float(3.0 * u01(rng)) : 1e30f;
  }
  return rays;
}

/// The test kernel's answers: every brick against every ray, then the surface.
struct KernelHit {
  float t = -1.0f;
  glm::vec3 normal{0.0f}, error{0.0f};
  std::uint32_t brick = RayHit::kNoHit;
};

std::vector<KernelHit> kernelClosest(const Scene& scene, const std::vector<Ray>& rays) {
  PrimitiveRows rows = gatherPrimitives(scene);
  const std::uint32_t bricks = std::uint32_t(rows.count[WT_PRIM_SDF_GRID]);
  EXPECT_GT(bricks, 0u);
  Context& ctx = test::deviceContext();
  std::vector<WtVec4> data(rows.data.begin() + rows.dataFirst[WT_PRIM_SDF_GRID], rows.data.end());
  std::vector<std::array<std::uint32_t, 4>> info(rows.info.begin() + rows.infoFirst[WT_PRIM_SDF_GRID], rows.info.end());
  std::vector<cl_float4> o(rays.size()), d(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    o[i] = {{rays[i].origin.x, rays[i].origin.y, rays[i].origin.z, rays[i].tmin}};
    d[i] = {{rays[i].direction.x, rays[i].direction.y, rays[i].direction.z, rays[i].tmax}};
  }
  auto in = [&](auto& v) {
    return cl::Buffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, v.size() * sizeof(v[0]), v.data());
  };
  cl::Buffer dataBuf = in(data), infoBuf = in(info), oBuf = in(o), dBuf = in(d);
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 2 * rays.size() * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("sdf_tests.cl"), "test_sdf_closest");
  k.setArg(0, cl_uint(rays.size())), k.setArg(1, bricks), k.setArg(2, dataBuf), k.setArg(3, infoBuf);
  k.setArg(4, oBuf), k.setArg(5, dBuf), k.setArg(6, out);
  ctx.launch("test_sdf_closest", k, rays.size());
  std::vector<cl_float4> got(2 * rays.size());
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * sizeof(cl_float4), got.data());
  std::vector<KernelHit> hits(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const cl_float4 a = got[2 * i], b = got[2 * i + 1];
    if (a.s[0] < 0.0f) continue;
    hits[i].t = a.s[0];
    hits[i].normal = glm::vec3(a.s[1], a.s[2], a.s[3]);
    hits[i].error = glm::vec3(b.s[0], b.s[1], b.s[2]);
    std::memcpy(&hits[i].brick, &b.s[3], 4);
  }
  return hits;
}

/// How far t may stray: float rounding of the ray moved into the lattice
/// (about 1e-7 of the lattice coordinates' size, over the ray's lattice
/// speed), magnified where the ray meets the surface at a slant.
Real tTolerance(const SdfGrid& g, const Ray& ray, const RefHit& want) {
  const glm::dmat3 inv(glm::inverse(g.latticeToScene));
  const double speed = glm::length(inv * glm::dvec3(ray.direction));
  const double size = glm::length(glm::dvec3(g.cells)) + glm::length(glm::dvec3(inv * glm::dvec3(ray.origin)));
  return Real(1e-5 * size / speed) / std::max(want.cosine, Real(1e-3)) + 1e-6L * std::abs(want.t);
}

class SdfStorages : public ::testing::TestWithParam<SdfStorage> {};

TEST_P(SdfStorages, KernelMatchesLongDoubleReference) {
  const Scene scene = unevenSdfScene(SdfShape::kNoisySphere, glm::uvec3(21, 14, 27), skewedPlacement(), GetParam());
  const SdfGrid& g = scene.sdfGrids[0];
  const std::vector<Ray> rays = raysAtGrid(g, test::testSize(6000, 600), 11);
  const std::vector<KernelHit> got = kernelClosest(scene, rays);
  int bad = 0, hits = 0, grazing = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RefHit want = reference(g, rays[i]);
    const bool hit = got[i].t >= 0.0f;
    hits += want.hit;
    std::string problem;
    if (hit != want.hit) {
      if (want.grazes || (want.hit && want.t >= Real(rays[i].tmax) * (1 - 1e-5L))) {
        ++grazing;
        continue;
      }
      problem = hit ? "kernel hit, reference missed" : "kernel missed, reference hit";
    } else if (hit) {
      const Real dt = std::abs(Real(got[i].t) - want.t);
      if (dt > tTolerance(g, rays[i], want)) problem = "t differs by " + std::to_string(double(dt));
      // the normal: the gradient at nearly the same point, to about 1e-4
      else if (glm::length(glm::dvec3(got[i].normal) - want.normal) > 1e-3 + 1e-4 / double(want.cosine))
        problem = "normal differs by " + std::to_string(glm::length(glm::dvec3(got[i].normal) - want.normal));
    }
    if (!problem.empty() && ++bad <= 8)
      ADD_FAILURE() << "ray " << i << ": " << problem << " (kernel t " << got[i].t << ", reference "
                    << (want.hit ? std::to_string(double(want.t)) : "miss") << ", cos " << double(want.cosine) << ")";
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(hits, int(rays.size() / 3));        // the rays do find the surface
  EXPECT_LT(grazing, int(rays.size() / 100) + 1);  // and grazing stays rare
}

TEST_P(SdfStorages, TraversalsFindWhatEveryBrickFinds) {
  // the BVH over the bricks loses none: each traversal's closest hit is
  // the brute-force one's
  const Scene scene = sdfScene(SdfShape::kTorus, 40, skewedPlacement(), GetParam());
  const std::vector<Ray> rays = raysAtGrid(scene.sdfGrids[0], test::testSize(6000, 600), 12);
  test::expectTraversalsFindWhatBruteForceFinds(scene, rays, kernelClosest(scene, rays), WT_PRIM_SDF_GRID,
                                                "every brick");
}

INSTANTIATE_TEST_SUITE_P(DenseAndSparse, SdfStorages, ::testing::Values(SdfStorage::kDense, SdfStorage::kSparse),
                         [](const auto& info) { return info.param == SdfStorage::kDense ? "Dense" : "Sparse"; });

TEST(SdfGrids, DenseAndSparseGiveTheSameHits) {
  const glm::dmat4 place = skewedPlacement();
  const Scene dense = sdfScene(SdfShape::kNoisySphere, 48, place, SdfStorage::kDense);
  const Scene sparse = sdfScene(SdfShape::kNoisySphere, 48, place, SdfStorage::kSparse);
  const std::vector<Ray> rays = raysAtGrid(dense.sdfGrids[0], test::testSize(8000, 800), 13);
  Tracer a(test::deviceContext(), dense), b(test::deviceContext(), sparse);
  // the same corners and the same arithmetic: the same bits
  const std::vector<RayHit> ha = a.traceClosest(rays), hb = b.traceClosest(rays);
  int differ = 0, hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    hits += ha[i].prim != RayHit::kNoHit;
    differ += ha[i].prim != hb[i].prim || ha[i].t != hb[i].t || ha[i].b1 != hb[i].b1;
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(hits, int(rays.size() / 3));
}

TEST(SdfGrids, SparseStorageTakesAQuarterOfDenseAt256) {
  // the goal: at 256^3 the sparse bricks take at most a quarter of
  // the dense grid's bytes, boxes and tree included
  const Scene dense = sdfScene(SdfShape::kNoisySphere, 256, glm::dmat4(1.0), SdfStorage::kDense);
  Scene sparse = dense;
  sparse.sdfGrids[0].storage = SdfStorage::kSparse;
  const PrimitiveRows a = gatherPrimitives(dense), b = gatherPrimitives(sparse);
  EXPECT_EQ(a.count[WT_PRIM_SDF_GRID], b.count[WT_PRIM_SDF_GRID]);
  // per brick its info rows, a box and a reference in the tree; the same for both
  const std::size_t shared = b.info.size() * 16 + b.count[WT_PRIM_SDF_GRID] * (sizeof(Aabb) + 4);
  const std::size_t denseBytes = a.data.size() * 16 + shared, sparseBytes = b.data.size() * 16 + shared;
  EXPECT_LE(4 * sparseBytes, denseBytes) << "sparse " << sparseBytes << " bytes, dense " << denseBytes;
}

TEST(SdfGrids, AnyHitAgreesWithClosestHitInEveryTraversal) {
  const Scene scene = sdfScene(SdfShape::kNoisySphere, 40, skewedPlacement(), SdfStorage::kSparse);
  const std::vector<Ray> rays = raysAtGrid(scene.sdfGrids[0], test::testSize(8000, 800), 14);
  test::expectAnyHitAgreesWithClosestHit(scene, rays, [&](std::size_t i) {
    const RefHit want = reference(scene.sdfGrids[0], rays[i]);
    // a crossing at the segment's very end or a tangency may go either way
    return want.grazes || (want.hit && std::abs(want.t - Real(rays[i].tmax)) <= 1e-5L * rays[i].tmax);
  });
}

TEST(SdfGrids, SpawnedRaysLeaveTheSurfaceOrCrossIt) {
  // a sphere of radius 0.8 in a 256^3 grid off the origin (lattice
  // coordinates up to 256, whose rounding the spawn offset must cover): rays
  // spawned outward (within 60 degrees of the normal) from its hits meet
  // nothing, since the surface cannot bend back that far within the grid;
  // rays spawned inward meet the far side, a chord of at least 2 r cos 60
  // away (less its discretisation)
  const glm::dmat4 place = glm::translate(glm::dmat4(1.0), glm::dvec3(3.0, -2.0, 1.0));
  const Scene scene = sdfScene(SdfShape::kSphere, 256, place, SdfStorage::kSparse);
  const std::vector<Ray> rays = raysAtGrid(scene.sdfGrids[0], test::testSize(6000, 600), 15);
  test::expectSpawnedRaysLeaveOrCross(scene, rays, kernelClosest(scene, rays), 16, 0.5f);
}

TEST(SdfGrids, NoLeaksThroughFacesAndEdgesOfCellsAndBricks) {
  // a plane z = 8 in the lattice (a brick boundary and a cell face) and one
  // at z = 12.5, both exact for a trilinear interpolant; rays from below
  // (outside) and above (inside) aimed at lattice points, cell edges and
  // brick corners must all stop at t where the plane is
  for (double plane : {8.0, 12.5}) {
    Scene scene;
    scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
    SdfGrid g;
    g.cells = glm::uvec3(24, 24, 24);
    g.storage = SdfStorage::kSparse;
    for (std::uint32_t z = 0; z <= 24; ++z)
      for (std::uint32_t y = 0; y <= 24; ++y)
        for (std::uint32_t x = 0; x <= 24; ++x) g.values.push_back(float(plane - z));  // inside above: rays meet it from below
    g.latticeToScene = glm::scale(glm::dmat4(1.0), glm::dvec3(0.25));
    scene.sdfGrids.push_back(g);
    std::mt19937 rng(17);
    std::uniform_int_distribution<int> lattice(1, 23);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < 4000; ++i) {
      // a lattice point, or halfway along an edge, on the plane
      glm::vec3 target(float(lattice(rng)), float(lattice(rng)), float(plane));
      if (i % 3 == 1) target.x += 0.5f;
      if (i % 8 == 0) target = glm::vec3(8.0f, 16.0f, float(plane));  // a corner of four bricks
      Ray r;
      r.origin = 0.25f * glm::vec3(target.x + 6.0f * unit(rng), target.y + 6.0f * unit(rng), float(plane) - 6.0f - 2.0f * std::abs(unit(rng)));
      if (i % 5 == 0) r.origin = 0.25f * glm::vec3(target.x, target.y, 1.0f);  // straight along a cell edge
      // half from inside (above): they leave the solid exactly on the face
      if (i % 2 == 1) r.origin.z = 0.25f * float(2.0 * plane + 0.5) - r.origin.z;
      r.direction = glm::normalize(0.25f * target - r.origin);
      rays.push_back(r);
    }
    Tracer tracer(test::deviceContext(), scene);
    for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
      const std::vector<RayHit> hits = tracer.traceClosest(rays, traversal);
      int leaks = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const float want = (0.25f * float(plane) - rays[i].origin.z) / rays[i].direction.z;
        const bool ok = hits[i].prim != RayHit::kNoHit && std::abs(hits[i].t - want) <= 1e-5f * (1.0f + want);
        if (!ok && ++leaks <= 5)
          ADD_FAILURE() << "plane " << plane << " ray " << i << ": t " << hits[i].t << " prim " << hits[i].prim
                        << ", plane at t " << want;
      }
      EXPECT_EQ(leaks, 0) << "plane " << plane << ", traversal " << int(traversal);
      const std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, traversal);
      int through = 0;
      for (std::uint8_t b : blocked) through += b == 0;
      EXPECT_EQ(through, 0) << "plane " << plane << ", traversal " << int(traversal);
    }
  }
}

TEST(SdfGrids, GridsWithoutSurfaceOrWithNaNDrawNothingAndNeverCrash) {
  // constant, all positive, all negative and NaN-riddled grids: no brick, no
  // hit, no NaN; a NaN corner takes its cells out and leaves the others
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.5f)));
  auto grid = [](float value) {
    SdfGrid g;
    g.cells = glm::uvec3(8);
    g.values.assign(9 * 9 * 9, value);
    return g;
  };
  scene.sdfGrids.push_back(grid(0.0f));
  scene.sdfGrids.push_back(grid(3.0f));
  scene.sdfGrids.push_back(grid(-3.0f));
  scene.sdfGrids.push_back(grid(NAN));
  PrimitiveRows rows = gatherPrimitives(scene);
  EXPECT_EQ(rows.count[WT_PRIM_SDF_GRID], 0u);
  // a sphere whose corners near one pole are NaN keeps the rest of its surface
  Scene sphere = sdfScene(SdfShape::kSphere, 16, glm::dmat4(1.0), SdfStorage::kDense);
  SdfGrid& g = sphere.sdfGrids[0];
  for (std::uint32_t x = 6; x <= 10; ++x)
    for (std::uint32_t y = 6; y <= 10; ++y) g.values[x + 17 * (y + 17 * 15)] = NAN;
  Tracer tracer(test::deviceContext(), sphere);
  std::vector<Ray> rays(2);
  rays[0].origin = glm::vec3(0.0f, 0.0f, 5.0f), rays[0].direction = glm::vec3(0, 0, -1);  // at the NaN cap
  rays[1].origin = glm::vec3(5.0f, 0.0f, 0.0f), rays[1].direction = glm::vec3(-1, 0, 0);
  const std::vector<RayHit> hits = tracer.traceClosest(rays);
  for (const RayHit& h : hits) {
    if (h.prim != RayHit::kNoHit) {
      EXPECT_TRUE(std::isfinite(h.t));
    }
  }
  EXPECT_NE(hits[1].prim, RayHit::kNoHit);
  EXPECT_NEAR(hits[1].t, 5.0f - 0.8f, 0.01f);
}

}  // namespace
}  // namespace wt
