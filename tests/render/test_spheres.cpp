// Analytic spheres rendered against closed forms: a white sphere in a
// uniform sky at several scales and far from the origin (every pixel is the
// sky's radiance unless a spawned ray hits the sphere it left), and a sphere
// light over a Lambertian floor (the irradiance of a uniform sphere), with
// and without next-event estimation and MIS.
#include "geometry/primitives.h"
#include "render/render_helpers.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace wt {
namespace {

struct FurnaceCase {
  float scale;       ///< sphere radius
  float offset;      ///< distance of the sphere and camera from the origin
  bool minimal;      ///< the brute-force integrator
  bool packets = true;  ///< camera and their shadow rays in packets (else one by one)
  bool nee = true;
};

class WhiteSphereInUniformSky : public ::testing::TestWithParam<FurnaceCase> {};

TEST_P(WhiteSphereInUniformSky, EveryPixelIsTheSky) {
  const FurnaceCase c = GetParam();
  const glm::vec3 center(c.offset, 0.5f * c.offset, -0.25f * c.offset);
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(1.0f)));
  scene.materialNames.push_back("white");
  scene.spheres.push_back({center, c.scale, 0});
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), center + glm::vec3(0.0f, 0.0f, 3.2f * c.scale));
  scene.camera = camera;

  RenderSettings settings;
  settings.width = settings.height = 24;
  // one bounce: a ray that hits the sphere it leaves is cut short there and
  // loses the sky behind it, which shows as a darker pixel
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.integrator = c.minimal ? Integrator::Minimal : Integrator::Path;
  settings.seed = 3;
  settings.packets = c.packets;
  settings.useNee = c.nee;
  const Image image = test::render(scene, settings, 64);
  // a convex white Lambertian surface returns the uniform sky exactly
  test::expectUniform(image, glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0, "white sphere in a uniform sky");
}

INSTANTIATE_TEST_SUITE_P(Scales, WhiteSphereInUniformSky,
                         ::testing::Values(FurnaceCase{1.0f, 0.0f, false}, FurnaceCase{1e-4f, 0.0f, false},
                                           FurnaceCase{1e4f, 0.0f, false}, FurnaceCase{1.0f, 1e6f, false},
                                           FurnaceCase{1e-2f, 1e3f, false}, FurnaceCase{1.0f, 0.0f, true},
                                           FurnaceCase{1.0f, 1e6f, true}, FurnaceCase{1.0f, 0.0f, false, false},
                                           FurnaceCase{1.0f, 0.0f, false, true, false}),
                         [](const ::testing::TestParamInfo<FurnaceCase>& info) {
                           const FurnaceCase& c = info.param;
                           auto exp10 = [](float v) { return v == 0.0f ? std::string("0") : "1e" + std::to_string(int(std::lround(std::log10(v)))); };
                           std::string name = "radius" + exp10(c.scale) + "_at" + exp10(c.offset) + (c.minimal ? "_minimal" : "_path") +
                                              (c.packets ? "" : "_single") + (c.nee ? "" : "_no_nee");
                           for (char& ch : name)
                             if (ch == '-') ch = 'm';
                           return name;
                         });

struct LightCase {
  Integrator integrator;
  bool mis;
  int spp;
  const char* name;
};

class SphereLightOverFloor : public ::testing::TestWithParam<LightCase> {};

// A floor of albedo rho at y = 0 lit by a black sphere of radius r and
// radiance L centred at height h: at floor point (x, z), d^2 = x^2 + h^2 + z^2,
// the irradiance is pi L (r/d)^2 (h/d), so the floor's radiance is
// rho L r^2 h / d^3. An orthographic camera between them looks straight down.
TEST_P(SphereLightOverFloor, MatchesTheClosedForm) {
  const LightCase c = GetParam();
  const float rho = 0.5f, r = 0.5f, h = 2.0f;
  const glm::vec3 le(4.0f, 2.0f, 1.0f);
  Scene scene = test::makeFloor(6.0f, 0.0f, makeMaterial(glm::vec3(rho)));
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), le));
  scene.materialNames.push_back("light");
  scene.spheres.push_back({glm::vec3(0.0f, h, 0.0f), r, 1});
  const float ymag = 2.0f;
  scene.camera = test::topDownCamera(glm::vec3(0.0f, 1.0f, 0.0f), ymag);

  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 1;
  settings.integrator = c.integrator;
  settings.useMis = c.mis;
  settings.seed = 11;
  const Image image = test::render(scene, settings, c.spp);

  // the closed form averaged over each pixel's footprint (the camera jitters
  // uniformly within it): world x = s_x ymag, z = -s_y ymag
  auto radiance = [&](double x, double z) {
    const double d = std::sqrt(x * x + double(h) * h + z * z);
    return rho * double(r) * r * h / (d * d * d);
  };
  constexpr int kSub = 8;
  int bad = 0;
  const int block = 4;
  for (int by = 0; by < settings.height / block; ++by)
    for (int bx = 0; bx < settings.width / block; ++bx) {
      double expected = 0.0;
      for (int py = by * block; py < (by + 1) * block; ++py)
        for (int px = bx * block; px < (bx + 1) * block; ++px)
          for (int j = 0; j < kSub * kSub; ++j) {
            const double sx = 2.0 * (px + (j % kSub + 0.5) / kSub) / settings.width - 1.0;
            const double sy = 1.0 - 2.0 * (py + (j / kSub + 0.5) / kSub) / settings.height;
            expected += radiance(sx * ymag, -sy * ymag);
          }
      expected /= double(block * block * kSub * kSub);
      for (int ch = 0; ch < 3; ++ch) {
        const test::BlockStat s = test::blockStat(image, bx * block, by * block, (bx + 1) * block, (by + 1) * block, ch);
        const double want = expected * le[ch];
        // 5 standard errors, and 1e-4 of the value for the footprint's quadrature
        const double tol = 5.0 * std::sqrt(s.varianceOfMean) + 1e-4 * want;
        if (std::abs(s.mean - want) > tol && ++bad <= 5)
          ADD_FAILURE() << c.name << ": block (" << bx << ", " << by << ") channel " << ch << ": " << s.mean << " vs "
                        << want << " (tolerance " << tol << ")";
      }
    }
  EXPECT_EQ(bad, 0);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SphereLightOverFloor,
                         ::testing::Values(LightCase{Integrator::Path, true, 64, "path"},
                                           LightCase{Integrator::Path, false, 64, "path_no_mis"},
                                           LightCase{Integrator::Minimal, false, 1024, "minimal"}),
                         [](const ::testing::TestParamInfo<LightCase>& info) { return std::string(info.param.name); });

TEST(SphereLight, SeenDirectlyIsItsRadianceAndNothingBehindIt) {
  // camera rays meet the emitter's outside; its inside, seen from within,
  // does not emit (single-sided) and is black
  Scene scene;
  scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(3.0f, 2.0f, 1.0f)));
  scene.materialNames.push_back("light");
  scene.spheres.push_back({glm::vec3(0.0f), 1.0f, 0});
  CameraDesc outside;
  outside.cameraToWorld = glm::translate(glm::mat4(1.0f), glm::vec3(0.0f, 0.0f, 1.5f));
  outside.yfov = 0.2f;  // the whole frame on the sphere
  scene.camera = outside;
  RenderSettings settings;
  settings.width = settings.height = 8;
  settings.maxBounces = 2;
  test::expectUniform(test::render(scene, settings, 4), glm::dvec3(3.0, 2.0, 1.0), 1e-5, 5.0, "emitter seen from outside");
  CameraDesc inside;
  inside.cameraToWorld = glm::mat4(1.0f);
  scene.camera = inside;
  test::expectUniform(test::render(scene, settings, 4), glm::dvec3(0.0), 0.0, 5.0, "emitter seen from inside");
}

}  // namespace
}  // namespace wt

namespace wt {
namespace {

TEST(SphereVersusTessellation, SameImageWithinNoise) {
  // a metallic-roughness sphere on a floor under a sphere light, once
  // analytic and once as an icosphere of 81 920 triangles (its facets stray
  // from the sphere by 3e-5 of the radius, far below the noise)
  const WtMaterial ball = makePbrMaterial(glm::vec3(0.8f, 0.5f, 0.3f), 0.0f, 0.4f);
  const Scene analytic = test::ballOnFloor([&](Scene& s) {
    s.materials.push_back(ball);
    s.materialNames.push_back("ball");
    s.spheres.push_back({glm::vec3(0.0f), 1.0f, 1});
  });
  const Scene tessellated =
      test::ballOnFloor([&](Scene& s) { appendScene(s, makeIcosphere(6, glm::vec3(0.0f), 1.0f, ball)); });
  test::expectSameBallImage(analytic, tessellated, "analytic sphere against an icosphere");
}

}  // namespace
}  // namespace wt

namespace wt {
namespace {

/// A displaced sphere of radius 1 at the origin from a low-poly base: the
/// octahedron cut into 4^s faces a side, vertices on the unit sphere, normals
/// the positions, uv = 0.5 + 0.5 (x, y). The base is the same above and below
/// z = 0 (its equator is edges), so a flat point's |P| is a function of its
/// (x, y), hence of its uv: the map holds 1 / |P| - 1 (beyond the equator's
/// chords, their value on the same bearing), which moves every point of a
/// base face, displaced along its interpolated normal (= P), onto the sphere.
DisplacedMesh displacedOctasphere(int s, std::uint32_t mapSize, int level, std::uint32_t material) {
  const int n = 1 << s;
  DisplacedMesh mesh;
  std::map<std::array<int, 3>, std::uint32_t> index;  // lattice point (a, b, c), |a| + |b| + |c| = n
  auto vertex = [&](int a, int b, int c) {
    const auto [it, added] = index.try_emplace({a, b, c}, std::uint32_t(mesh.positions.size()));
    if (added) {
      const glm::vec3 p(glm::normalize(glm::dvec3(a, b, c)));
      mesh.positions.push_back(p);
      mesh.normals.push_back(p);
      mesh.texcoords.emplace_back(0.5f + 0.5f * p.x, 0.5f + 0.5f * p.y);
    }
    return it->second;
  };
  struct Flat {
    glm::dvec3 p[3];
  };
  std::vector<Flat> upper;  // the faces above z = 0, in double
  for (int sz : {1, -1})
    for (int sx : {1, -1})
      for (int sy : {1, -1})
        for (int j = 0; j < n; ++j)
          for (int i = 0; i + j < n; ++i)
            for (int up = 0; up < (i + j + 1 < n ? 2 : 1); ++up) {
              std::array<std::array<int, 3>, 3> c =
                  up == 0 ? std::array<std::array<int, 3>, 3>{{{i, j, 0}, {i + 1, j, 0}, {i, j + 1, 0}}}
                          : std::array<std::array<int, 3>, 3>{{{i + 1, j, 0}, {i + 1, j + 1, 0}, {i, j + 1, 0}}};
              glm::dvec3 q[3];
              for (int k = 0; k < 3; ++k) {
                c[std::size_t(k)] = {sx * c[std::size_t(k)][0], sy * c[std::size_t(k)][1],
                                     sz * (n - c[std::size_t(k)][0] * sx * sx - c[std::size_t(k)][1] * sy * sy)};
                q[k] = glm::normalize(glm::dvec3(c[std::size_t(k)][0], c[std::size_t(k)][1], c[std::size_t(k)][2]));
              }
              // wind outwards
              if (glm::dot(glm::cross(q[1] - q[0], q[2] - q[0]), q[0] + q[1] + q[2]) < 0.0) {
                std::swap(c[1], c[2]);
                std::swap(q[1], q[2]);
              }
              mesh.triangles.push_back({vertex(c[0][0], c[0][1], c[0][2]), vertex(c[1][0], c[1][1], c[1][2]),
                                        vertex(c[2][0], c[2][1], c[2][2])});
              if (sz == 1) upper.push_back({{q[0], q[1], q[2]}});
            }
  // the map: texel (x, y) at uv ((x + 0.5) / size, (y + 0.5) / size), (x, y) = 2 uv - 1; 1 / |P| - 1 from
  // the upper face over each texel centre, -1 where none is
  std::vector<double> length(std::size_t(mapSize) * mapSize, -1.0);
  auto centre = [&](std::uint32_t i) { return 2.0 * (i + 0.5) / mapSize - 1.0; };
  for (const Flat& f : upper) {
    const glm::dvec2 a(f.p[0]), b(f.p[1]), c(f.p[2]);
    const glm::dvec2 lo = glm::min(a, glm::min(b, c)), hi = glm::max(a, glm::max(b, c));
    const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    auto texel = [&](double v) { return std::uint32_t(std::clamp((v + 1.0) * 0.5 * mapSize, 0.0, mapSize - 1.0)); };
    for (std::uint32_t y = texel(lo.y); y <= texel(hi.y); ++y)
      for (std::uint32_t x = texel(lo.x); x <= texel(hi.x); ++x) {
        const glm::dvec2 q(centre(x), centre(y));
        const double wb = ((q.x - a.x) * (c.y - a.y) - (q.y - a.y) * (c.x - a.x)) / area;
        const double wc = ((b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x)) / area;
        if (wb >= -1e-12 && wc >= -1e-12 && wb + wc <= 1.0 + 1e-12)
          length[x + std::size_t(y) * mapSize] = glm::length((1.0 - wb - wc) * f.p[0] + wb * f.p[1] + wc * f.p[2]);
      }
  }
  std::vector<std::array<glm::dvec2, 2>> equator;  // the upper faces' edges in z = 0
  for (const Flat& f : upper)
    for (int k = 0; k < 3; ++k)
      if (f.p[k].z == 0.0 && f.p[(k + 1) % 3].z == 0.0) equator.push_back({glm::dvec2(f.p[k]), glm::dvec2(f.p[(k + 1) % 3])});
  mesh.mapWidth = mesh.mapHeight = mapSize;
  for (std::uint32_t y = 0; y < mapSize; ++y)
    for (std::uint32_t x = 0; x < mapSize; ++x) {
      const glm::dvec2 xy(centre(x), centre(y));
      double len = length[x + std::size_t(y) * mapSize];
      // outside the equator's chords: the chord's point on the same bearing
      for (std::size_t k = 0; len < 0.0 && k < equator.size(); ++k) {
        const glm::dvec2 a = equator[k][0], e = equator[k][1] - a;
        const double den = xy.x * e.y - xy.y * e.x;  // solve r xy = a + w e
        const double r = (a.x * e.y - a.y * e.x) / den, w = (a.x * xy.y - a.y * xy.x) / den;
        if (den != 0.0 && r > 0.0 && w >= 0.0 && w <= 1.0) len = glm::length(a + w * e);
      }
      mesh.map.push_back(float(1.0 / len - 1.0));
    }
  mesh.scale = 1.0f;
  mesh.offset = 0.0f;
  mesh.level = level;
  mesh.material = material;
  return mesh;
}

TEST(DisplacedVersusAnalyticSphere, SameImageWithinNoiseAndDiscretisation) {
  // a metallic-roughness sphere of radius 1 on a floor under a sphere light,
  // once analytic and once as a displaced octahedron of 2 048 faces at level
  // 4. Not coarser: shading normals are bump mapping on the smooth base, so
  // where the map makes up for a facet they tilt by the facet's slope, which
  // at 512 faces shows (docs/lab/2026-12-06-issue32-audit.md)
  const WtMaterial ball = makePbrMaterial(glm::vec3(0.8f, 0.5f, 0.3f), 0.0f, 0.4f);
  const DisplacedMesh displaced = displacedOctasphere(4, 512, 4, 1);
  // the stated discretisation error: every micro-vertex within 2e-3 of the
  // radius, half the base's own sag (3.9e-3): the rest is the bilinear map of
  // 1 / |P| - 1 cutting the bends at the base's edges; a micro-triangle's own
  // sag (its edges span 1/16 of a face's) is far below that
  Scene probe;
  probe.displacedMeshes.push_back(displaced);
  probe.materials.push_back(ball);
  probe.materialNames.push_back("ball");
  tessellateDisplaced(probe, 1 << displaced.level);
  double worst = 0.0;
  for (const WtVec4& p : probe.positions) worst = std::max(worst, std::abs(glm::length(glm::dvec3(p.x, p.y, p.z)) - 1.0));
  EXPECT_LT(worst, 2e-3) << "the displaced sphere's micro-vertices stray from the radius";
  // and the base alone (no displacement) strays farther: the map does the work
  probe.positions.clear(), probe.normals.clear(), probe.texcoords.clear(), probe.triangles.clear();
  probe.displacedMeshes.assign(1, displaced);
  probe.displacedMeshes[0].scale = 0.0f;
  tessellateDisplaced(probe, 1 << displaced.level);
  double flat = 0.0;
  for (const WtVec4& p : probe.positions) flat = std::max(flat, std::abs(glm::length(glm::dvec3(p.x, p.y, p.z)) - 1.0));
  EXPECT_GT(flat, 2e-3) << "the base alone is as near the sphere as the bound";
  auto withBall = [&](bool analytic) {
    return test::ballOnFloor([&](Scene& s) {
      s.materials.push_back(ball);
      s.materialNames.push_back("ball");
      if (analytic) s.spheres.push_back({glm::vec3(0.0f), 1.0f, 1});
      else s.displacedMeshes.push_back(displaced);
    });
  };
  test::expectSameBallImage(withBall(true), withBall(false), "analytic sphere against a displaced octahedron");
}

}  // namespace
}  // namespace wt
