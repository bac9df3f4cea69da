// Instances (WT_PRIM_INSTANCE, kernels/geometry/instance.cl): a geometry
// placed several times stored once, traced through its copies' transforms.
// The instanced form of a scene against its flattened form (every copy's
// triangles in world space, Instancing::Off): the same hits on random rays
// in every traversal mode, spawned rays that never meet the surface they
// leave, the same image for a seed, and the memory it saves.
#include "../render/render_helpers.h"
#include "attribute_grid.h"
#include "core/spawn.h"
#include "device/scene_buffers.h"
#include "device_fixture.h"
#include "instancing_checks.h"
#include "scene/generators.h"
#include "scene/gltf_loader.h"
#include "test_util.h"
#include "texture_helpers.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace wt {
namespace {

using test::hitsAgree;
using test::Placed;
using test::withInstancing;

/// Icospheres (1280 triangles each) turned, scaled unevenly, one mirrored,
/// moved near and far (1e4) from the origin, apart, with a soup of other
/// triangles around the first (`soup`; the mesh then loses a zero-area
/// triangle in every copy).
Placed placedIcospheres(bool soup = true) {
  Scene mesh = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.6f)));
  if (soup) mesh.triangles[7].v2 = mesh.triangles[7].v0;  // (a hole: the closed mesh tests go without)
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> turn(-3.0f, 3.0f), size(0.3f, 1.5f);
  const glm::vec3 places[] = {{0, 0, 0},    {4, 0, 0},       {0, 4, 1},     {-4, -1, 0}, {3.5f, 3.5f, -3},
                              {1e4f, 0, 0}, {-1e4f, 2e3f, 5}, {0, -4, -4}};
  Placed out;
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 8; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), places[c]);
    m = glm::rotate(m, turn(rng), glm::normalize(glm::vec3(turn(rng), turn(rng), 1.0f)));
    glm::vec3 s(size(rng), size(rng), size(rng));
    if (c == 3) s.y = -s.y;  // a mirror image
    transforms.push_back(glm::scale(m, s));
    out.centres.push_back(places[c]);
    out.scales.push_back(std::max({std::abs(s.x), std::abs(s.y), std::abs(s.z)}));
  }
  if (soup) out.scene = makeTriangleSoup(300, 9, 0.5f);
  appendScene(out.scene, placeCopies(mesh, transforms));
  return out;
}

/// Instancing::On stores the icosphere once with one instance per copy that
/// is not flattened; the soup stays flat.
TEST(Instancing, CopiesBecomeInstances) {
  // the uploaded buffers alone: a Tracer would also build a program these checks never run
  const Placed p = placedIcospheres();
  SceneBuffers on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  EXPECT_EQ(on.instanceCount(), 8u);
  EXPECT_EQ(on.instancedTriangles(), 8u * 1279u);
  SceneBuffers off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  EXPECT_EQ(off.instanceCount(), 0u);
  // Auto keeps a scene this small flat
  SceneBuffers automatic(test::deviceContext(), p.scene, withInstancing(Instancing::Auto));
  EXPECT_EQ(automatic.instanceCount(), 0u);
  // and stores copies once where their flattened form outgrows the cache
  constexpr double kTriangle = SceneBuffers::kFlatBytesPerTriangle;
  EXPECT_TRUE(SceneBuffers::instancingPays(double(1 << 20) * kTriangle, std::uint64_t(32) << 20));
  EXPECT_FALSE(SceneBuffers::instancingPays(double(1 << 20) * kTriangle, std::uint64_t(128) << 20));
  EXPECT_FALSE(SceneBuffers::instancingPays(7 * 1279 * kTriangle, 0));
}

/// The geometry is stored as the copy whose floats are finest for its size:
/// here the large copy 300 from the origin, not the tiny one (1e-5 of its
/// size) beside the origin, whose corners are a few float spacings apart
/// and would draw every copy with corners off by about 0.5 % of its size.
/// The large copy's instanced hits match its flattened ones within the
/// rounding of its own coordinates (the tiny one's flattened floats are too
/// coarse to compare with).
TEST(Instancing, TheStoredCopyIsTheFinestForItsSize) {
  const Scene mesh = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.6f)));
  Placed p;
  const glm::mat4 copies[] = {glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(1.0f, 0.5f, 0.0f)), glm::vec3(1e-5f)),
                              glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(300.0f, 0.0f, 0.0f)), 0.4f,
                                          glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f)))};
  p.scene = placeCopies(mesh, copies);
  p.centres = {glm::vec3(1.0f, 0.5f, 0.0f), glm::vec3(300.0f, 0.0f, 0.0f)};
  p.scales = {1e-5f, 1.0f};
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 2u);
  std::vector<Ray> rays = test::raysAtCopies(p, 0.8f, 4000, 13);
  rays.erase(rays.begin(), rays.begin() + 4000);  // the large copy's
  const std::vector<RayHit> flat = off.traceClosest(rays), got = on.traceClosest(rays);
  int bad = 0, edges = 0, hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    hits += flat[i].triangle != RayHit::kNoHit;
    if (!hitsAgree(p.scene, rays[i], got[i], flat[i], &edges) && ++bad <= 5)
      ADD_FAILURE() << "ray " << i << ": instanced t=" << got[i].t << ", flattened t=" << flat[i].t;
  }
  EXPECT_EQ(bad, 0);
  EXPECT_GT(hits, int(rays.size() / 2));
  EXPECT_LT(edges, int(rays.size() / 100));
}

/// Closest hits, any hits, in every traversal mode: the instanced form
/// against the flattened one, on rays aimed at every copy (the mirrored one
/// and those 1e4 from the origin included) and random rays through the rest.
TEST(Instancing, HitsMatchTheFlattenedScene) {
  const Placed p = placedIcospheres();
  std::vector<Ray> rays = test::raysAtCopies(p, 0.8f, 600, 11);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  ASSERT_GT(on.sceneBuffers().instanceCount(), 0u);
  const std::vector<RayHit> flat = off.traceClosest(rays);
  const std::vector<std::uint8_t> flatBlocked = off.traceOccluded(rays);
  int flatHits = 0;
  for (const RayHit& h : flat) flatHits += h.triangle != RayHit::kNoHit;
  EXPECT_GT(flatHits, int(rays.size() / 2));
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    SCOPED_TRACE(traversal == Traversal::kSingle ? "single" : "packet");
    const std::vector<RayHit> got = on.traceClosest(rays, traversal);
    int bad = 0, edges = 0, instanceHits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      instanceHits += got[i].instance != RayHit::kNoHit;
      if (!hitsAgree(p.scene, rays[i], got[i], flat[i], &edges) && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << ": instanced triangle " << got[i].triangle << " t=" << got[i].t
                      << " (instance " << got[i].instance << "), flattened triangle " << flat[i].triangle
                      << " t=" << flat[i].t;
      // the same scene triangle: the barycentrics too (b1, b2 swapped back on the mirrored copy),
      // within the flattened floats' rounding relative to the triangle's size
      if (got[i].triangle != flat[i].triangle || got[i].triangle == RayHit::kNoHit) continue;
      const WtTriangle& tri = p.scene.triangles[got[i].triangle];
      const WtVec4 &a = p.scene.positions[tri.v0], &b = p.scene.positions[tri.v1];
      const double edge = std::hypot(b.x - a.x, b.y - a.y, b.z - a.z);
      const double magnitude = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z), 1.0f});
      const double tolB = 1e-4 + 4e-7 * magnitude / edge;
      if ((std::abs(got[i].b1 - flat[i].b1) > tolB || std::abs(got[i].b2 - flat[i].b2) > tolB) && ++bad <= 5)
        ADD_FAILURE() << "ray " << i << ": barycentrics (" << got[i].b1 << ", " << got[i].b2 << ") against ("
                      << flat[i].b1 << ", " << flat[i].b2 << ")";
    }
    EXPECT_EQ(bad, 0);
    EXPECT_LT(edges, int(rays.size() / 100));
    EXPECT_GT(instanceHits, int(rays.size() / 3));
  }
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
    const std::vector<std::uint8_t> blocked = on.traceOccluded(rays, traversal);
    // differences only where a ray grazes an edge, as the closest hits' (a few in 1e3 at most)
    int differ = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) differ += blocked[i] != flatBlocked[i];
    EXPECT_LT(differ, int(rays.size() / 200)) << "traversal " << int(traversal);
  }
}

/// Rays spawned off instanced surfaces (the point from the copy's
/// triangle, pushed past its error bound, skipping that triangle on that
/// copy): outwards they never meet their own convex copy, inwards they meet
/// its far side, never the surface they leave; in every copy, mirrored and
/// far ones included.
TEST(Instancing, SpawnedRaysLeaveTheirSurface) {
  const Placed p = placedIcospheres(false);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  std::vector<Ray> rays = test::raysAtCopies(p, 0.8f, 400, 23);
  for (Ray& r : rays) r.tmin = 0.0f, r.tmax = 1e30f;
  const std::vector<RayHit> hits = on.traceClosest(rays);
  std::vector<Ray> outward, inward;
  std::vector<std::uint32_t> copyOf;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const RayHit& h = hits[i];
    if (h.instance == RayHit::kNoHit) continue;
    const WtTriangle& t = p.scene.triangles[h.triangle];
    auto pos = [&](std::uint32_t v) { return glm::vec3(p.scene.positions[v].x, p.scene.positions[v].y, p.scene.positions[v].z); };
    glm::vec3 error;
    const glm::vec3 point = trianglePoint(pos(t.v0), pos(t.v1), pos(t.v2), h.b1, h.b2, &error);
    // The host knows the flattened floats only, and placeCopies made them
    // with float matrices (each corner rounded on its own, up to a few ulps
    // of |p|); the instanced copy is its geometry moved by other float
    // matrices. Push past both, 32 ulps of |p| (the renderer's own spawns,
    // from the instanced surface, are tested by InstancedWhiteIcosphereInUniformSky).
    error += 32.0f * 5.96e-8f * (glm::abs(point) + glm::vec3(1.0f));
    // the outward normal of the copy (the winding's: corners swapped on the mirror)
    const glm::vec3 n = glm::normalize(glm::cross(pos(t.v1) - pos(t.v0), pos(t.v2) - pos(t.v0)));
    Ray out;
    out.origin = offsetRayOrigin(point, error, n);
    out.direction = glm::normalize(n + 0.9f * glm::normalize(rays[i].direction - n * glm::dot(rays[i].direction, n) +
                                                               glm::vec3(1e-3f)));
    out.skip = h.triangle;
    outward.push_back(out);
    Ray in = out;
    in.origin = offsetRayOrigin(point, error, -n);
    in.direction = -out.direction;
    inward.push_back(in);
  }
  ASSERT_GT(outward.size(), rays.size() / 2);
  const std::vector<RayHit> outHits = on.traceClosest(outward);
  const std::vector<RayHit> inHits = on.traceClosest(inward);
  int selfOut = 0, selfIn = 0, missedIn = 0;
  for (std::size_t i = 0; i < outward.size(); ++i) {
    const std::uint32_t instance = on.sceneBuffers().triangleInstance(outward[i].skip);
    if (outHits[i].instance == instance && ++selfOut <= 5)
      ADD_FAILURE() << "outward ray " << i << " from scene triangle " << outward[i].skip << " met triangle "
                    << outHits[i].triangle << " of its own copy at t=" << outHits[i].t;
    if (inHits[i].triangle == inward[i].skip) ++selfIn;
    if (inHits[i].instance != instance && ++missedIn <= 5)
      ADD_FAILURE() << "inward ray " << i << " from scene triangle " << inward[i].skip << " met triangle "
                    << inHits[i].triangle << " of instance " << inHits[i].instance << " at t=" << inHits[i].t;
  }
  EXPECT_EQ(selfOut, 0);
  EXPECT_EQ(selfIn, 0);
  EXPECT_EQ(missedIn, 0);
  // shadow rays towards a point beyond the copy: never blocked by the surface they leave
  for (Ray& r : outward) r.tmax = 0.05f;
  const std::vector<std::uint8_t> blocked = on.traceOccluded(outward, Traversal::kStream);
  int blockedCount = 0;
  for (std::uint8_t b : blocked) blockedCount += b;
  EXPECT_EQ(blockedCount, 0);
}

/// The instanced and the flattened forms of one scene give the same image
/// for a seed within noise. Not bit for bit: the instanced copies are their
/// geometry moved by float matrices, so points, normals and hence the
/// paths' directions differ in the last bits and the paths decorrelate.
TEST(Instancing, RendersMatchTheFlattenedScene) {
  Placed p = placedIcospheres();
  // a light above the near copies
  const std::uint32_t light = std::uint32_t(p.scene.materials.size());
  p.scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f), true));
  p.scene.materialNames.push_back("light");
  appendScene(p.scene, test::makeFloor(1.5f, 6.0f, p.scene.materials[light], true));
  CameraDesc camera;
  camera.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.5f, 1.0f, 12.0f), glm::vec3(0.0f), glm::vec3(0, 1, 0)));
  camera.yfov = 0.9f;
  p.scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = 48;
  settings.maxBounces = 4;
  settings.seed = 3;
  settings.background = glm::vec3(0.2f);
  // the floor light sampled as triangles: the instanced render's program is then
  // InstancedWhiteIcosphereInUniformSky's, compiled once in the suite (quad lights are not what this compares)
  settings.quadLights = false;
  settings.instancing = Instancing::Off;
  const Image flat = test::render(p.scene, settings, 64);
  settings.instancing = Instancing::On;
  const Image instanced = test::render(p.scene, settings, 64);
  test::expectSameImage(flat, instanced, 6, 4.5, "instanced against flattened");
}

/// attributeGridDoc's grid (8 x 8 cells) loaded from a file, placed by `placements` as `layout` says.
Scene loadAttributeGrid(std::span<const test::Placement> placements, test::GridLayout layout, const std::string& name) {
  const std::filesystem::path path = test::scratchDir("instancing") / (name + ".gltf");
  const std::string text = test::attributeGridDoc(8, placements, layout).embedded();
  std::ofstream(path, std::ios::binary).write(text.data(), std::streamsize(text.size()));
  GltfLoadOptions options;
  options.recenter = false;
  return loadGltf(path.string(), options);
}

/// Material 0 reads a 4 x 4 base colour texture (sRGB, TEXCOORD_0) and a
/// 4 x 4 normal map tilted a different way per texel (TEXCOORD_1), both nearest.
void addGridTextures(Scene& scene) {
  DecodedImage colour, normal;
  colour.width = colour.height = normal.width = normal.height = 4;
  colour.name = "colour", normal.name = "normal";
  for (int i = 0; i < 16; ++i) {
    for (int c : {255 - 9 * i, 90 + 10 * i, 60 + 12 * ((7 * i) % 16), 255}) colour.rgba8.push_back(std::uint8_t(c));
    const float a = 0.9f * float(i), x = 0.55f * std::cos(a), y = 0.55f * std::sin(a);
    for (float c : {x, y, std::sqrt(1.0f - x * x - y * y)}) normal.rgba8.push_back(std::uint8_t(std::lround(127.5f * (c + 1.0f))));
    normal.rgba8.push_back(255);
  }
  const std::uint32_t colourTexture = scene.textures.addTexture(scene.textures.addImage(colour, true), -1, -1,
                                                                test::kNearest, test::kNearest);
  const std::uint32_t normalTexture = scene.textures.addTexture(scene.textures.addImage(normal, false), -1, -1,
                                                                test::kNearest, test::kNearest);
  test::setBaseColorTexture(scene, 0, colourTexture);
  test::setMaterialTexture(scene, 0, WT_TEXTURE_SLOT_NORMAL, normalTexture);
  scene.materialTextures[WT_TEXTURE_SLOT_NORMAL].texcoord = 1;
}

/// A glTF mesh with vertex colours, a second set of texture coordinates and
/// tangents from the file, textured (base colour on the first set, a normal
/// map on the second), placed four times by nodes sharing it (turned;
/// turned, scaled and mirrored; two out of view), all stored once, renders
/// as the same mesh placed by placeCopies with the two copies in view each a
/// geometry of its own (flattened; the two out of view stay instanced, so
/// both scenes build one program): same seed, directional light, one
/// bounce, so each sample is a function of where it meets the surface and
/// the images differ by float rounding. Fails where a copy loses or misplaces
/// a vertex attribute (placeCopies, the loader, or the instance's tangent
/// and bitangent side in shade).
TEST(Instancing, CopiesKeepTheirVertexColoursSecondCoordinatesAndTangents) {
  const test::Placement placements[] = {
      {{-1.6f, 0.0f, 0.1f}, glm::angleAxis(0.5f, glm::vec3(0.0f, 1.0f, 0.0f)), {1.0f, 1.0f, 1.0f}},
      {{1.6f, 0.0f, -0.1f}, glm::angleAxis(-0.8f, glm::vec3(0.0f, 1.0f, 0.0f)), {1.2f, 1.0f, -0.8f}},
      {{-30.0f, 0.0f, 0.0f}},
      {{30.0f, 0.0f, 0.0f}}};
  Scene instanced = loadAttributeGrid(placements, test::GridLayout::kNodesShareAMesh, "shared");
  addGridTextures(instanced);
  const test::Placement identity;
  Scene mesh = loadAttributeGrid(std::span(&identity, 1), test::GridLayout::kNodesShareAMesh, "alone");
  addGridTextures(mesh);
  std::vector<glm::mat4> transforms;
  for (const test::Placement& p : placements) transforms.push_back(p.matrix());
  Scene flat = placeCopies(mesh, transforms);
  ASSERT_EQ(flat.instances.size(), 4u);
  flat.instances[0].geometry = 1, flat.instances[1].geometry = 2;
  for (Scene* scene : {&instanced, &flat}) {
    PunctualLight light;
    light.type = WT_LIGHT_DIRECTIONAL;
    light.direction = glm::normalize(glm::vec3(0.6f, -1.0f, 0.35f));
    light.intensity = glm::vec3(3.0f);
    scene->lights.push_back(light);
    scene->camera = test::topDownCamera(glm::vec3(0.0f, 5.0f, 0.0f), 3.2f);
  }
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 1;
  settings.seed = 3;
  settings.instancing = Instancing::On;
  const auto renderOf = [&](const Scene& scene, std::uint32_t instances) {
    Renderer renderer(test::deviceContext(), scene, settings);
    EXPECT_EQ(renderer.sceneBuffers().instanceCount(), instances);
    for (int s = 0; s < 8; ++s) renderer.renderSample();
    EXPECT_EQ(renderer.stats().nonFiniteSamples, 0u);
    return renderer.readImage();
  };
  const Image one = renderOf(instanced, 4), other = renderOf(flat, 2);
  test::expectSameImage(one, other, 4, 4.5, "stored once against written out per copy");
}

/// Memory: 98 copies of a geometry stored once take about 1/98 of the
/// flattened form's triangle bytes, plus the instances' rows and tree.
TEST(Instancing, StoredOnce) {
  // the uploaded buffers alone: a Tracer would also build a program these checks never run
  const Scene mesh = makeIcosphere(4, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(0.5f)));  // 5120 triangles
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 98; ++c)
    transforms.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(3.0f * float(c % 14), 3.0f * float(c / 14), 0)));
  const Scene scene = placeCopies(mesh, transforms);
  SceneBuffers on(test::deviceContext(), scene, withInstancing(Instancing::On));
  SceneBuffers off(test::deviceContext(), scene, withInstancing(Instancing::Off));
  const double ratio = double(on.triangleBytes()) / double(off.triangleBytes());
  // per instance: 6 rows of 16 bytes, an info row, a typed id and its share of a node
  const double overhead = 98.0 * (7 * 16 + 4 + 128.0 / 2) / double(off.triangleBytes());
  EXPECT_LT(ratio, 1.0 / 98.0 * 1.1 + overhead);
  EXPECT_GT(ratio, 1.0 / 98.0 * 0.9);
}

/// A white convex copy (geometric normals) in a uniform sky returns the sky
/// exactly: a bounce ray or shadow ray that met the surface it leaves, on
/// the instanced surface the renderer computes (kernels/geometry/
/// instance.cl), would darken its pixel. The mirrored copy and copies 1e4
/// from the origin, alone in view; the others far away.
TEST(Instancing, InstancedWhiteIcosphereInUniformSky) {
  Scene mesh = makeIcosphere(3, glm::vec3(0.0f), 1.0f, makeMaterial(glm::vec3(1.0f)));
  for (WtVec4& n : mesh.normals) n = {0.0f, 0.0f, 0.0f, 0.0f};
  const glm::vec3 places[] = {{0, 0, 0}, {1e4f, 0, 0}, {-1e4f, 2e3f, 5}, {0, 3e3f, 0}};
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < 4; ++c) {
    glm::mat4 m = glm::translate(glm::mat4(1.0f), places[c]);
    m = glm::rotate(m, 0.7f * float(c + 1), glm::normalize(glm::vec3(1.0f, 2.0f, float(c))));
    transforms.push_back(glm::scale(m, c == 3 ? glm::vec3(1.0f, -0.6f, 1.3f) : glm::vec3(1.2f, 0.8f, 1.0f)));
  }
  Scene scene = placeCopies(mesh, transforms);
  RenderSettings settings;
  settings.width = settings.height = 24;
  settings.maxBounces = 1;
  settings.background = glm::vec3(0.5f, 1.0f, 2.0f);
  settings.seed = 3;
  settings.instancing = Instancing::On;
  for (int c : {1, 2, 3}) {
    SCOPED_TRACE("copy " + std::to_string(c));
    CameraDesc camera;
    camera.cameraToWorld = glm::translate(glm::mat4(1.0f), places[c] + glm::vec3(0.0f, 0.0f, 4.0f));
    scene.camera = camera;
    for (bool packets : {true, false}) {
      settings.packets = packets;
      test::expectUniform(test::render(scene, settings, 32), glm::dvec3(0.5, 1.0, 2.0), 1e-5, 5.0,
                          "white instanced icosphere in a uniform sky");
    }
  }
}

}  // namespace
}  // namespace wt
