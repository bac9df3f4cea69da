// The alpha test inside traversal (kernels/materials/alpha.cl): a hit on a
// MASK triangle whose coverage is below the cutoff, or on a BLEND triangle
// whose number says so, is no hit, and traversal finds what lies behind.
// Single rays, packets (both widths, the lane-by-lane leaves included) and
// streams must agree ray by ray, BLEND's numbers too; and all agree with a
// brute-force reference that runs the same test on the host. Also which
// triangles the host flags, and that a scene without holes compiles none of it.
#include "brute_force.h"
#include "bvh/builders.h"
#include "device/program.h"
#include "device_fixture.h"
#include "instancing_checks.h"
#include "scene/generators.h"
#include "shared/rng.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <string>

namespace wt {
namespace {

using test::addCheckerTexture;
using test::kNearest;
using test::setBaseColorTexture;

WtMaterial alphaMaterial(std::uint32_t mode, float alpha, float cutoff = 0.5f) {
  WtMaterial m = makePbrMaterial(glm::vec3(0.8f), 0.0f, 0.5f);
  m.alpha_mode = mode;
  m.alpha = alpha;
  m.alpha_cutoff = cutoff;
  return m;
}

/// The checker texture's side, in texels (addCheckerTexture).
constexpr std::uint32_t kChecker = 4;

/// The host's alpha test, as the kernels run it: whether scene triangle
/// `tri` keeps a hit at (b1, b2) for ray `ray` of a batch traced with key
/// `key`. `ambiguous` is set where float rounding may decide otherwise (the
/// texture coordinate within 1e-3 texel of a texel edge).
struct AlphaReference {
  const Scene& scene;
  const Tracer& tracer;
  std::uint32_t key = 0;

  bool keeps(std::uint32_t ray, std::uint32_t tri, std::uint32_t instance, double b1, double b2,
             bool* ambiguous) const {
    const WtTriangle& t = scene.triangles[tri];
    const WtMaterial& m = scene.materials[t.material];
    if (m.alpha_mode == WT_ALPHA_OPAQUE) return true;
    double coverage = m.alpha;
    if (m.texture_mask & (1u << WT_TEXTURE_SLOT_BASE_COLOR)) {
      const double b0 = 1.0 - b1 - b2;
      glm::dvec2 uv = b0 * glm::dvec2(scene.texcoords[t.v0]) + b1 * glm::dvec2(scene.texcoords[t.v1]) +
                      b2 * glm::dvec2(scene.texcoords[t.v2]);
      glm::dvec2 texel = (uv - glm::floor(uv)) * double(kChecker);  // repeat
      glm::dvec2 frac = texel - glm::floor(texel);
      if (std::min({frac.x, frac.y, 1.0 - frac.x, 1.0 - frac.y}) < 1e-3) *ambiguous = true;
      const int x = std::min(int(texel.x), int(kChecker) - 1), y = std::min(int(texel.y), int(kChecker) - 1);
      coverage *= (x + y) % 2 == 0 ? 1.0 : 0.0;
    }
    if (m.alpha_mode == WT_ALPHA_MASK) return coverage >= m.alpha_cutoff;
    std::uint32_t stream = rng_alpha_ray(key, ray);
    if (instance != RayHit::kNoHit) stream = rng_alpha_instance(stream, instance);
    return double(rng_alpha_uniform(stream, tracer.sceneBuffers().leafTriangle(tri))) < coverage;
  }

  /// The nearest hit the test keeps, by brute force over every triangle
  /// (a flat scene: no instances).
  test::BruteHit closest(std::uint32_t index, const Ray& ray, bool* ambiguous) const {
    std::vector<std::pair<double, std::uint32_t>> hits;
    for (std::uint32_t i = 0; i < scene.triangles.size(); ++i) {
      double t, b0, b1, b2;
      if (!test::triangleParams(scene, i, ray, t, b0, b1, b2)) continue;
      if (b0 < 0.0 || b1 < 0.0 || b2 < 0.0 || !(t > ray.tmin && t < ray.tmax) || i == ray.skip) continue;
      hits.emplace_back(t, i);
    }
    std::sort(hits.begin(), hits.end());
    for (auto [t, i] : hits) {
      double tt, b0, b1, b2;
      test::triangleParams(scene, i, ray, tt, b0, b1, b2);
      if (std::min({b0, b1, b2}) < 1e-5) *ambiguous = true;  // an edge graze: either answer is right
      if (!keeps(index, i, RayHit::kNoHit, b1, b2, ambiguous)) continue;
      test::BruteHit h;
      h.t = t;
      h.triangle = i;
      h.minBarycentric = std::min({b0, b1, b2});
      return h;
    }
    return {};
  }
};

using test::sameBits;

/// Four large triangles stacked along z (z = 0, -1, -2, -3, in one leaf and
/// one block of four), each covering the square [-2, 2]^2 seen from +z: a
/// MASK hole (alpha 0.4, cutoff 0.5), BLEND alpha 0.5, a MASK checker (4 x 4
/// texels over [-2, 2]^2) and BLEND alpha 0.5 again.
Scene stackedLayers() {
  Scene scene;
  const WtMaterial materials[] = {alphaMaterial(WT_ALPHA_MASK, 0.4f), alphaMaterial(WT_ALPHA_BLEND, 0.5f),
                                  alphaMaterial(WT_ALPHA_MASK, 1.0f), alphaMaterial(WT_ALPHA_BLEND, 0.5f)};
  for (std::uint32_t layer = 0; layer < 4; ++layer) {
    const float z = -float(layer);
    const std::uint32_t base = std::uint32_t(scene.positions.size());
    for (glm::vec2 c : {glm::vec2(-2.0f, -2.0f), glm::vec2(6.0f, -2.0f), glm::vec2(-2.0f, 6.0f)}) {
      scene.positions.push_back({c.x, c.y, z, 0.0f});
      scene.normals.push_back({0.0f, 0.0f, 0.0f, 0.0f});
      scene.texcoords.push_back((c + 2.0f) / 4.0f);  // one texture period over [-2, 2]
    }
    scene.triangles.push_back({base, base + 1, base + 2, layer});
    scene.materials.push_back(materials[layer]);
    scene.materialNames.push_back("layer " + std::to_string(layer));
  }
  setBaseColorTexture(scene, 2, addCheckerTexture(scene, kChecker));
  return scene;
}

/// Rays straight down (-z) through the layers at texel centres (never near
/// a texel edge), jittered; in each group of `width`, the first k lanes
/// (k = 1, 2, ..., width in turn) aim at the layers and the others far off,
/// so that some packets have one or two lanes in the leaf (tested lane by
/// lane, packets of 8) and others are full.
std::vector<Ray> raysThroughLayers(int width, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.3f, 0.3f);
  std::uniform_int_distribution<int> centre(0, 3);
  std::vector<Ray> rays;
  for (int group = 0; group < 64; ++group) {
    const int k = 1 + group % width;
    for (int l = 0; l < width; ++l) {
      Ray r;
      const float x = -1.5f + float(centre(rng)) + jitter(rng), y = -1.5f + float(centre(rng)) + jitter(rng);
      r.origin = l < k ? glm::vec3(x, y, 5.0f) : glm::vec3(x + 50.0f, y, 5.0f);
      r.direction = glm::vec3(0.0f, 0.0f, -1.0f);
      rays.push_back(r);
    }
  }
  return rays;
}

// The first layer is never there, the checker layer where its texel is
// opaque, the blended ones half the time: whichever layer comes first is the
// hit, found in the same block of four as the holes in front of it.
TEST(AlphaTraversal, StackedLayersFindTheFirstSurfaceThatIsThere) {
  Scene scene = stackedLayers();
  BvhBuildOptions options;
  options.maxLeafSize = 8;
  for (int width : {8, 16}) {
    SCOPED_TRACE("packets of " + std::to_string(width));
    Tracer tracer(test::deviceContext(), scene, options, width);
    ASSERT_EQ(tracer.sceneBuffers().alphaTriangles(), 4u);
    ASSERT_EQ(tracer.sceneBuffers().bvh4Stats().leafCount, 1u) << "the layers must share one leaf";
    tracer.setAlphaKey(rng_alpha_key(3, 1, WT_DIM_ALPHA_EXTEND, 7));
    const AlphaReference reference{scene, tracer, rng_alpha_key(3, 1, WT_DIM_ALPHA_EXTEND, 7)};
    const std::vector<Ray> rays = raysThroughLayers(width, 11);
    const std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
    const std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
    const std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, Traversal::kSingle);
    const std::vector<std::uint8_t> packetBlocked = tracer.traceOccluded(rays, Traversal::kPacket);
    const std::vector<std::uint8_t> streamBlocked = tracer.traceOccluded(rays, Traversal::kStream);
    int wrong = 0, counts[5] = {};
    for (std::size_t i = 0; i < rays.size(); ++i) {
      bool ambiguous = false;
      const test::BruteHit want = reference.closest(std::uint32_t(i), rays[i], &ambiguous);
      ASSERT_FALSE(ambiguous) << "ray " << i;
      ++counts[want.triangle == RayHit::kNoHit ? 4 : want.triangle];
      const bool ok = single[i].triangle == want.triangle && packet[i].triangle == want.triangle &&
                      sameBits(single[i].t, packet[i].t) && blocked[i] == (want.triangle != RayHit::kNoHit) &&
                      packetBlocked[i] == blocked[i] && streamBlocked[i] == blocked[i];
      if (!ok && ++wrong <= 5)
        ADD_FAILURE() << "ray " << i << ": expected layer " << int(want.triangle) << "; single "
                      << int(single[i].triangle) << ", packet " << int(packet[i].triangle) << ", blocked "
                      << int(blocked[i]) << " / " << int(packetBlocked[i]) << " / " << int(streamBlocked[i]);
    }
    EXPECT_EQ(wrong, 0);
    // every case occurs: the hole is never hit; the others, and misses, are
    EXPECT_EQ(counts[0], 0);
    for (int c : {1, 2, 3, 4}) EXPECT_GT(counts[c], int(rays.size()) / 40) << "case " << c;
  }
}

/// A soup whose triangles take five materials in turn: opaque, a MASK hole,
/// a MASK checker, BLEND alpha 0.5 and a BLEND checker (alpha 0.7 on the
/// opaque texels), with random texture coordinates (two periods across).
Scene alphaSoup(std::uint32_t count, std::uint32_t seed) {
  Scene scene = makeTriangleSoup(count, seed, 0.2f);
  scene.materials.clear();
  scene.materialNames.clear();
  for (const WtMaterial& m :
       {makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f), alphaMaterial(WT_ALPHA_MASK, 0.4f),
        alphaMaterial(WT_ALPHA_MASK, 1.0f), alphaMaterial(WT_ALPHA_BLEND, 0.5f), alphaMaterial(WT_ALPHA_BLEND, 0.7f)}) {
    scene.materials.push_back(m);
    scene.materialNames.push_back("m" + std::to_string(scene.materials.size()));
  }
  for (std::size_t i = 0; i < scene.triangles.size(); ++i) scene.triangles[i].material = std::uint32_t(i % 5);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uv(0.0f, 2.0f);
  scene.texcoords.resize(scene.positions.size());
  for (glm::vec2& t : scene.texcoords) t = glm::vec2(uv(rng), uv(rng));
  const std::uint32_t checker = addCheckerTexture(scene, kChecker);
  setBaseColorTexture(scene, 2, checker);
  setBaseColorTexture(scene, 4, checker);
  return scene;
}

/// Camera-like fans from three eyes at the unit cube (neighbouring rays are
/// neighbouring pixels), some with a short tmax, a later tmin or a skip.
std::vector<Ray> fans(const Scene& scene, int side, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> t01(0.0f, 1.0f);
  std::uniform_int_distribution<std::uint32_t> tri(0, std::uint32_t(scene.triangles.size() - 1));
  std::vector<Ray> rays;
  for (glm::vec3 eye : {glm::vec3(0.4f, 0.6f, 3.0f), glm::vec3(-2.0f, 1.5f, -1.0f), glm::vec3(2.5f, -1.2f, 0.7f)}) {
    const glm::vec3 w = glm::normalize(glm::vec3(0.5f) - eye);
    const glm::vec3 u = glm::normalize(glm::cross(w, glm::vec3(0.0f, 1.0f, 0.0f))), v = glm::cross(u, w);
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) {
        Ray r;
        r.origin = eye;
        r.direction = glm::normalize(w + 0.6f * ((x + 0.5f) / side - 0.5f) * u + 0.6f * ((y + 0.5f) / side - 0.5f) * v);
        const std::size_t i = rays.size();
        if (i % 7 == 3) r.tmax = 2.0f + 2.0f * t01(rng);
        if (i % 11 == 5) r.tmin = 2.5f * t01(rng);
        if (i % 13 == 2) r.skip = tri(rng);
        rays.push_back(r);
      }
  }
  return rays;
}

class AlphaSoup : public ::testing::TestWithParam<std::tuple<BvhBuilder, int>> {};

// Every traversal takes the same hits and holes as single rays, and those
// are brute force's with the host's alpha test (but where a texel edge or
// a triangle edge makes the call a float-precision one).
TEST_P(AlphaSoup, TraversalsAgreeWithSingleRaysAndBruteForce) {
  Scene scene = alphaSoup(2000, 3);
  BvhBuildOptions options;
  options.builder = std::get<0>(GetParam());
  options.maxLeafSize = std::get<1>(GetParam());
  const std::vector<Ray> rays = fans(scene, int(test::testSize(40, 16)), 5);
  const std::uint32_t key = rng_alpha_key(0, 2, WT_DIM_ALPHA_SHADOW, 1);
  for (int width : {8, 16}) {
    SCOPED_TRACE("packets of " + std::to_string(width));
    Tracer tracer(test::deviceContext(), scene, options, width, StreamPrefetch::kOn);
    tracer.setAlphaKey(key);
    const AlphaReference reference{scene, tracer, key};
    const std::vector<RayHit> single = tracer.traceClosest(rays, Traversal::kSingle);
    const std::vector<RayHit> packet = tracer.traceClosest(rays, Traversal::kPacket);
    const std::vector<std::uint8_t> blocked = tracer.traceOccluded(rays, Traversal::kSingle);
    const std::vector<std::uint8_t> packetBlocked = tracer.traceOccluded(rays, Traversal::kPacket);
    const std::vector<std::uint8_t> streamBlocked = tracer.traceOccluded(rays, Traversal::kStream);
    int differ = 0, wrong = 0, ambiguousCalls = 0, throughHoles = 0, hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const RayHit &a = single[i], &b = packet[i];
      const bool tie = a.triangle != b.triangle && a.triangle != RayHit::kNoHit && b.triangle != RayHit::kNoHit &&
                       sameBits(a.t, b.t);
      if (!tie && !(a.triangle == b.triangle && sameBits(a.t, b.t)) && ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": single " << a.triangle << " t=" << a.t << ", packet " << b.triangle
                      << " t=" << b.t;
      if ((packetBlocked[i] != blocked[i] || streamBlocked[i] != blocked[i]) && ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": blocked " << int(blocked[i]) << " alone, " << int(packetBlocked[i])
                      << " in a packet, " << int(streamBlocked[i]) << " in a stream";
      // an occluded ray has a closest hit and the other way round (the same test, both ways)
      if (bool(blocked[i]) != (a.triangle != RayHit::kNoHit) && ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": blocked " << int(blocked[i]) << " but closest hit " << a.triangle;
      bool ambiguous = false;
      const test::BruteHit want = reference.closest(std::uint32_t(i), rays[i], &ambiguous);
      hits += want.triangle != RayHit::kNoHit;
      const test::BruteHit plain = test::bruteClosest(scene, rays[i]);
      throughHoles += plain.triangle != want.triangle && plain.triangle != rays[i].skip;
      if (ambiguous) {
        ++ambiguousCalls;
        continue;
      }
      if (!test::agrees(scene, rays[i], a, want) && ++wrong <= 5)
        ADD_FAILURE() << "ray " << i << ": single " << a.triangle << " t=" << a.t << ", brute force "
                      << want.triangle << " t=" << want.t;
    }
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(wrong, 0);
    EXPECT_LT(ambiguousCalls, int(rays.size() / 50));
    // the holes matter: many rays go through one to something else or nothing
    EXPECT_GT(throughHoles, int(rays.size() / 20));
    EXPECT_GT(hits, int(rays.size() / 10));
  }
}

INSTANTIATE_TEST_SUITE_P(Trees, AlphaSoup,
                         ::testing::Combine(::testing::Values(BvhBuilder::Lbvh, BvhBuilder::Sah),
                                            ::testing::Values(1, 4, 8)),
                         [](const auto& param) {
                           return std::string(bvhBuilderName(std::get<0>(param.param))) + "_leaf" +
                                  std::to_string(std::get<1>(param.param));
                         });

// A geometry stored once (instances) cuts the same MASK holes in each copy
// as its flattened copies do; BLEND copies draw numbers of their own, the
// same in every traversal.
TEST(AlphaTraversal, InstancesCutTheSameHolesAsTheirFlattenedCopies) {
  Scene mesh = makeGrid(8, glm::vec3(0.0f), 1.0f, glm::vec3(1, 0, 0), glm::vec3(0, 1, 0), makeMaterial(glm::vec3(0.5f)));
  ASSERT_GE(mesh.triangles.size(), SceneBuffers::kMinInstanceTriangles);
  mesh.texcoords.resize(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    mesh.texcoords[v] = glm::vec2(mesh.positions[v].x, mesh.positions[v].y) * 0.37f + 0.1f;
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 4; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(0.3f * c, 0.2f * c, -0.5f * c));
    m = glm::rotate(m, 0.3f * c, glm::vec3(0.2f, 1.0f, 0.1f));
    if (c == 2) m = glm::scale(m, glm::vec3(1.0f, -1.0f, 1.0f));  // a mirror image
    transforms.push_back(m);
  }
  Scene scene = placeCopies(mesh, transforms);
  scene.materials[0] = alphaMaterial(WT_ALPHA_MASK, 1.0f);
  setBaseColorTexture(scene, 0, addCheckerTexture(scene, kChecker));
  std::vector<Ray> rays;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < int(test::testSize(4096, 512)); ++i) {
    Ray r;
    r.origin = glm::vec3(0.4f + 0.8f * u(rng), 0.3f + 0.8f * u(rng), 4.0f);
    r.direction = glm::normalize(glm::vec3(0.1f * u(rng), 0.1f * u(rng), -1.0f));
    rays.push_back(r);
  }
  Tracer flat(test::deviceContext(), scene, test::withInstancing(Instancing::Off));
  Tracer instanced(test::deviceContext(), scene, test::withInstancing(Instancing::On));
  ASSERT_GT(instanced.sceneBuffers().instanceCount(), 0u);
  ASSERT_EQ(instanced.sceneBuffers().alphaTriangles(), mesh.triangles.size());  // the geometry's, once
  const std::vector<RayHit> want = flat.traceClosest(rays);
  const std::vector<std::uint8_t> wantBlocked = flat.traceOccluded(rays);
  int differ = 0, edges = 0, covered = 0, behind = 0;
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    const std::vector<RayHit> got = instanced.traceClosest(rays, traversal);
    const std::vector<std::uint8_t> blocked = instanced.traceOccluded(rays, traversal);
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (!test::hitsAgree(scene, rays[i], got[i], want[i], &edges) && ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": instanced " << got[i].triangle << ", flat " << want[i].triangle;
      if (blocked[i] != wantBlocked[i] && ++differ <= 5)
        ADD_FAILURE() << "ray " << i << ": blocked " << int(blocked[i]) << " instanced, " << int(wantBlocked[i])
                      << " flat";
      covered += want[i].triangle != RayHit::kNoHit;
      behind += want[i].triangle != RayHit::kNoHit && want[i].triangle >= mesh.triangles.size();
    }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_LT(edges, int(rays.size() / 50));
  EXPECT_GT(behind, covered / 10);  // rays through the first copy's holes meet the others

  // BLEND: the instanced traversals agree with one another ray by ray
  scene.materials[0] = alphaMaterial(WT_ALPHA_BLEND, 0.6f);
  Tracer blended(test::deviceContext(), scene, test::withInstancing(Instancing::On));
  blended.setAlphaKey(99);
  const std::vector<RayHit> single = blended.traceClosest(rays, Traversal::kSingle);
  const std::vector<RayHit> packet = blended.traceClosest(rays, Traversal::kPacket);
  const std::vector<std::uint8_t> oneBlocked = blended.traceOccluded(rays, Traversal::kSingle);
  const std::vector<std::uint8_t> streamBlocked = blended.traceOccluded(rays, Traversal::kStream);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if ((single[i].triangle != packet[i].triangle || single[i].instance != packet[i].instance ||
         oneBlocked[i] != streamBlocked[i]) &&
        ++differ <= 5)
      ADD_FAILURE() << "ray " << i << ": BLEND single " << single[i].triangle << ", packet " << packet[i].triangle;
  }
  EXPECT_EQ(differ, 0);
}

// Which triangles may have a hole: only they pay for the test, and a scene
// with none compiles none of it.
TEST(AlphaFlags, OnlyTrianglesThatMayHaveHolesAreFlagged) {
  Scene scene = makeTriangleSoup(8, 1, 0.2f);
  scene.materials.clear();
  scene.materialNames.clear();
  const WtMaterial materials[] = {
      alphaMaterial(WT_ALPHA_OPAQUE, 0.1f),        // 0: alpha ignored
      alphaMaterial(WT_ALPHA_MASK, 0.6f),          // 1: always above the cutoff
      alphaMaterial(WT_ALPHA_MASK, 0.4f),          // 2: always a hole
      alphaMaterial(WT_ALPHA_BLEND, 1.0f),         // 3: always there
      alphaMaterial(WT_ALPHA_BLEND, 0.99f),        // 4: sometimes not
      alphaMaterial(WT_ALPHA_MASK, 1.0f),          // 5: a checker texture
      alphaMaterial(WT_ALPHA_MASK, 1.0f),          // 6: an opaque texture
      alphaMaterial(WT_ALPHA_MASK, 0.5f, 0.5f),    // 7: coverage equal to the cutoff is there
  };
  for (const WtMaterial& m : materials) {
    scene.materials.push_back(m);
    scene.materialNames.push_back("m");
  }
  for (std::uint32_t i = 0; i < 8; ++i) scene.triangles[i].material = i;
  setBaseColorTexture(scene, 5, addCheckerTexture(scene, 2));
  DecodedImage opaque;
  opaque.width = opaque.height = 2;
  opaque.rgba8.assign(16, 255);
  opaque.rgba8[0] = 3;  // colour varies, alpha does not
  opaque.name = "opaque";
  const std::uint32_t solid = scene.textures.addTexture(scene.textures.addImage(opaque, true));
  setBaseColorTexture(scene, 6, solid);
  EXPECT_FALSE(textureIsOpaque(scene.textures, 0));
  EXPECT_TRUE(textureIsOpaque(scene.textures, solid));
  std::vector<std::int8_t> opaqueTexture = {0, 1};
  const bool want[] = {false, false, true, false, true, true, false, false};
  for (std::uint32_t i = 0; i < 8; ++i) EXPECT_EQ(triangleMayHaveHoles(scene, i, opaqueTexture), want[i]) << i;
  // COLOR_0's alpha at a corner takes part: 0.6 * 0.5 is below the cutoff
  Scene coloured = scene;
  coloured.colors.assign(coloured.positions.size(), glm::vec4(1.0f));
  EXPECT_FALSE(triangleMayHaveHoles(coloured, 1, opaqueTexture));
  coloured.colors[coloured.triangles[1].v2].w = 0.5f;
  EXPECT_TRUE(triangleMayHaveHoles(coloured, 1, opaqueTexture));

  Tracer tracer(test::deviceContext(), scene);
  EXPECT_EQ(tracer.sceneBuffers().alphaTriangles(), 3u);
  EXPECT_TRUE(tracer.sceneBuffers().hasAlpha());
  for (std::uint32_t m : {2u, 4u, 5u}) scene.materials[m].alpha_mode = WT_ALPHA_OPAQUE;
  Tracer none(test::deviceContext(), scene);
  EXPECT_EQ(none.sceneBuffers().alphaTriangles(), 0u);
  EXPECT_FALSE(none.sceneBuffers().hasAlpha());
}

TEST(AlphaFlags, TheSwitchComesFromKernelFeatures) {
  KernelFeatures features;
  auto has = [&](const std::string& d) {
    std::vector<std::string> defines = kernelDefines(features);
    return std::find(defines.begin(), defines.end(), d) != defines.end();
  };
  EXPECT_TRUE(has("-D WT_HAS_ALPHA=0"));
  features.alpha = true;
  EXPECT_TRUE(has("-D WT_HAS_ALPHA=1"));
}

}  // namespace
}  // namespace wt
