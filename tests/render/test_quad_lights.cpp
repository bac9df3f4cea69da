// Rectangle lights: findQuadLights pairs exactly the emissive triangles that
// make a rectangle (one light each, its two halves pointing at it), and a
// scene lit by rectangles renders the same with them sampled as spherical
// rectangles as with their triangles sampled apart (RenderSettings::quadLights).
#include "device/program.h"
#include "render/light_list.h"
#include "render/render_helpers.h"
#include "test_util.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <set>
#include <utility>

namespace wt {
namespace {

/// Appends triangles (a, b, c) and (a, c, d) of material `material`: a
/// rectangle split along a-c when the corners make one.
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, std::uint32_t material) {
  const std::uint32_t first = std::uint32_t(scene.positions.size());
  for (glm::vec3 p : {a, b, c, d}) {
    scene.positions.push_back({p.x, p.y, p.z, 0});
    scene.normals.push_back({0, 0, 0, 0});
    scene.texcoords.emplace_back(0.0f);
  }
  scene.triangles.push_back({first, first + 1, first + 2, material});
  scene.triangles.push_back({first, first + 2, first + 3, material});
}

/// Rectangle (c, e1, e2), e1 and e2 perpendicular, facing e1 x e2.
void addRect(Scene& scene, glm::vec3 c, glm::vec3 e1, glm::vec3 e2, std::uint32_t material) {
  addQuad(scene, c, c + e1, c + e1 + e2, c + e2, material);
}

std::uint32_t addMaterial(Scene& scene, const WtMaterial& m, const char* name) {
  scene.materials.push_back(m);
  scene.materialNames.push_back(name);
  return std::uint32_t(scene.materials.size() - 1);
}

// Found: an axis-aligned rectangle, and one turned by an odd angle whose
// corners were rounded to float. Not found: a parallelogram, a rectangle
// whose halves differ in material, one with a half turned over, one whose far
// corner is off by 1e-3 of the diagonal (100 x kQuadTolerance), one with
// holes (BLEND), and the floor, which does not emit. Each rectangle is one
// light of both halves' power; both halves point at it, with the
// rectangle's selection probability over its area.
TEST(QuadLights, FoundExactlyWhereTwoTrianglesMakeARectangle) {
  Scene scene = test::makeFloor(2.0f, 0.0f, makeMaterial(glm::vec3(0.7f)));
  const std::uint32_t lamp = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(2.0f)), "lamp");
  const std::uint32_t twin = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(2.0f)), "twin");
  WtMaterial holed = makeMaterial(glm::vec3(0.0f), glm::vec3(2.0f));
  holed.alpha_mode = WT_ALPHA_BLEND;
  holed.alpha = 0.5f;
  const std::uint32_t blend = addMaterial(scene, holed, "blend");
  const glm::vec3 down(0.0f, 0.0f, 0.3f), side(0.4f, 0.0f, 0.0f);
  const std::size_t axisAligned = scene.triangles.size();
  addRect(scene, {-1.5f, 1.0f, -1.5f}, side, down, lamp);
  // turned about an odd axis: corners rounded to float
  const glm::mat3 turn = glm::mat3(glm::rotate(glm::mat4(1.0f), 0.7316f, glm::normalize(glm::vec3(0.3f, 0.8f, -0.52f))));
  const std::size_t turned = scene.triangles.size();
  addRect(scene, {-0.5f, 1.2f, -1.5f}, turn * side, turn * down, lamp);
  addQuad(scene, {0.5f, 1.0f, -1.5f}, glm::vec3(0.5f, 1.0f, -1.5f) + side,
          glm::vec3(0.5f, 1.0f, -1.5f) + side + down + glm::vec3(0.1f, 0.0f, 0.0f),
          glm::vec3(0.5f, 1.0f, -1.5f) + down + glm::vec3(0.1f, 0.0f, 0.0f), lamp);  // a parallelogram
  addRect(scene, {-1.5f, 1.0f, 0.0f}, side, down, lamp);  // halves of two materials
  scene.triangles.back().material = twin;
  addRect(scene, {-0.5f, 1.0f, 0.0f}, side, down, lamp);  // a half turned over
  std::swap(scene.triangles.back().v1, scene.triangles.back().v2);
  {
    const glm::vec3 c(0.5f, 1.0f, 0.0f);
    const float off = 1e-3f * glm::length(side + down);  // the far corner, off the rectangle
    addQuad(scene, c, c + side, c + side + down + glm::vec3(0.0f, off, 0.0f), c + down, lamp);
  }
  addRect(scene, {1.5f, 1.0f, 0.0f}, side, down, blend);

  RenderSettings settings;
  settings.width = settings.height = 4;
  settings.lightSampler = LightSampler::Power;
  Renderer renderer(test::deviceContext(), scene, settings);
  const LightList& list = renderer.lights();
  const std::vector<std::uint32_t>& order = renderer.sceneBuffers().leafOrder();
  const std::vector<QuadLight> quads = findQuadLights(scene, renderer.sceneBuffers());
  std::set<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (const QuadLight& q : quads)
    pairs.insert({std::min(order[q.first], order[q.second]), std::max(order[q.first], order[q.second])});
  const std::set<std::pair<std::uint32_t, std::uint32_t>> want = {
      {std::uint32_t(axisAligned), std::uint32_t(axisAligned + 1)}, {std::uint32_t(turned), std::uint32_t(turned + 1)}};
  EXPECT_EQ(pairs, want);
  ASSERT_EQ(list.quadLights, 2u);
  // 7 lamps of 2 triangles: 2 rectangles and 10 triangles
  EXPECT_EQ(list.emissiveTriangles, 14u);
  const double rectArea = glm::length(side) * glm::length(down);
  // a triangle light of the same emission, opaque: the twin half's
  std::uint32_t triangleLight = ~0u;
  for (std::uint32_t i = list.analyticCount; i < list.lights.size(); ++i)
    if (list.lights[i].type == WT_LIGHT_TRIANGLE && scene.triangles[order[list.lights[i].triangle]].material == twin)
      triangleLight = i;
  ASSERT_NE(triangleLight, ~0u);
  for (const QuadLight& q : quads) {
    const std::uint32_t light = list.emitterQuad[q.first];
    ASSERT_LT(light, list.lights.size());
    EXPECT_EQ(list.emitterQuad[q.second], light);
    EXPECT_EQ(list.lights[light].type, std::uint32_t(WT_LIGHT_QUAD));
    EXPECT_EQ(list.lights[light].triangle, q.first);
    // the row's corner and edges: the first half's right-angle corner and its edges in float, bit for bit
    // (the kernels sample from them and the emitter hit's pdf reads them); the second half's index
    const WtLight& row = list.lights[light];
    const WtTriangle& first = scene.triangles[order[q.first]];
    const std::array<std::uint32_t, 3> v = {first.v0, first.v1, first.v2};
    auto at = [&](std::uint32_t k) {
      const WtVec4& p = scene.positions[v[(q.corner + k) % 3]];
      return glm::vec3(p.x, p.y, p.z);
    };
    const glm::vec3 e1 = at(1) - at(0), e2 = at(2) - at(0);
    EXPECT_EQ(glm::vec3(row.position.x, row.position.y, row.position.z), at(0));
    EXPECT_EQ(glm::vec3(row.direction.x, row.direction.y, row.direction.z), e1);
    EXPECT_EQ(glm::vec3(row.intensity.w, row.cos_inner, row.cos_outer), e2);
    EXPECT_EQ(std::bit_cast<std::uint32_t>(row.direction.w), q.second);
    // pi L area, both halves' power: twice a triangle's of the same emission and half the area
    EXPECT_NEAR(list.alias[light].pmf / list.alias[triangleLight].pmf, 2.0, 1e-5);
    EXPECT_NEAR(list.emitterPdfArea[q.first], list.alias[light].pmf / rectArea, 1e-5 * list.emitterPdfArea[q.first]);
    EXPECT_EQ(list.emitterPdfArea[q.second], list.emitterPdfArea[q.first]);
  }
  std::size_t marked = 0;
  for (std::uint32_t l : list.emitterQuad) marked += l != WT_NO_QUAD;
  EXPECT_EQ(marked, 4u);
  // off: two triangle lights each
  settings.quadLights = false;
  Renderer apart(test::deviceContext(), scene, settings);
  EXPECT_EQ(apart.lights().quadLights, 0u);
  EXPECT_EQ(apart.lights().lights.size(), 14u);
}

/// A diffuse floor lit by a large rectangle close above it (sampled by
/// solid angle from the floor below) and a small, distant, tilted two-sided
/// one (by area from most of the floor), seen from above and in front.
Scene quadLitScene() {
  Scene scene = test::makeFloor(2.0f, 0.0f, makeMaterial(glm::vec3(0.7f)));
  const std::uint32_t big = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(2.0f)), "big");
  const std::uint32_t small = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(150.0f), true), "small");
  addRect(scene, {-0.6f, 0.35f, -0.4f}, {1.2f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.8f}, big);
  addRect(scene, {1.2f, 1.6f, -1.0f}, {0.08f, 0.0f, 0.0f}, {0.0f, 0.03f, 0.06f}, small);
  CameraDesc camera;
  camera.cameraToWorld =
      glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.8f, 3.0f), glm::vec3(0.0f, 0.2f, 0.0f), glm::vec3(0, 1, 0)));
  scene.camera = camera;
  return scene;
}

/// Samples per pixel of the image comparisons below: the z test takes its
/// tolerance from the renders' own variances, so it holds at the small size
/// (the sanitizer pass: the host code is the same per sample).
int comparisonSpp() { return int(test::testSize(256, 64)); }

// The same image, rectangles sampled as one or as two triangles each, NEE
// with MIS, the lights picked by power and by the light tree (4 x 4 blocks,
// z 4.5 from the two renders' own variances).
TEST(QuadLights, RenderTheSameAsTheirTriangles) {
  const Scene scene = quadLitScene();
  for (LightSampler sampler : {LightSampler::Power, LightSampler::Tree}) {
    RenderSettings settings;
    settings.width = settings.height = 32;
    settings.maxBounces = 3;
    settings.lightSampler = sampler;
    settings.seed = 11;
    const Image quads = test::render(scene, settings, comparisonSpp());
    settings.quadLights = false;
    settings.seed = 12;
    const Image triangles = test::render(scene, settings, comparisonSpp());
    const double worst = test::expectSameImage(quads, triangles, 4, 4.5,
                                               sampler == LightSampler::Power ? "lights by power" : "light tree");
    std::printf("rectangle lights against their triangles (%s): worst |z| %.2f\n",
                sampler == LightSampler::Power ? "power" : "tree", worst);
  }
}

/// Renders `scene` on shade's lanes (seed `seed`) and one path per work-item
/// (seed + 1), comparisonSpp() each, and expects the same image (4 x 4 blocks, z 4.5);
/// the worst |z|.
double shadeLanesAgainstOnePath(const Scene& scene, RenderSettings settings, std::uint32_t seed, const char* what) {
  settings.seed = seed;
  const Image lanes = test::render(scene, settings, comparisonSpp());
  settings.shadeLanes = false;
  settings.seed = seed + 1;
  const Image single = test::render(scene, settings, comparisonSpp());
  const double worst = test::expectSameImage(lanes, single, 4, 4.5, what);
  std::printf("shade on lanes against one path per work-item (%s): worst |z| %.2f\n", what, worst);
  return worst;
}

// Shade on 8 lanes (kernels/shade_lanes.cl, RenderSettings::shadeLanes; the
// metallic-roughness test below takes the device's width, 16 on AVX-512)
// against one path per work-item (shade.cl): the same image within noise
// (4 x 4 blocks, z 4.5 from the two renders' own variances). The scene has
// every light the lanes reach: rectangles (by solid angle and by area),
// lone emissive triangles (by solid angle and by area), a point light and a
// constant sky (one lane at a time), picked by power and by the light tree; a corner of a wall next to
// the floor sends paths back and forth.
TEST(QuadLights, ShadeLanesRenderTheSameAsOnePathPerWorkItem) {
  Scene scene = quadLitScene();
  const std::uint32_t tri = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(6.0f), true), "triangle");
  const std::uint32_t wall = addMaterial(scene, makeMaterial(glm::vec3(0.8f, 0.3f, 0.2f)), "wall");
  addRect(scene, {-2.0f, 0.0f, -1.2f}, {0.0f, 1.5f, 0.0f}, {4.0f, 0.0f, 0.0f}, wall);
  // a triangle near enough to be sampled by solid angle, and a tiny one by area
  const std::uint32_t tiny = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(3000.0f), true), "tiny");
  for (auto [corners, material] : {std::pair{std::array{glm::vec3(0.9f, 0.9f, 0.3f), glm::vec3(1.2f, 0.9f, 0.6f),
                                                        glm::vec3(0.8f, 1.1f, 0.7f)}, tri},
                                   std::pair{std::array{glm::vec3(-0.5f, 1.8f, 0.5f), glm::vec3(-0.45f, 1.8f, 0.5f),
                                                        glm::vec3(-0.5f, 1.8f, 0.55f)}, tiny}}) {
    const std::uint32_t first = std::uint32_t(scene.positions.size());
    for (glm::vec3 p : corners) {
      scene.positions.push_back({p.x, p.y, p.z, 0});
      scene.normals.push_back({0, 0, 0, 0});
      scene.texcoords.emplace_back(0.0f);
    }
    scene.triangles.push_back({first, first + 1, first + 2, material});
  }
  // a tilted rectangle whose edges have distinct non-zero y and z (dyadic: exactly a
  // rectangle in float), so that a lane reading an edge's components out of order shows
  const std::uint32_t tilted = addMaterial(scene, makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f), true), "tilted");
  addRect(scene, {0.75f, 0.375f, -0.75f}, {1.0f, 0.25f, 0.5f}, {0.0f, 0.5f, -0.25f}, tilted);
  PunctualLight point;
  point.position = glm::vec3(-1.0f, 1.2f, 1.0f);
  point.intensity = glm::vec3(0.6f, 0.8f, 1.0f);
  scene.lights.push_back(point);
  {
    RenderSettings probe;
    probe.width = probe.height = 4;
    Renderer renderer(test::deviceContext(), scene, probe);
    ASSERT_EQ(findQuadLights(scene, renderer.sceneBuffers()).size(), 3u) << "the tilted rectangle is one light";
  }
  for (LightSampler sampler : {LightSampler::Power, LightSampler::Tree}) {
    RenderSettings settings;
    settings.width = settings.height = 32;
    settings.maxBounces = 3;
    settings.rrMinDepth = 1;  // roulette where it weighs
    settings.lightSampler = sampler;
    settings.background = glm::vec3(0.2f, 0.25f, 0.3f);
    settings.shadeLanesWidth = 8;
    shadeLanesAgainstOnePath(scene, settings, 21, sampler == LightSampler::Power ? "lights by power" : "light tree");
  }
}

// The same for metallic-roughness surfaces (kernels/shade_lanes.cl's GGX on
// lanes) beside a Lambertian one: a rough copper floor under the rectangles
// (where light sampling and the BSDF share by MIS), a rough dielectric (GGX
// over its diffuse base), a near-mirror half-metal (a delta lobe picked
// against a diffuse one) and a rough half-metal, also lit by a point light,
// with the diffuse and specular bounce limits apart so that a path's lobes
// run out one at a time.
TEST(QuadLights, ShadeLanesRenderMetallicRoughnessTheSameAsOnePathPerWorkItem) {
  Scene scene = quadLitScene();
  scene.materials[0] = makePbrMaterial(glm::vec3(0.95f, 0.64f, 0.54f), 1.0f, 0.5f);
  const std::uint32_t plastic = addMaterial(scene, makePbrMaterial(glm::vec3(0.2f, 0.4f, 0.8f), 0.0f, 0.5f), "plastic");
  const std::uint32_t mirror = addMaterial(scene, makePbrMaterial(glm::vec3(0.9f), 0.5f, 0.01f), "mirror");
  const std::uint32_t half = addMaterial(scene, makePbrMaterial(glm::vec3(0.7f, 0.7f, 0.3f), 0.5f, 0.7f), "half");
  const std::uint32_t white = addMaterial(scene, makeMaterial(glm::vec3(0.8f)), "white");
  addRect(scene, {-2.0f, 0.0f, -1.2f}, {0.0f, 1.5f, 0.0f}, {2.0f, 0.0f, 0.0f}, plastic);
  addRect(scene, {0.0f, 0.0f, -1.2f}, {0.0f, 1.5f, 0.0f}, {2.0f, 0.0f, 0.0f}, mirror);
  addRect(scene, {-1.2f, 0.0f, 0.4f}, {0.0f, 0.0f, 0.5f}, {0.0f, 0.6f, 0.0f}, white);
  addRect(scene, {1.2f, 0.0f, 0.4f}, {0.0f, 0.6f, 0.0f}, {0.0f, 0.0f, 0.5f}, half);
  PunctualLight point;
  point.position = glm::vec3(-1.0f, 1.2f, 1.0f);
  point.intensity = glm::vec3(0.6f, 0.8f, 1.0f);
  scene.lights.push_back(point);
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 3;
  settings.maxDiffuseBounces = 1;
  settings.maxSpecularBounces = 2;
  settings.rrMinDepth = 1;
  settings.background = glm::vec3(0.2f, 0.25f, 0.3f);
  shadeLanesAgainstOnePath(scene, settings, 31, "metallic-roughness");
}

/// An axis-aligned box [lo, hi] of `material`, its faces facing out.
void addBox(Scene& scene, glm::vec3 lo, glm::vec3 hi, std::uint32_t material) {
  const glm::vec3 d = hi - lo, x(d.x, 0.0f, 0.0f), y(0.0f, d.y, 0.0f), z(0.0f, 0.0f, d.z);
  addRect(scene, lo, z, y, material);
  addRect(scene, lo + x, y, z, material);
  addRect(scene, lo, x, z, material);
  addRect(scene, lo + y, z, x, material);
  addRect(scene, lo, y, x, material);
  addRect(scene, lo + z, x, y, material);
}

// With transmission the lanes shade the paths in air at opaque surfaces and
// at smooth glass met from air or on the way out of the one volume a path is
// in, and hand the rest to shade.cl's code one lane at a time: the same
// image as one path per work-item. Glass boxes of triangles (which the lanes
// take): a smooth absorbing one (the lanes' Fresnel choice, refraction and
// absorption on the way out) holding a glowing opaque block (paths inside a
// medium hit it, and the medium absorbs its light) and a lower-priority water
// block (false hits, which shift a path's bounce, and two-deep stacks), and a
// rough one (rough transmission), beside the metallic-roughness and
// Lambertian surfaces that stay on the lanes.
TEST(QuadLights, ShadeLanesRenderGlassTheSameAsOnePathPerWorkItem) {
  Scene scene = quadLitScene();
  scene.materials[0] = makePbrMaterial(glm::vec3(0.7f, 0.6f, 0.5f), 0.0f, 0.6f);
  const std::uint32_t glass = addMaterial(
      scene, withPriority(withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.5f, false,
                                           glm::vec3(0.5f, 1.5f, 3.0f)), 1), "glass");
  const std::uint32_t water = addMaterial(
      scene, withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.33f, false, glm::vec3(4.0f)),
      "water");
  const std::uint32_t rough = addMaterial(
      scene, withTransmission(makePbrMaterial(glm::vec3(0.9f, 1.0f, 0.9f), 0.0f, 0.3f), 1.0f, 1.5f, false, glm::vec3(0.0f)),
      "rough glass");
  const std::uint32_t block =
      addMaterial(scene, makeMaterial(glm::vec3(0.9f, 0.2f, 0.1f), glm::vec3(1.5f, 1.0f, 0.8f)), "glowing block");
  addBox(scene, {-1.4f, 0.02f, 0.3f}, {-0.5f, 0.6f, 1.1f}, glass);
  addBox(scene, {-1.3f, 0.1f, 0.4f}, {-1.0f, 0.4f, 0.9f}, block);
  addBox(scene, {-0.9f, 0.1f, 0.45f}, {-0.6f, 0.5f, 0.95f}, water);
  addBox(scene, {0.6f, 0.02f, 0.3f}, {1.3f, 0.5f, 1.0f}, rough);
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 5;
  settings.rrMinDepth = 1;
  settings.background = glm::vec3(0.2f, 0.25f, 0.3f);
  shadeLanesAgainstOnePath(scene, settings, 41, "glass");
}

// The same past false hits: a smooth glass slab (priority 1) between the
// camera and the floor holds four thin layers of a lower-priority medium, so
// a path through it passes eight false hits, which are no bounces
// (shared/media.h). Under 4 bounces the floor beyond the slab is lit only
// at the path's own bounce (2), not the wavefront pass (10): lanes that took
// the pass for the bounce would leave it dark. The slab's faces met from air
// and from inside with no false hit behind are the lanes' own glass; a bright
// sky over a dark floor makes its Fresnel reflection weigh.
TEST(QuadLights, ShadeLanesRenderGlassPastFalseHitsTheSameAsOnePathPerWorkItem) {
  Scene scene = quadLitScene();
  scene.materials[0] = makeMaterial(glm::vec3(0.15f));
  const std::uint32_t glass = addMaterial(
      scene, withPriority(withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.5f, false,
                                           glm::vec3(0.0f)), 1), "slab");
  const std::uint32_t layer = addMaterial(
      scene, withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.33f, false, glm::vec3(0.0f)),
      "layer");
  addBox(scene, {-2.5f, 0.8f, -0.5f}, {2.5f, 1.2f, 2.6f}, glass);
  for (float y : {0.85f, 0.93f, 1.01f, 1.09f}) addBox(scene, {-2.4f, y, -0.4f}, {2.4f, y + 0.02f, 2.5f}, layer);
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 4;
  settings.rrMinDepth = 1;
  settings.background = glm::vec3(1.0f, 1.1f, 1.2f);
  shadeLanesAgainstOnePath(scene, settings, 61, "glass past false hits");
}

// Shade's lanes at 16 wide (AVX-512's) and at 8 compute each path alike:
// the same image bit for bit, under a grey sky and under a black one (whose
// misses skip the emission loop). Every lane width takes the path state's
// rows whole (kernels/shade_lanes.cl's gather_rows and scatter_v), 16 lanes
// as two halves of 8. The glass scene above: Lambertian, metallic-roughness
// and glass on the lanes, paths handed to shade_path, rectangles, a point light.
TEST(QuadLights, ShadeLanesAt16WideRenderBitForBitAsAt8) {
  Scene scene = quadLitScene();
  scene.materials[0] = makePbrMaterial(glm::vec3(0.7f, 0.6f, 0.5f), 0.0f, 0.6f);
  const std::uint32_t glass = addMaterial(
      scene, withTransmission(makePbrMaterial(glm::vec3(1.0f), 0.0f, 0.0f), 1.0f, 1.5f, false, glm::vec3(0.5f, 1.5f, 3.0f)),
      "glass");
  const std::uint32_t metal = addMaterial(scene, makePbrMaterial(glm::vec3(0.9f, 0.6f, 0.5f), 1.0f, 0.3f), "metal");
  const std::uint32_t white = addMaterial(scene, makeMaterial(glm::vec3(0.8f)), "white");
  addBox(scene, {-1.4f, 0.02f, 0.3f}, {-0.5f, 0.6f, 1.1f}, glass);
  addBox(scene, {0.6f, 0.02f, 0.3f}, {1.3f, 0.5f, 1.0f}, metal);
  addRect(scene, {-2.0f, 0.0f, -1.2f}, {0.0f, 1.5f, 0.0f}, {4.0f, 0.0f, 0.0f}, white);
  PunctualLight point;
  point.position = glm::vec3(-1.0f, 1.2f, 1.0f);
  point.intensity = glm::vec3(0.6f, 0.8f, 1.0f);
  scene.lights.push_back(point);
  for (glm::vec3 sky : {glm::vec3(0.2f, 0.25f, 0.3f), glm::vec3(0.0f)}) {
    RenderSettings settings;
    settings.width = settings.height = 24;
    settings.maxBounces = 4;
    settings.rrMinDepth = 1;
    settings.seed = 71;
    settings.background = sky;
    settings.shadeLanesWidth = 8;
    const Image eight = test::render(scene, settings, 4);
    settings.shadeLanesWidth = 16;
    const Image sixteen = test::render(scene, settings, 4);
    ASSERT_EQ(eight.rgb.size(), sixteen.rgb.size());
    std::size_t differ = 0, lit = 0;
    for (std::size_t i = 0; i < eight.rgb.size(); ++i) {
      differ += eight.rgb[i] != sixteen.rgb[i];
      lit += eight.rgb[i] > 0.0f;
    }
    EXPECT_EQ(differ, 0u) << "sky " << sky.x;
    EXPECT_GT(lit, eight.rgb.size() / 2) << "sky " << sky.x;  // the comparison saw a lit image
  }
}

TEST(QuadLights, ShadeLanesWidthByDevice) {
  // 16 lanes where the device's float vector is 16 wide, 8 elsewhere; an
  // explicit 8 or 16 wins; anything else is refused
  DeviceInfo device;
  device.nativeFloatWidth = 16;
  EXPECT_EQ(shadeLanesWidthFor(device), 16);
  EXPECT_EQ(shadeLanesWidthFor(device, 8), 8);
  device.nativeFloatWidth = 8;
  EXPECT_EQ(shadeLanesWidthFor(device), 8);
  device.nativeFloatWidth = 1;
  EXPECT_EQ(shadeLanesWidthFor(device), 8);
  EXPECT_EQ(shadeLanesWidthFor(device, 16), 16);
  EXPECT_THROW(shadeLanesWidthFor(device, 4), DeviceError);
}

}  // namespace
}  // namespace wt
