// Instances of SDF grids and displaced meshes (WT_INSTANCE_PRIMITIVES,
// SceneBuffers::layoutPrimitiveInstances): a grid or a displaced mesh
// placed several times is stored once, in object space, the ray moved into
// each copy's. The instanced form against the flattened one
// (Instancing::Off): the same hits on rays at every copy in every traversal
// mode, any hit agreeing with closest hit, the same image within noise, and
// buffers that do not grow with the copies.
#include "../render/render_helpers.h"
#include "device/scene_buffers.h"
#include "device/tracer.h"
#include "device_fixture.h"
#include "geometry/primitives.h"
#include "instancing_checks.h"
#include "scene/generators.h"
#include "scene/sdf_volume.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <string>

namespace wt {
namespace {

using test::Placed;
using test::raysAtCopies;
using test::withInstancing;

/// One geometry: a torus of signed distances (24^3 cells, sparse) beside a
/// displaced icosphere (80 base triangles, level 3), about a unit across.
Scene surfaceGeometry() {
  Scene s = makeDisplacedSphere(1, glm::vec3(0.35f, 0.0f, 0.0f), 0.45f, 16, 0.12f, -0.06f, 3,
                                makeMaterial(glm::vec3(0.6f)));
  const SdfVolume torus = makeSdfShape(SdfShape::kTorus, SdfShapeParams{}, 24);
  SdfGrid grid;
  grid.cells = torus.cells;
  grid.values = torus.values;
  grid.storage = SdfStorage::kSparse;
  grid.latticeToScene = glm::translate(glm::dmat4(1.0), glm::dvec3(-0.5, 0.1, 0.0)) *
                        glm::scale(glm::dmat4(1.0), glm::dvec3(0.5)) * torus.latticeToObject();
  grid.material = 0;
  s.sdfGrids.push_back(std::move(grid));
  return s;
}

/// `copies` copies, turned and scaled uniformly, near and 1e4 from the
/// origin; copy 3 mirrored (its displaced mesh then stays flat: its corners
/// are swapped), and with `uneven` copy 2 scaled unevenly (an SDF grid
/// still, so instanced; its displaced mesh stays flat).
Placed placedSurfaces(int copies, bool uneven = false) {
  const Scene geometry = surfaceGeometry();
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> turn(-3.0f, 3.0f), size(0.5f, 1.5f);
  const glm::vec3 places[] = {{0, 0, 0}, {4, 0, 0}, {0, 4, 1}, {-4, -1, 0}, {1e4f, 0, 0}, {-1e4f, 2e3f, 5}};
  Placed out;
  std::vector<glm::mat4> transforms;
  for (int c = 0; c < copies; ++c) {
    const glm::vec3 at = places[c % 6] + glm::vec3(0.0f, 0.0f, 6.0f * float(c / 6));
    glm::mat4 m = glm::translate(glm::mat4(1.0f), at);
    m = glm::rotate(m, turn(rng), glm::normalize(glm::vec3(turn(rng), turn(rng), 1.0f)));
    const float k = size(rng);
    glm::vec3 axes(k);
    if (c == 3) axes.y = -k;
    if (uneven && c == 2) axes.x = 1.4f * k;
    transforms.push_back(glm::scale(m, axes));
    out.centres.push_back(at);
    out.scales.push_back(k);
  }
  out.scene = placeCopies(geometry, transforms);
  return out;
}

/// Every copy of the grid and of the displaced mesh becomes an instance with
/// Instancing::On (a mirrored displaced copy stays flat), none with Off; a
/// grid whose values differ in one bit from its geometry's stays flat.
TEST(SurfaceInstancing, CopiesBecomeInstances) {
  const Placed p = placedSurfaces(6, true);
  SceneBuffers on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  EXPECT_EQ(on.instanceCount(), 6u + 4u);  // grids: all six; displaced: not the mirrored or the uneven copy
  EXPECT_TRUE(on.primitivesInstanced());
  SceneBuffers off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  EXPECT_EQ(off.instanceCount(), 0u);
  Scene other = p.scene;
  other.sdfGrids[4].values[100] = std::nextafter(other.sdfGrids[4].values[100], 1e9f);
  SceneBuffers some(test::deviceContext(), other, withInstancing(Instancing::On));
  EXPECT_EQ(some.instanceCount(), 5u + 4u);
}

/// Memory: the buffers of 3 and of 12 instanced copies differ by the copies'
/// own rows (an instance's rows, id and share of a node, a grid's and a
/// mesh's header rows), while the flattened form grows by the geometry
/// itself per copy.
TEST(SurfaceInstancing, StoredOnce) {
  const Placed few = placedSurfaces(3), many = placedSurfaces(12);
  SceneBuffers onFew(test::deviceContext(), few.scene, withInstancing(Instancing::On));
  SceneBuffers onMany(test::deviceContext(), many.scene, withInstancing(Instancing::On));
  SceneBuffers offFew(test::deviceContext(), few.scene, withInstancing(Instancing::Off));
  SceneBuffers offMany(test::deviceContext(), many.scene, withInstancing(Instancing::Off));
  ASSERT_EQ(onFew.instanceCount(), 2u * 3u);
  ASSERT_EQ(onMany.instanceCount(), 2u * 12u - 1u);  // copy 3 is mirrored: its displaced mesh stays flat
  // per copy and type: 6 + 1 instance rows, a typed id, half a node, and a grid's 4 or a mesh's 2 header rows
  const double perCopy = 2.0 * (7 * 16 + 4 + 64) + (4 + 2) * 16;
  const double flatPerCopy = (double(offMany.primitiveBytes) - double(offFew.primitiveBytes)) / 9.0;
  // the mirrored copy's flat displaced mesh in `many`: less than one more copy's worth
  const double grown = double(onMany.primitiveBytes) - double(onFew.primitiveBytes);
  EXPECT_LT(grown, 9.0 * perCopy + flatPerCopy);
  EXPECT_GT(flatPerCopy, 10.0 * perCopy);
}

/// Instancing::Auto weighs a copied item by its own type's flattened bytes
/// (SceneBuffers::flatBytesPerPrimitive), not as a triangle: per type the
/// estimate is within 2x of what each flattened copy adds to the upload, so
/// 12 copies of a geometry whose copy takes a third of the cache are stored
/// once and 12 that fit are not (weighed as triangles, neither would be).
TEST(SurfaceInstancing, AutoWeighsEachTypesBytes) {
  for (const std::uint32_t type : {WT_PRIM_SDF_GRID, WT_PRIM_DISPLACED}) {
    SCOPED_TRACE(primTypeName(type));
    Scene geometry = surfaceGeometry();
    if (type == WT_PRIM_SDF_GRID) geometry.displacedMeshes.clear();
    else geometry.sdfGrids.clear();
    auto placed = [&](int copies) {
      std::vector<glm::mat4> transforms;
      for (int c = 0; c < copies; ++c)
        transforms.push_back(glm::translate(glm::mat4(1.0f), glm::vec3(3.0f * float(c), 0.0f, 0.0f)));
      return placeCopies(geometry, transforms);
    };
    const Scene few = placed(3), many = placed(12);
    const PrimitiveRows rows = gatherPrimitives(many);
    ASSERT_GT(rows.count[type], 0u);
    const double items = double(rows.count[type]) / 12.0;  // a copy's
    const double bytes = SceneBuffers::flatBytesPerPrimitive(rows)[type];
    const SceneBuffers offFew(test::deviceContext(), few, withInstancing(Instancing::Off));
    const SceneBuffers offMany(test::deviceContext(), many, withInstancing(Instancing::Off));
    const double copyBytes = (double(offMany.primitiveBytes) - double(offFew.primitiveBytes)) / 9.0;
    EXPECT_GT(items * bytes, 0.5 * copyBytes);
    EXPECT_LT(items * bytes, 2.0 * copyBytes);
    const double copied = 11.0 * items * bytes;
    EXPECT_TRUE(SceneBuffers::instancingPays(copied, std::uint64_t(3.0 * copyBytes)));
    EXPECT_FALSE(SceneBuffers::instancingPays(copied, std::uint64_t(20.0 * copyBytes)));
  }
}

/// Closest and any hits, in every traversal mode: the instanced form against
/// the flattened one, on rays at every copy (mirrored, unevenly scaled and
/// 1e4 away included): the same flattened primitive (brick or base
/// triangle, by its scene id) at t within the float rounding of the copy's
/// placement. A ray that grazes a silhouette may go either way: at most
/// one in 200. Any hits agree with closest hits of the same traversal.
TEST(SurfaceInstancing, HitsMatchTheFlattenedScene) {
  const Placed p = placedSurfaces(6, true);
  const std::vector<Ray> rays = raysAtCopies(p, 0.7f, test::testSize(600, 200), 11);
  Tracer on(test::deviceContext(), p.scene, withInstancing(Instancing::On));
  Tracer off(test::deviceContext(), p.scene, withInstancing(Instancing::Off));
  ASSERT_EQ(on.sceneBuffers().instanceCount(), 10u);
  const std::vector<RayHit> flat = off.traceClosest(rays);
  int flatHits = 0;
  for (const RayHit& h : flat) flatHits += h.prim != RayHit::kNoHit;
  EXPECT_GT(flatHits, int(rays.size() / 3));
  for (Traversal traversal : {Traversal::kSingle, Traversal::kPacket}) {
    SCOPED_TRACE(traversal == Traversal::kSingle ? "single" : "packet");
    const std::vector<RayHit> got = on.traceClosest(rays, traversal);
    int differ = 0, sdfHits = 0, displacedHits = 0;
    std::string differences;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      if (got[i].instance != RayHit::kNoHit) {
        sdfHits += primType(got[i].prim) == WT_PRIM_SDF_GRID;
        displacedHits += primType(got[i].prim) == WT_PRIM_DISPLACED;
      }
      const double magnitude = 1.0 + std::max({std::abs(rays[i].origin.x), std::abs(rays[i].origin.y),
                                               std::abs(rays[i].origin.z)});
      const double tol = 4e-6 * (magnitude + (flat[i].prim != RayHit::kNoHit ? flat[i].t : 0.0));
      const bool same = got[i].prim == flat[i].prim &&
                        (got[i].prim == RayHit::kNoHit || std::abs(got[i].t - flat[i].t) <= tol);
      const bool tie = got[i].prim != RayHit::kNoHit && flat[i].prim != RayHit::kNoHit &&
                       std::abs(got[i].t - flat[i].t) <= tol;  // two bricks or base triangles meeting at one point
      if (same || tie) continue;
      std::ostringstream line;
      line << "ray " << i << ": instanced prim " << std::hex << got[i].prim << std::dec << " t=" << got[i].t
           << " (instance " << got[i].instance << "), flattened prim " << std::hex << flat[i].prim << std::dec
           << " t=" << flat[i].t << "\n";
      if (++differ <= 5) differences += line.str();
    }
    EXPECT_LE(differ, int(rays.size() / 200)) << differences;
    EXPECT_GT(sdfHits, int(rays.size() / 20));
    EXPECT_GT(displacedHits, int(rays.size() / 20));
    for (Traversal any : {Traversal::kSingle, Traversal::kPacket, Traversal::kStream}) {
      const std::vector<std::uint8_t> blocked = on.traceOccluded(rays, any);
      int disagree = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) disagree += bool(blocked[i]) != (got[i].prim != RayHit::kNoHit);
      EXPECT_LE(disagree, int(rays.size() / 200)) << "any hit by traversal " << int(any);
    }
  }
}

/// The instanced and the flattened forms render the same image for a seed
/// within noise (the copies' floats differ in their last bits, and paths decorrelate).
TEST(SurfaceInstancing, RendersMatchTheFlattenedScene) {
  Placed p = placedSurfaces(4, true);
  const std::uint32_t light = std::uint32_t(p.scene.materials.size());
  p.scene.materials.push_back(makeMaterial(glm::vec3(0.0f), glm::vec3(8.0f), true));
  p.scene.materialNames.push_back("light");
  appendScene(p.scene, test::makeFloor(1.5f, 6.0f, p.scene.materials[light], true));
  CameraDesc camera;
  camera.cameraToWorld = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.0f, 11.0f), glm::vec3(0.0f, 1.0f, 0.0f),
                                                  glm::vec3(0, 1, 0)));
  camera.yfov = 0.9f;
  p.scene.camera = camera;
  RenderSettings settings;
  settings.width = settings.height = 32;
  settings.maxBounces = 3;
  settings.seed = 3;
  settings.background = glm::vec3(0.2f);
  settings.instancing = Instancing::Off;
  const Image flat = test::render(p.scene, settings, 48);
  settings.instancing = Instancing::On;
  const Image instanced = test::render(p.scene, settings, 48);
  test::expectSameImage(flat, instanced, 4, 4.5, "instanced SDF grids and displaced meshes against flattened");
}

}  // namespace
}  // namespace wt
