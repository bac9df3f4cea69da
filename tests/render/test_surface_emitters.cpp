// Displaced meshes and SDF grids as lights: each emitting base triangle and
// brick is an entry of the light list that next-event estimation samples
// (kernels/geometry/displaced.cl, sdf_grid.cl), and a BSDF ray that hits
// one weighs itself by the pdf NEE would have had. A bumpy emissive sheet
// and an emissive torus over a diffuse floor render the same image with
// NEE and MIS, with NEE alone (no MIS: light sampling must find all the
// light by itself), and with BSDF sampling alone (the reference).
#include "geometry/primitives.h"
#include "render/light_list.h"
#include "render/render_helpers.h"
#include "scene/sdf_volume.h"

#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <string>

namespace wt {
namespace {

/// A square sheet of two base triangles at height h, [-half, half]^2,
/// facing down (normals and winding), displaced down by a bumpy map.
DisplacedMesh bumpySheet(float h, float half, std::uint32_t material) {
  DisplacedMesh m;
  m.positions = {{-half, h, -half}, {half, h, -half}, {-half, h, half}, {half, h, half}};
  m.normals.assign(4, glm::vec3(0.0f, -1.0f, 0.0f));
  m.texcoords = {{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 1.0f}, {1.0f, 1.0f}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}};
  m.mapWidth = m.mapHeight = 16;
  for (std::uint32_t y = 0; y < 16; ++y)
    for (std::uint32_t x = 0; x < 16; ++x)
      m.map.push_back(float(0.5 + 0.5 * std::sin(0.9 * x) * std::cos(1.3 * y)));
  m.scale = 0.4f;  // bumps as tall as a fifth of the sheet: micro-triangles of very different areas
  m.offset = 0.0f;
  m.level = 3;
  m.material = material;
  return m;
}

/// A torus of ring radius 0.8 lying flat (axis y) at height h, `cells` per edge of its grid.
SdfGrid flatTorus(float h, std::uint32_t cells, std::uint32_t material) {
  SdfShapeParams params;
  params.radius = 0.6;
  params.minorRadius = 0.2;
  SdfVolume v = makeSdfShape(SdfShape::kTorus, params, cells);
  SdfGrid g;
  g.cells = v.cells;
  g.values = std::move(v.values);
  g.latticeToScene = glm::translate(glm::dmat4(1.0), glm::dvec3(0.0, h, 0.0)) * v.latticeToObject();
  g.material = material;
  return g;
}

/// A grey floor at y = 0 seen from the side, lit by what `addLight` adds.
Scene floorScene(const std::function<void(Scene&)>& addLight) {
  Scene s = test::makeFloor(3.0f, 0.0f, makeMaterial(glm::vec3(0.5f)));
  addLight(s);
  CameraDesc camera;
  camera.cameraToWorld =
      glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.2f, 3.5f), glm::vec3(0.0f, 0.3f, 0.0f), glm::vec3(0, 1, 0)));
  s.camera = camera;
  return s;
}

/// Renders `scene` three ways (NEE and MIS, NEE alone, BSDF sampling alone)
/// and compares the first two with the third block by block.
void expectNeeMatchesBsdfSampling(const Scene& scene, const std::string& what) {
  RenderSettings settings;
  settings.width = settings.height = 24;
  settings.maxBounces = 2;  // the floor's light and what the emitter's bumps send each other
  settings.seed = 7;
  settings.useNee = false;
  const Image bsdf = test::render(scene, settings, 512);
  settings.useNee = true;
  settings.seed = 8;
  const Image mis = test::render(scene, settings, 128);
  settings.useMis = false;
  settings.seed = 9;
  const Image nee = test::render(scene, settings, 128);
  test::expectSameImage(mis, bsdf, 4, 4.5, what + ": NEE and MIS against BSDF sampling");
  test::expectSameImage(nee, bsdf, 4, 4.5, what + ": NEE alone against BSDF sampling");
}

/// The light list's entries for `scene`'s primitives of `type`: each a light
/// whose emitter slot holds its selection probability.
std::size_t primitiveLightsOf(const Scene& scene, std::uint32_t type) {
  RenderSettings settings;
  settings.width = settings.height = 4;
  Renderer renderer(test::deviceContext(), scene, settings);
  const SceneBuffers& buffers = renderer.sceneBuffers();
  const LightList lights = buildLightList(scene, buffers, 0.0);
  std::size_t found = 0;
  for (std::size_t k = 0; k < lights.lights.size(); ++k) {
    const WtLight& l = lights.lights[k];
    if (l.type != WT_LIGHT_PRIMITIVE || primType(l.triangle) != type) continue;
    ++found;
    const std::size_t slot = buffers.geometry.emitter_first[type] + primIndex(l.triangle);
    EXPECT_GT(lights.emitterPdfArea.at(slot), 0.0f);
    EXPECT_EQ(lights.emitterPdfArea[slot], lights.alias[k].pmf);
  }
  return found;
}

TEST(SurfaceEmitters, DisplacedSheetIsSampledByNee) {
  const Scene scene = floorScene([](Scene& s) {
    s.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(4.0f, 3.0f, 2.0f)));
    s.materialNames.push_back("sheet");
    s.displacedMeshes.push_back(bumpySheet(1.2f, 0.6f, std::uint32_t(s.materials.size() - 1)));
  });
  EXPECT_EQ(primitiveLightsOf(scene, WT_PRIM_DISPLACED), 2u);
  expectNeeMatchesBsdfSampling(scene, "displaced sheet");
}

TEST(SurfaceEmitters, TwoSidedDisplacedSheetIsSampledByNee) {
  // tilted, so the floor sees both faces
  const Scene scene = floorScene([](Scene& s) {
    s.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(4.0f, 3.0f, 2.0f), true));
    s.materialNames.push_back("sheet");
    DisplacedMesh m = bumpySheet(0.0f, 0.5f, std::uint32_t(s.materials.size() - 1));
    const glm::mat3 tilt(glm::rotate(glm::mat4(1.0f), 1.2f, glm::vec3(0.0f, 0.0f, 1.0f)));
    for (glm::vec3& p : m.positions) p = tilt * p + glm::vec3(0.0f, 0.9f, 0.0f);
    for (glm::vec3& n : m.normals) n = tilt * n;
    s.displacedMeshes.push_back(std::move(m));
  });
  EXPECT_EQ(primitiveLightsOf(scene, WT_PRIM_DISPLACED), 2u);
  expectNeeMatchesBsdfSampling(scene, "two-sided displaced sheet");
}

TEST(SurfaceEmitters, SdfTorusIsSampledByNee) {
  const Scene scene = floorScene([](Scene& s) {
    s.materials.push_back(makeMaterial(glm::vec3(0.5f), glm::vec3(4.0f, 3.0f, 2.0f)));
    s.materialNames.push_back("torus");
    s.sdfGrids.push_back(flatTorus(0.8f, 32, std::uint32_t(s.materials.size() - 1)));
  });
  EXPECT_GT(primitiveLightsOf(scene, WT_PRIM_SDF_GRID), 8u);
  expectNeeMatchesBsdfSampling(scene, "SDF torus");
}

}  // namespace
}  // namespace wt
