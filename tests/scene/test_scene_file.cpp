// Scene file (.json) tests on files the tests write themselves: spheres,
// materials, camera and settings read back; glTF files placed by transforms
// checked numerically; recentring far from the world origin; every error
// checked for the file and the JSON path it names; mutated files never crash.
#include "geometry/primitives.h"
#include "core/embedded.h"
#include "output/image_io.h"
#include "scene/default_scene.h"
#include "scene/gltf_doc.h"
#include "scene/scene_file.h"

#include "test_util.h"

#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <regex>
#include <string>
#include <vector>

namespace wt {
namespace {

namespace fs = std::filesystem;
using namespace gltf_doc;

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

/// A scratch folder named after the running test, so parallel tests never share one.
fs::path testDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : name)
    if (c == '/') c = '_';
  fs::path dir = test::scratchDir("scene_file") / name;
  fs::create_directories(dir);
  return dir;
}

fs::path writeFile(const fs::path& path, const std::string& contents) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary).write(contents.data(), std::streamsize(contents.size()));
  return path;
}

/// The scene file `scene.json` in the test's folder.
SceneFile loadText(const std::string& json, const GltfLoadOptions& options = {}) {
  return loadSceneFile(writeFile(testDir() / "scene.json", json).string(), options);
}

/// The SceneError of loading `json` as scene.json; it must start with the file's name.
std::string errorOf(const std::string& json, const GltfLoadOptions& options = {}) {
  try {
    loadText(json, options);
  } catch (const SceneError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("scene.json: ", 0), 0u) << "message does not start with the file name: " << message;
    return message;
  }
  ADD_FAILURE() << "expected a SceneError for " << json;
  return "";
}

/// A scene file with these top-level members besides the version.
std::string doc(const std::string& members) { return "{\"version\": 1" + (members.empty() ? "" : ", " + members) + "}"; }

glm::dvec3 worldPosition(const Scene& s, std::uint32_t v) {
  return s.origin + glm::dvec3(s.positions[v].x, s.positions[v].y, s.positions[v].z);
}
glm::dvec3 cameraPosition(const Scene& s) { return s.origin + glm::dvec3(s.camera->cameraToWorld[3]); }
glm::vec3 normal(const Scene& s, std::uint32_t v) { return {s.normals[v].x, s.normals[v].y, s.normals[v].z}; }

void expectNear(const glm::dvec3& actual, const glm::dvec3& expected, double eps = 1e-5) {
  EXPECT_NEAR(actual.x, expected.x, eps);
  EXPECT_NEAR(actual.y, expected.y, eps);
  EXPECT_NEAR(actual.z, expected.z, eps);
}

void expectConsistent(const Scene& s) {
  ASSERT_EQ(s.normals.size(), s.positions.size());
  ASSERT_EQ(s.texcoords.size(), s.positions.size());
  ASSERT_FALSE(s.materials.empty());
  ASSERT_EQ(s.materialNames.size(), s.materials.size());
  for (const WtTriangle& t : s.triangles) {
    ASSERT_LT(std::max({t.v0, t.v1, t.v2}), s.positions.size());
    ASSERT_LT(t.material, s.materials.size());
  }
  for (const Sphere& sphere : s.spheres) {
    ASSERT_LT(sphere.material, s.materials.size());
    ASSERT_GT(sphere.radius, 0.0f);
  }
  std::uint32_t end = 0;
  for (const GeometryInstance& copy : s.instances) {
    ASSERT_GE(copy.firstTriangle, end);  // in triangle order, not overlapping
    end = copy.firstTriangle + copy.triangleCount;
  }
  ASSERT_LE(end, s.triangles.size());
}

/// One triangle in the z = 0 plane, counter-clockwise seen from +z, with
/// normals +z and one material "tri"; optionally a camera node and a light.
GltfDoc triangleDoc(const std::string& moreNodes = "") {
  GltfDoc doc;
  const int pos = doc.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const int nrm = doc.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(pos)) + ",\"NORMAL\":" + str(std::size_t(nrm)) +
              "},\"material\":0}");
  doc.materials.push_back("{\"name\":\"tri\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.2,0.4,0.6,1]}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0" + moreNodes + "]}");
  return doc;
}

/// triangle.gltf in the test's folder.
void writeTriangle(const GltfDoc& doc = triangleDoc(), const std::string& name = "triangle.gltf") {
  writeFile(testDir() / name, doc.embedded());
}

std::string gltfObject(const std::string& transform, const std::string& file = "triangle.gltf") {
  return "{\"type\": \"gltf\", \"file\": \"" + file + "\"" + (transform.empty() ? "" : ", \"transform\": " + transform) + "}";
}

// ---------------------------------------------------------------------------
// what a valid file gives

TEST(SceneFile, SpheresMaterialsAndCamera) {
  SceneFile f = loadText(doc(R"(
    "camera": {"from": [0, 1, 5], "to": [0, 1, 0], "fov": 30},
    "materials": {
      "red": {"base_color": [0.8, 0.1, 0.1], "roughness": 0.3},
      "lamp": {"type": "lambert", "base_color": [0, 0, 0], "emission": [1, 2, 3], "emission_strength": 10,
               "double_sided": true}
    },
    "objects": [
      {"type": "sphere", "center": [0, -1000, 0], "radius": 1000, "material": "red"},
      {"type": "sphere", "center": [0.5, 0.25, -2], "radius": 0.01, "material": "lamp"},
      {"type": "spheres", "centers": [[1, 0, 0], [2, 0, 0]], "radii": [0.5, 0.25], "material": "red"},
      {"type": "spheres", "centers": [[3, 0, 0]], "radius": 2}
    ])"));
  const Scene& s = f.scene;
  expectConsistent(s);
  EXPECT_TRUE(s.triangles.empty());
  // recentred on the camera
  EXPECT_EQ(s.origin, glm::dvec3(0, 1, 5));
  ASSERT_EQ(s.spheres.size(), 5u);
  expectNear(glm::dvec3(s.spheres[0].center), {0, -1001, -5});
  EXPECT_EQ(s.spheres[0].radius, 1000.0f);
  expectNear(glm::dvec3(s.spheres[1].center), {0.5, -0.75, -7});
  EXPECT_EQ(s.spheres[1].radius, 0.01f);
  EXPECT_EQ(s.spheres[2].radius, 0.5f);
  EXPECT_EQ(s.spheres[3].radius, 0.25f);
  EXPECT_EQ(s.spheres[4].radius, 2.0f);
  expectNear(s.origin + glm::dvec3(s.spheres[3].center), {2, 0, 0});

  // materials in file order, then the default the last object asked for
  ASSERT_EQ(s.materialNames, (std::vector<std::string>{"red", "lamp", "(default)"}));
  EXPECT_EQ(s.spheres[0].material, 0u);
  EXPECT_EQ(s.spheres[1].material, 1u);
  EXPECT_EQ(s.spheres[4].material, 2u);
  const WtMaterial& red = s.materials[0];
  EXPECT_EQ(red.model, WT_MATERIAL_PBR);
  EXPECT_FLOAT_EQ(red.base_color.x, 0.8f);
  EXPECT_FLOAT_EQ(red.base_color.w, 0.0f);  // metallic
  EXPECT_FLOAT_EQ(red.roughness, 0.3f);
  const WtMaterial& lamp = s.materials[1];
  EXPECT_EQ(lamp.model, WT_MATERIAL_DIFFUSE);
  EXPECT_FLOAT_EQ(lamp.emission.x, 10.0f);
  EXPECT_FLOAT_EQ(lamp.emission.z, 30.0f);
  EXPECT_FLOAT_EQ(lamp.emission.w, 1.0f);  // double-sided
  const WtMaterial& fallback = s.materials[2];
  EXPECT_EQ(fallback.model, WT_MATERIAL_PBR);
  EXPECT_FLOAT_EQ(fallback.base_color.y, 0.8f);
  EXPECT_FLOAT_EQ(fallback.roughness, 0.5f);

  ASSERT_TRUE(s.camera.has_value());
  EXPECT_FLOAT_EQ(s.camera->yfov, glm::radians(30.0f));
  expectNear(cameraPosition(s), {0, 1, 5});
  // looks down -Z of the camera, towards `to`, +Y up
  expectNear(glm::dvec3(-s.camera->cameraToWorld[2]), {0, 0, -1});
  expectNear(glm::dvec3(s.camera->cameraToWorld[1]), {0, 1, 0});
  EXPECT_FALSE(f.settings.environment.has_value());
  EXPECT_FALSE(f.settings.width.has_value());
}

TEST(SceneFile, CameraDefaultsAndOrientation) {
  SceneFile f = loadText(doc(R"("camera": {"from": [3, 0, 0], "to": [0, 0, 0]})"));
  ASSERT_TRUE(f.scene.camera.has_value());
  EXPECT_FLOAT_EQ(f.scene.camera->yfov, glm::radians(45.0f));
  const glm::mat4& m = f.scene.camera->cameraToWorld;
  expectNear(glm::dvec3(-m[2]), {-1, 0, 0});
  expectNear(glm::dvec3(m[1]), {0, 1, 0});
  expectNear(glm::dvec3(m[0]), {0, 0, -1});  // right = forward x up
  // a tilted up vector is made orthogonal to the view
  f = loadText(doc(R"("camera": {"from": [0, 0, 0], "to": [0, 0, -1], "up": [1, 1, 0]})"));
  expectNear(glm::dvec3(f.scene.camera->cameraToWorld[1]), {std::sqrt(0.5), std::sqrt(0.5), 0});
  // no camera: the renderer frames the bounds; the origin is their centre
  f = loadText(doc(R"("objects": [{"type": "sphere", "center": [10, 0, 0], "radius": 1}])"));
  EXPECT_FALSE(f.scene.camera.has_value());
  EXPECT_EQ(f.scene.origin, glm::dvec3(10, 0, 0));
  EXPECT_EQ(f.scene.spheres[0].center, glm::vec3(0.0f));
}

TEST(SceneFile, TransmissionAndAttenuation) {
  SceneFile f = loadText(doc(R"("materials": {
      "glass": {"base_color": [1, 1, 1], "roughness": 0, "transmission": 1, "ior": 1.33,
                "attenuation_color": [0.5, 1, 0.25], "attenuation_distance": 2},
      "sheet": {"transmission": 0.5, "thin_walled": true},
      "gold": {"base_color": [1, 0.8, 0.3], "metallic": 1, "roughness": 0.1, "ior": 2}
    })"));
  const Scene& s = f.scene;
  const WtMaterial& glass = s.materials[0];
  EXPECT_FLOAT_EQ(glass.transmission, 1.0f);
  EXPECT_FLOAT_EQ(glass.ior, 1.33f);
  EXPECT_FLOAT_EQ(glass.volume.w, 1.0f);  // a volume boundary
  EXPECT_NEAR(glass.volume.x, -std::log(0.5) / 2.0, 1e-6);
  EXPECT_NEAR(glass.volume.y, 0.0, 1e-6);
  EXPECT_NEAR(glass.volume.z, -std::log(0.25) / 2.0, 1e-6);
  const WtMaterial& sheet = s.materials[1];
  EXPECT_FLOAT_EQ(sheet.transmission, 0.5f);
  EXPECT_FLOAT_EQ(sheet.volume.w, 0.0f);  // thin-walled
  // ior on a metal does nothing, and says so
  EXPECT_FLOAT_EQ(s.materials[2].transmission, 0.0f);
  bool warned = false;
  for (const std::string& w : s.warnings)
    warned |= w.find("materials.gold.ior has no effect on a metal") != std::string::npos;
  EXPECT_TRUE(warned);
}

// The nested-dielectric priority: 0 by default, a warning where it cannot matter.
TEST(SceneFile, NestedPriority) {
  SceneFile f = loadText(doc(R"("materials": {
      "glass": {"transmission": 1, "priority": 3},
      "water": {"transmission": 1, "ior": 1.33},
      "sheet": {"transmission": 1, "thin_walled": true, "priority": 2},
      "paint": {"priority": 1}
    })"));
  const Scene& s = f.scene;
  EXPECT_EQ(s.materials[0].priority, 3u);
  EXPECT_EQ(s.materials[1].priority, 0u);
  int warned = 0;
  for (const std::string& w : s.warnings)
    warned += w.find("materials.sheet.priority has no effect on a thin-walled material") != std::string::npos ||
              w.find("materials.paint.priority has no effect without transmission") != std::string::npos;
  EXPECT_EQ(warned, 2);
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"transmission": 1, "priority": 1.5}})")),
                  "materials.m.priority: must be an integer, got 1.5");
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"transmission": 1, "priority": -1}})")),
                  "materials.m.priority: must be an integer in [0, 2147483647], got -1");
}

// The layers: a weighted, tinted specular F0 (ior sets it without
// transmission too), a clear coat, a sheen; defaults where absent.
TEST(SceneFile, MaterialLayers) {
  SceneFile f = loadText(doc(R"("materials": {
      "velvet": {"base_color": [0.3, 0.1, 0.1], "specular": 0.5, "specular_color": [1, 0.5, 3], "ior": 1.8,
                 "clearcoat": 0.7, "clearcoat_roughness": 0.2, "sheen_color": [0.9, 0.4, 0.1], "sheen_roughness": 0.6},
      "plain": {},
      "wall": {"specular": 0}
    })"));
  const Scene& s = f.scene;
  const WtMaterial& v = s.materials[0];
  EXPECT_FLOAT_EQ(v.specular.w, 0.5f);
  EXPECT_FLOAT_EQ(v.specular.z, 3.0f);
  EXPECT_FLOAT_EQ(v.ior, 1.8f);
  EXPECT_FLOAT_EQ(v.clearcoat, 0.7f);
  EXPECT_FLOAT_EQ(v.clearcoat_roughness, 0.2f);
  EXPECT_FLOAT_EQ(v.sheen.x, 0.9f);
  EXPECT_FLOAT_EQ(v.sheen.w, 0.6f);
  const WtMaterial& p = s.materials[1];
  EXPECT_EQ(p.specular.w, 1.0f);
  EXPECT_EQ(p.specular.x, 1.0f);
  EXPECT_EQ(p.clearcoat, 0.0f);
  EXPECT_EQ(p.sheen.x, 0.0f);
  EXPECT_EQ(p.ior, 1.5f);
  EXPECT_EQ(s.materials[2].specular.w, 0.0f);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.at(0);
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"sheen_color": [2, 0, 0]}})")), "materials.m.sheen_color");
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"clearcoat": 1.5}})")), "materials.m.clearcoat: must be in [0, 1]");
  // KHR_materials_anisotropy's strength and rotation (a whole turn less, for the device's cos and sin)
  SceneFile a = loadText(doc(R"("materials": {"brushed": {"metallic": 1, "anisotropy": 0.6, "anisotropy_rotation": 7}})"));
  EXPECT_FLOAT_EQ(a.scene.materials[0].anisotropy, 0.6f);
  EXPECT_NEAR(a.scene.materials[0].anisotropy_rotation, 7.0f - 2.0f * float(M_PI), 1e-5f);
  EXPECT_EQ(p.anisotropy, 0.0f);
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"anisotropy": -0.1}})")), "materials.m.anisotropy: must be in [0, 1]");
  // KHR_materials_iridescence's factor, film index and thickness (defaults 0, 1.3, 400 nm)
  SceneFile film = loadText(doc(R"("materials": {"soap": {"iridescence": 0.9, "iridescence_ior": 1.6, "iridescence_thickness": 550}})"));
  EXPECT_FLOAT_EQ(film.scene.materials[0].iridescence.x, 0.9f);
  EXPECT_FLOAT_EQ(film.scene.materials[0].iridescence.y, 1.6f);
  EXPECT_FLOAT_EQ(film.scene.materials[0].iridescence.w, 550.0f);
  EXPECT_EQ(p.iridescence.x, 0.0f);
  EXPECT_FLOAT_EQ(p.iridescence.y, 1.3f);
  EXPECT_FLOAT_EQ(p.iridescence.w, 400.0f);
  EXPECT_CONTAINS(errorOf(doc(R"("materials": {"m": {"iridescence_ior": 0.5}})")), "materials.m.iridescence_ior: must be in [1, 10]");
}

TEST(SceneFile, AutoExposureWithAnOffset) {
  for (auto [text, stops] : {std::pair<const char*, float>{"auto", 0.0f}, {"auto+1.5", 1.5f}, {"auto-2", -2.0f}}) {
    SceneFile f = loadText(doc(std::string(R"("render": {"exposure": ")") + text + "\"}"));
    EXPECT_TRUE(f.settings.autoExposure) << text;
    EXPECT_EQ(f.settings.exposureStops, stops) << text;
  }
}

TEST(SceneFile, RenderSettingsAndEnvironment) {
  writeFile(testDir() / "maps" / "sky.hdr", "not read by the loader");
  SceneFile f = loadText(doc(R"(
    "render": {"width": 320, "height": 200, "spp": 16, "max_bounces": 3, "seed": 4000000000, "exposure": -1.5,
               "integrator": "minimal", "tonemap": "agx"},
    "environment": {"map": "maps/sky.hdr", "intensity": 2, "rotation": 90, "hidden": true})"));
  const SceneFileSettings& s = f.settings;
  EXPECT_EQ(s.width, 320);
  EXPECT_EQ(s.height, 200);
  EXPECT_EQ(s.samplesPerPixel, 16);
  EXPECT_EQ(s.maxBounces, 3);
  EXPECT_EQ(s.seed, 4000000000u);
  EXPECT_EQ(s.exposureStops, -1.5f);
  EXPECT_FALSE(s.autoExposure);
  EXPECT_EQ(s.integrator, "minimal");
  EXPECT_EQ(s.tonemap, "agx");
  ASSERT_TRUE(s.environment.has_value());
  EXPECT_FALSE(s.environment->color.has_value());
  // resolved against the scene file's folder
  EXPECT_EQ(fs::path(s.environment->map), (testDir() / "maps" / "sky.hdr").lexically_normal());
  EXPECT_EQ(s.environment->intensity, 2.0f);
  EXPECT_EQ(s.environment->rotationDegrees, 90.0f);
  EXPECT_TRUE(s.environment->hidden);

  f = loadText(doc(R"("environment": {"color": [0.1, 0.2, 0.3]})"));
  ASSERT_TRUE(f.settings.environment.has_value());
  EXPECT_EQ(f.settings.environment->color, glm::vec3(0.1f, 0.2f, 0.3f));
  EXPECT_TRUE(f.settings.environment->map.empty());
  EXPECT_FALSE(f.settings.environment->hidden);
}

TEST(SceneFile, LoadSceneDispatchesJson) {
  const fs::path path = writeFile(testDir() / "scene.json", doc(R"(
    "render": {"spp": 3},
    "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1}])"));
  EXPECT_EQ(loadScene(path.string()).spheres.size(), 1u);
  SceneFile f = loadSceneAny(path.string());
  EXPECT_EQ(f.settings.samplesPerPixel, 3);
  EXPECT_EQ(f.scene.sourceName, path.string());
  // glTF files and built-in scenes come without settings
  writeTriangle();
  f = loadSceneAny((testDir() / "triangle.gltf").string());
  EXPECT_EQ(f.scene.triangles.size(), 1u);
  EXPECT_FALSE(f.settings.samplesPerPixel.has_value());
  EXPECT_FALSE(loadSceneAny("cornell").settings.environment.has_value());
}

TEST(SceneFile, ExampleScenesLoad) {
  const fs::path scenes = wt::embedded::sourceDirectory() / "scenes";
  SceneFile spheres = loadSceneFile((scenes / "spheres.json").string());
  expectConsistent(spheres.scene);
  EXPECT_GE(spheres.scene.spheres.size(), 10u);
  EXPECT_TRUE(spheres.scene.camera.has_value());
  EXPECT_TRUE(spheres.scene.warnings.empty()) << spheres.scene.warnings.front();
  SceneFile mixed = loadSceneFile((scenes / "mixed.json").string());
  expectConsistent(mixed.scene);
  EXPECT_GT(mixed.scene.triangles.size(), 0u);
  EXPECT_GE(mixed.scene.spheres.size(), 4u);
  EXPECT_TRUE(mixed.scene.warnings.empty()) << mixed.scene.warnings.front();
  SceneFile tube = loadSceneFile((scenes / "glass_tube.json").string());
  expectConsistent(tube.scene);
  EXPECT_EQ(tube.scene.curves.size(), 1u);
  EXPECT_EQ(tube.scene.curves[0].pointCount, 25u);
  SceneFile instances = loadSceneFile((scenes / "instances.json").string());
  expectConsistent(instances.scene);
  EXPECT_EQ(instances.scene.primitiveInstances.size(), 14u + 24u);  // pebbles and grass tufts
  EXPECT_EQ(instances.scene.curves.size(), 24u * 31u);
  EXPECT_TRUE(instances.scene.warnings.empty()) << instances.scene.warnings.front();
  // the box is scaled by 10: its light hangs at y = 5.487
  float top = -1e30f;
  for (const WtVec4& p : mixed.scene.positions) top = std::max(top, p.y);
  EXPECT_NEAR(mixed.scene.origin.y + top, 5.488, 1e-3);
}

// The example in docs/scene-format.md is a valid file (its glTF file from scenes/).
TEST(SceneFile, DocumentedExampleLoads) {
  std::ifstream in(wt::embedded::sourceDirectory() / "docs" / "scene-format.md");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t start = text.find("```json\n");
  ASSERT_NE(start, std::string::npos);
  const std::size_t end = text.find("```", start + 8);
  ASSERT_NE(end, std::string::npos);
  const SceneFile f = loadSceneFileFromMemory(text.substr(start + 8, end - start - 8), "scene-format.md",
                                              (wt::embedded::sourceDirectory() / "scenes").string());
  expectConsistent(f.scene);
  EXPECT_GT(f.scene.triangles.size(), 0u);
  EXPECT_EQ(f.scene.spheres.size(), 4u);
  EXPECT_TRUE(f.scene.warnings.empty()) << f.scene.warnings.front();
  EXPECT_EQ(f.settings.samplesPerPixel, 64);
}

// ---------------------------------------------------------------------------
// glTF files placed by transforms

TEST(SceneFile, GltfIncludeIsPlacedByItsTransform) {
  writeTriangle();
  // translate * rotate (90 degrees about +z) * scale (2, 3, 1)
  SceneFile f = loadText(doc(R"("objects": [)" +
                             gltfObject(R"({"translate": [10, 20, 30], "rotate": [0, 0, 1, 90], "scale": [2, 3, 1]})") +
                             "]"));
  const Scene& s = f.scene;
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 1u);
  const WtTriangle& t = s.triangles[0];
  expectNear(worldPosition(s, t.v0), {10, 20, 30});
  expectNear(worldPosition(s, t.v1), {10, 22, 30});  // (1,0,0) -> (2,0,0) -> (0,2,0)
  expectNear(worldPosition(s, t.v2), {7, 20, 30});   // (0,1,0) -> (0,3,0) -> (-3,0,0)
  expectNear(glm::dvec3(normal(s, t.v0)), {0, 0, 1});
  // the glTF's material comes along, named as in the file
  ASSERT_EQ(s.materialNames, std::vector<std::string>{"tri"});
  EXPECT_EQ(t.material, 0u);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.y, 0.4f);
}

TEST(SceneFile, MatrixQuaternionAndRotateAgree) {
  writeTriangle();
  const glm::dmat4 expected = glm::translate(glm::dmat4(1.0), glm::dvec3(1, -2, 3)) *
                              glm::rotate(glm::dmat4(1.0), glm::radians(40.0), glm::normalize(glm::dvec3(1, 2, 3))) *
                              glm::scale(glm::dmat4(1.0), glm::dvec3(0.5, 2, -1.5));
  std::string matrix = "[";
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) {
      if (c + r > 0) matrix += ",";
      matrix += num(float(expected[c][r]));
    }
  const glm::dquat q = glm::angleAxis(glm::radians(40.0), glm::normalize(glm::dvec3(1, 2, 3)));
  const std::string quaternion = "[" + num(float(q.x)) + "," + num(float(q.y)) + "," + num(float(q.z)) + "," +
                                 num(float(q.w)) + "]";
  const std::vector<std::string> transforms = {
      R"({"matrix": )" + matrix + "]}",
      R"({"translate": [1, -2, 3], "quaternion": )" + quaternion + R"(, "scale": [0.5, 2, -1.5]})",
      R"({"translate": [1, -2, 3], "rotate": [1, 2, 3, 40], "scale": [0.5, 2, -1.5]})"};
  for (const std::string& transform : transforms) {
    SCOPED_TRACE(transform);
    const Scene s = loadText(doc(R"("objects": [)" + gltfObject(transform) + "]")).scene;
    ASSERT_EQ(s.triangles.size(), 1u);
    const glm::dvec3 corners[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    // the mirroring scale swaps two corners, keeping the front face the front face
    const WtTriangle& t = s.triangles[0];
    expectNear(worldPosition(s, t.v0), glm::dvec3(expected * glm::dvec4(corners[0], 1.0)));
    expectNear(worldPosition(s, t.v1), glm::dvec3(expected * glm::dvec4(corners[2], 1.0)));
    expectNear(worldPosition(s, t.v2), glm::dvec3(expected * glm::dvec4(corners[1], 1.0)));
    // normals by the inverse transpose, agreeing with the winding
    const glm::dvec3 n = glm::normalize(glm::transpose(glm::inverse(glm::dmat3(expected))) * glm::dvec3(0, 0, 1));
    expectNear(glm::dvec3(normal(s, t.v0)), n);
    const glm::dvec3 geometric = glm::cross(worldPosition(s, t.v1) - worldPosition(s, t.v0),
                                            worldPosition(s, t.v2) - worldPosition(s, t.v0));
    EXPECT_GT(glm::dot(geometric, n), 0.0);
  }
}

TEST(SceneFile, GltfCameraAndLightsArePlaced) {
  GltfDoc gltf = triangleDoc(",1,2");
  gltf.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.5,\"znear\":0.01}}");
  gltf.addNode("{\"camera\":0,\"translation\":[0,0,4]}");
  gltf.addNode("{\"translation\":[0,2,0],\"rotation\":[-0.7071068,0,0,0.7071068],"
               "\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");  // a spot pointing down
  gltf.extensionsUsed = "[\"KHR_lights_punctual\"]";
  gltf.extensions = "{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"spot\":{},\"intensity\":5}]}}";
  writeTriangle(gltf);
  const std::string transform = R"({"translate": [100, 0, 0], "rotate": [0, 1, 0, 90]})";
  SceneFile f = loadText(doc(R"("objects": [)" + gltfObject(transform) + "]"));
  const Scene& s = f.scene;
  expectConsistent(s);
  // the file's camera, placed: (0,0,4) turned 90 degrees about +y is (4,0,0)
  ASSERT_TRUE(s.camera.has_value());
  EXPECT_FLOAT_EQ(s.camera->yfov, 0.5f);
  expectNear(cameraPosition(s), {104, 0, 0});
  expectNear(s.origin, {104, 0, 0});
  expectNear(glm::dvec3(-glm::normalize(s.camera->cameraToWorld[2])), {-1, 0, 0});
  ASSERT_EQ(s.lights.size(), 1u);
  expectNear(s.origin + glm::dvec3(s.lights[0].position), {100, 2, 0});
  expectNear(glm::dvec3(s.lights[0].direction), {0, -1, 0});
  EXPECT_EQ(s.lights[0].intensity, glm::vec3(5.0f));
  expectNear(worldPosition(s, s.triangles[0].v1), {100, 0, -1});

  // the scene file's own camera wins
  f = loadText(doc(R"("camera": {"from": [0, 0, 50], "to": [0, 0, 0]}, "objects": [)" + gltfObject(transform) + "]"));
  expectNear(cameraPosition(f.scene), {0, 0, 50});
  expectNear(f.scene.origin, {0, 0, 50});
  expectNear(worldPosition(f.scene, f.scene.triangles[0].v1), {100, 0, -1});
}

// A textured file placed by a scene file keeps its textures (renumbered
// past another file's), its texture coordinates and vertex colours, and a
// scaling transform scales its camera's near plane.
TEST(SceneFile, GltfTexturesColoursAndScaledCameraArePlaced) {
  auto textured = [](std::uint8_t red) {
    GltfDoc gltf = triangleDoc(",1");
    const int uv = gltf.addVec2({{0, 0}, {1, 0}, {0, 1}});
    const std::vector<float> colors = {1, 0, 0, 1, 0, 1, 0, 1, 0, 0, 1, 1};
    const int col = gltf.addAccessor(gltf.addView(colors), gltf_doc::kFloat, 3, "VEC4");
    gltf.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":" +
                     str(std::size_t(uv)) + ",\"COLOR_0\":" + str(std::size_t(col)) + "},\"material\":0}]}";
    gltf.materials[0] = "{\"name\":\"tri\",\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}";
    std::vector<unsigned char> png;
    const std::uint8_t pixels[4] = {red, 20, 30, 255};
    stbi_write_png_to_func([](void* out, void* data, int size) {
      auto* bytes = static_cast<unsigned char*>(data);
      static_cast<std::vector<unsigned char>*>(out)->insert(static_cast<std::vector<unsigned char>*>(out)->end(),
                                                            bytes, bytes + size);
    }, &png, 1, 1, 4, pixels, 4);
    gltf.images.push_back("{\"uri\":\"data:image/png;base64," + gltf_doc::base64(png) + "\"}");
    gltf.textures.push_back("{\"source\":0}");
    gltf.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.5,\"znear\":0.1}}");
    gltf.addNode("{\"camera\":0,\"translation\":[0,0,4]}");
    return gltf;
  };
  writeTriangle(textured(200), "red.gltf");
  writeTriangle(textured(100), "dim.gltf");
  SceneFile f = loadText(doc(R"("materials": {"m": {}}, "objects": [
      {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"},)" +
                             gltfObject(R"({"scale": [0.001, 0.001, 0.001]})", "red.gltf") + "," +
                             gltfObject("", "dim.gltf") + "]"));
  const Scene& s = f.scene;
  expectConsistent(s);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
  ASSERT_EQ(s.materials.size(), 3u);
  ASSERT_EQ(s.materialTextures.size(), 3u * WT_TEXTURE_SLOTS);
  ASSERT_EQ(s.textures.textures.size(), 2u);
  for (std::uint32_t m : {1u, 2u}) {
    EXPECT_EQ(s.materials[m].texture_mask, 1u << WT_TEXTURE_SLOT_BASE_COLOR);
    const WtTextureRef& ref = s.materialTextures[m * WT_TEXTURE_SLOTS + WT_TEXTURE_SLOT_BASE_COLOR];
    ASSERT_EQ(ref.texture, m - 1);
    // each texture's level 0 is its own 1x1 image
    const WtTextureLevel& level = s.textures.levels[s.textures.textures[ref.texture].first_level];
    EXPECT_EQ(s.textures.texels[level.offset] & 0xffu, m == 1 ? 200u : 100u);
  }
  ASSERT_EQ(s.colors.size(), s.positions.size());
  ASSERT_EQ(s.texcoords.size(), s.positions.size());
  EXPECT_EQ(s.colors[s.triangles[0].v0], glm::vec4(1, 0, 0, 1));
  EXPECT_EQ(s.texcoords[s.triangles[1].v1], glm::vec2(1, 0));
  // the first file's camera, scaled by 1e-3 with its scene
  ASSERT_TRUE(s.camera.has_value());
  EXPECT_NEAR(s.camera->znear, 1e-4f, 1e-9f);
  EXPECT_NEAR(glm::length(glm::vec3(s.camera->cameraToWorld[2])), 1.0f, 1e-6f);
}

TEST(SceneFile, PlacedCopiesShareGeometryAndMaterials) {
  // the file itself places its mesh twice
  GltfDoc gltf = triangleDoc(",1");
  gltf.addNode("{\"mesh\":0,\"translation\":[5,0,0]}");
  writeTriangle(gltf);
  writeTriangle(triangleDoc(), "other.gltf");
  SceneFile f = loadText(doc(R"("materials": {"m": {}}, "objects": [
      {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"},)" +
                             gltfObject("") + "," + gltfObject(R"({"translate": [0, 10, 0]})") + "," +
                             gltfObject("", "other.gltf") + "]"));
  const Scene& s = f.scene;
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 5u);
  ASSERT_EQ(s.instances.size(), 5u);
  // triangle.gltf's four copies share one geometry, other.gltf's its own
  for (int i = 1; i < 4; ++i) EXPECT_EQ(s.instances[i].geometry, s.instances[0].geometry);
  EXPECT_NE(s.instances[4].geometry, s.instances[0].geometry);
  // each file's materials once, however often it is placed
  EXPECT_EQ(s.materialNames, (std::vector<std::string>{"m", "tri", "tri"}));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(s.triangles[i].material, 1u);
  EXPECT_EQ(s.triangles[4].material, 2u);
  expectNear(worldPosition(s, s.triangles[3].v1), {6, 10, 0});
}

// The same scene 1e6 units from the world origin: stored relative to the
// camera, its float coordinates are those of the scene at the origin.
TEST(SceneFile, RecentringKeepsFarScenesPrecise) {
  writeTriangle();
  auto placed = [&](double d, bool camera) {
    auto v = [&](double x, double y, double z) {
      char text[128];
      std::snprintf(text, sizeof text, "[%.17g, %.17g, %.17g]", x + d, y - d, z + d);
      return std::string(text);
    };
    std::string members = R"("objects": [)" +
                          gltfObject(R"({"translate": )" + v(0.1, 0.2, -0.3) + R"(, "rotate": [0, 1, 0, 30]})") +
                          R"(, {"type": "sphere", "center": )" + v(0.3, 0.05, -1.1) +
                          R"(, "radius": 0.01}, {"type": "sphere", "center": )" + v(-0.7, 0.4, -2) +
                          R"(, "radius": 0.5}])";
    if (camera) members += R"(, "camera": {"from": )" + v(0.25, 0.5, 3) + R"(, "to": )" + v(0, 0, 0) + "}";
    return loadText(doc(members)).scene;
  };
  for (bool camera : {true, false}) {
    SCOPED_TRACE(camera ? "with a camera" : "without a camera");
    const Scene here = placed(0.0, camera), far = placed(1e6, camera);
    expectNear(far.origin - here.origin, {1e6, -1e6, 1e6}, 1e-9);
    ASSERT_EQ(here.positions.size(), far.positions.size());
    for (std::size_t v = 0; v < here.positions.size(); ++v) {
      EXPECT_FLOAT_EQ(here.positions[v].x, far.positions[v].x) << "vertex " << v;
      EXPECT_FLOAT_EQ(here.positions[v].y, far.positions[v].y) << "vertex " << v;
      EXPECT_FLOAT_EQ(here.positions[v].z, far.positions[v].z) << "vertex " << v;
    }
    ASSERT_EQ(here.spheres.size(), far.spheres.size());
    for (std::size_t i = 0; i < here.spheres.size(); ++i) {
      EXPECT_FLOAT_EQ(here.spheres[i].center.x, far.spheres[i].center.x) << "sphere " << i;
      EXPECT_FLOAT_EQ(here.spheres[i].center.y, far.spheres[i].center.y) << "sphere " << i;
      EXPECT_FLOAT_EQ(here.spheres[i].center.z, far.spheres[i].center.z) << "sphere " << i;
    }
    if (camera) {
      EXPECT_EQ(glm::vec3(far.camera->cameraToWorld[3]), glm::vec3(0.0f));
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r)
          EXPECT_FLOAT_EQ(here.camera->cameraToWorld[c][r], far.camera->cameraToWorld[c][r]);
    }
  }
  // without recentring the world coordinates are kept (and 0.01 is lost at 1e6)
  GltfLoadOptions options;
  options.recenter = false;
  const Scene world = loadText(doc(R"("objects": [{"type": "sphere", "center": [1000000, 0, 0], "radius": 1}])"), options).scene;
  EXPECT_EQ(world.origin, glm::dvec3(0.0));
  EXPECT_EQ(world.spheres[0].center.x, 1e6f);
}

/// A .hair file of strands with 3 and 2 points, thickness 0.5 by default.
std::string hairFile(float y = 1.0f) {
  std::string out = "HAIR";
  auto u32 = [&](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  auto f32 = [&](float v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  u32(2), u32(5), u32(3), u32(0), f32(0.5f);
  out.resize(128, '\0');
  for (std::uint16_t segments : {2, 1}) out.append(reinterpret_cast<const char*>(&segments), 2);
  const float points[5][3] = {{0, 0, 0}, {0, y, 0}, {0, 2, 0}, {1, 0, 0}, {1, 1, 0}};
  for (const auto& p : points) f32(p[0]), f32(p[1]), f32(p[2]);
  return out;
}

TEST(SceneFile, CurvesInlineFromAFileAndChildren) {
  writeFile(testDir() / "two.hair", hairFile());
  const std::string text = doc(R"("materials": {"hair": {"base_color": [0.3, 0.2, 0.1]}}, "objects": [
      {"type": "curves", "basis": "bspline", "material": "hair", "transform": {"translate": [10, 0, 0], "scale": 2},
       "strands": [[[0, 0, 0, 0.1], [1, 0, 0], [2, 1, 0, 0.3], [3, 1, 1]]], "radius_scale": 1.5},
      {"type": "curves", "file": "two.hair", "radius": 0.05},
      {"type": "curves", "file": "two.hair", "children": 3, "child_radius": 0.2, "seed": 5}])");
  GltfLoadOptions options;
  options.recenter = false;
  // the points without a radius want the object's
  EXPECT_CONTAINS(errorOf(text, options), "objects[0].strands[0][1]: has no radius");
  const std::string fixed = std::regex_replace(text, std::regex(R"("radius_scale": 1.5)"), R"("radius_scale": 1.5, "radius": 0.2)");
  const Scene s = loadText(fixed, options).scene;
  ASSERT_EQ(s.curves.size(), 1u + 2u + 2u * (1u + 3u));
  // a transform scales positions and radii; "radius" replaces every point's, radius_scale multiplies it
  EXPECT_EQ(s.curves[0].basis, CurveBasis::kBSpline);
  EXPECT_EQ(s.curves[0].pointCount, 4u);
  EXPECT_EQ(s.materialNames[s.curves[0].material], "hair");
  const WtVec4 p = s.curvePoints[s.curves[0].firstPoint + 2];
  EXPECT_EQ(glm::vec4(p.x, p.y, p.z, p.w), glm::vec4(14, 2, 0, 0.2f * 1.5f * 2.0f));
  // the file's radii are half its thickness unless "radius" is given
  EXPECT_FLOAT_EQ(s.curvePoints[s.curves[1].firstPoint].w, 0.05f);
  EXPECT_FLOAT_EQ(s.curvePoints[s.curves[3].firstPoint].w, 0.25f);
  EXPECT_EQ(s.curves[1].pointCount, 3u);
  EXPECT_EQ(s.curves[2].pointCount, 2u);
  // children follow their guide within child_radius, across it
  for (std::uint32_t c = 5; c < s.curves.size(); ++c) {
    const Curve& child = s.curves[c];
    const Curve& guide = s.curves[child.pointCount == 3 ? 3 : 4];
    ASSERT_EQ(child.pointCount, guide.pointCount);
    for (std::uint32_t i = 0; i < child.pointCount; ++i) {
      const WtVec4 a = s.curvePoints[guide.firstPoint + i], b = s.curvePoints[child.firstPoint + i];
      const glm::vec3 offset(b.x - a.x, b.y - a.y, b.z - a.z);
      EXPECT_LE(glm::length(offset), 0.2f + 1e-6f);
      EXPECT_NEAR(offset.y, 0.0f, 1e-6f);  // the guides run along y
      EXPECT_EQ(a.w, b.w);
    }
  }
  // bounds take the curves in
  EXPECT_NEAR(s.bounds().hi.x, 16.0f + 0.6f, 1e-4f);
}

TEST(SceneFileAssets, HairExampleLoads) {
  WT_REQUIRE_ASSET(bangs, "curves/hairutil_testdata/Bangs_100.hair");
  SceneFile hair = loadSceneFile((wt::embedded::sourceDirectory() / "scenes" / "hair.json").string());
  expectConsistent(hair.scene);
  EXPECT_TRUE(hair.scene.warnings.empty()) << hair.scene.warnings.front();
  EXPECT_GE(hair.scene.curves.size(), 10000u);
  std::size_t segments = 0;
  for (const Curve& c : hair.scene.curves) segments += c.pointCount - 1;
  EXPECT_GE(segments, 100000u);
  EXPECT_EQ(hair.scene.spheres.size(), 1u);  // the lamp; the head is a mesh
  EXPECT_EQ(hair.scene.triangles.size(), 7694u);
}

/// A PLY square of two triangles (one quad face) with normals along +z.
std::string plySquare() {
  return "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
         "property list uchar int vertex_indices\nend_header\n"
         "0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n";
}

TEST(SceneFile, MeshesFromPlyFiles) {
  writeFile(testDir() / "square.ply", plySquare());
  GltfLoadOptions options;
  options.recenter = false;
  const Scene s = loadText(doc(R"("materials": {"red": {"base_color": [1, 0, 0]}, "blue": {"base_color": [0, 0, 1]}},
      "objects": [
      {"type": "mesh", "file": "square.ply", "material": "red",
       "transform": {"translate": [10, 0, 0], "rotate": [1, 0, 0, 90], "scale": 2}},
      {"type": "mesh", "file": "square.ply", "material": "red"},
      {"type": "mesh", "file": "square.ply", "material": "blue"}])"), options).scene;
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 6u);
  ASSERT_EQ(s.instances.size(), 3u);
  // the same file with the same material is one geometry; another material makes another
  EXPECT_EQ(s.instances[0].geometry, s.instances[1].geometry);
  EXPECT_NE(s.instances[0].geometry, s.instances[2].geometry);
  EXPECT_EQ(s.materialNames[s.triangles[0].material], "red");
  EXPECT_EQ(s.materialNames[s.triangles[4].material], "blue");
  // the quad's far corner (1, 1, 0): scaled by 2, turned about x by 90 degrees, moved to x = 10
  const glm::dvec3 corner = worldPosition(s, s.triangles[1].v1);
  EXPECT_NEAR(corner.x, 12.0, 1e-5);
  EXPECT_NEAR(corner.y, 0.0, 1e-5);
  EXPECT_NEAR(corner.z, 2.0, 1e-5);
  // normals turn with the surface: +z becomes -y
  const WtVec4 n = s.normals[s.triangles[0].v0];
  EXPECT_NEAR(n.y, -1.0f, 1e-6f);
}

TEST(SceneFile, DisplacedMeshFromPlyAndExr) {
  // a unit square with uv, its map a 4 x 2 EXR; a mirroring transform flips the winding
  writeFile(testDir() / "uv_square.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n");
  Image map;
  map.width = 4;
  map.height = 2;
  for (int i = 0; i < 8; ++i) map.rgb.insert(map.rgb.end(), {0.125f * float(i), 0.0f, 0.0f});
  writeImage(testDir() / "uv_map.exr", map);
  GltfLoadOptions options;
  options.recenter = false;
  const Scene s = loadText(doc(R"("objects": [{"type": "displaced", "mesh": "uv_square.ply", "displacement": "uv_map.exr",
      "scale": 0.5, "offset": -0.25, "transform": {"scale": [-1, 1, 1]}}])"), options).scene;
  ASSERT_EQ(s.displacedMeshes.size(), 1u);
  const DisplacedMesh& m = s.displacedMeshes[0];
  EXPECT_TRUE(s.triangles.empty());
  ASSERT_EQ(m.positions.size(), 4u);
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.mapWidth, 4u);
  EXPECT_EQ(m.mapHeight, 2u);
  EXPECT_EQ(m.map[5], 0.625f);
  EXPECT_EQ(m.scale, 0.5f);
  EXPECT_EQ(m.offset, -0.25f);
  EXPECT_EQ(m.level, -1);
  // the longest base edge (the diagonal) spans 4 texels along u: micro-edges of a texel at level 2
  EXPECT_EQ(displacedLevel(m), 2u);
  // made normals: the square's +z; the mirror keeps them (x flips, z stays) and swaps two corners
  EXPECT_NEAR(m.normals[0].z, 1.0f, 1e-6f);
  EXPECT_NEAR(m.positions[1].x, -1.0f, 1e-6f);
  const glm::vec3 a = m.positions[m.triangles[0][0]], b = m.positions[m.triangles[0][1]], c = m.positions[m.triangles[0][2]];
  EXPECT_GT(glm::cross(b - a, c - a).z, 0.0f);
  // PLY's v runs up: the loader gives glTF's (v = 0 the map's top row)
  EXPECT_EQ(m.texcoords[0].y, 1.0f);
}

// A displaced glTF mesh is shaded by the object's material: the file's textures are dropped, and a warning names them.
TEST(SceneFile, DisplacedGltfMeshWarnsThatItsTexturesAreNotApplied) {
  Image map;
  map.width = map.height = 2;
  map.rgb.assign(12, 0.5f);
  writeImage(testDir() / "uv_map.exr", map);
  const unsigned char texels[12] = {200, 100, 50, 200, 100, 50, 200, 100, 50, 200, 100, 50};
  ASSERT_NE(stbi_write_png((testDir() / "albedo.png").string().c_str(), 2, 2, 3, texels, 6), 0);
  GltfDoc gltf;
  const int pos = gltf.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  const int uv = gltf.addVec2({{0, 0}, {1, 0}, {0, 1}});
  gltf.addMesh("{\"attributes\":{\"POSITION\":" + std::to_string(pos) + ",\"TEXCOORD_0\":" + std::to_string(uv) +
               "},\"material\":0}");
  gltf.images.push_back("{\"uri\":\"albedo.png\"}");
  gltf.textures.push_back("{\"source\":0}");
  gltf.addNode("{\"mesh\":0}");
  gltf.scenes.push_back("{\"nodes\":[0]}");
  const auto load = [&](const std::string& material) {
    gltf.materials = {material};
    writeFile(testDir() / "uv_triangle.gltf", gltf.embedded());
    return loadText(doc(R"("objects": [{"type": "displaced", "mesh": "uv_triangle.gltf", "displacement": "uv_map.exr",
        "scale": 0.1}])")).scene;
  };
  const auto warned = [](const Scene& s) {
    for (const std::string& w : s.warnings)
      if (w.find("objects[0]: uv_triangle.gltf: its materials' textures are not applied to a displaced mesh") !=
          std::string::npos)
        return true;
    return false;
  };
  const Scene textured = load("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}");
  ASSERT_EQ(textured.displacedMeshes.size(), 1u);
  EXPECT_TRUE(warned(textured));
  EXPECT_FALSE(warned(load("{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1]}}")));
}

TEST(SceneFileAssets, HeadMeshLoads) {
  WT_REQUIRE_ASSET(head, "curves/hairutil_testdata/Bangs_head.ply");
  const Scene s = loadText(doc(R"("objects": [{"type": "mesh", "file": ")" + head.string() + R"("}])")).scene;
  expectConsistent(s);
  EXPECT_EQ(s.positions.size(), 3943u);
  EXPECT_EQ(s.triangles.size(), 7694u);
}

/// "instances" place an SDF grid (any affine transform: one copy here is
/// scaled unevenly) or a displaced mesh (similarities: its displacement
/// scales with the copy) once per transform, each a PrimitiveInstance of one
/// geometry per object: the grid's lattice and the mesh's vertices moved by
/// the copy's transform after the object's own.
TEST(SceneFile, SdfGridsAndDisplacedMeshesPlacedAsInstances) {
  writeFile(testDir() / "uv_square.ply",
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "property float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
            "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n");
  Image map;
  map.width = 4;
  map.height = 2;
  for (int i = 0; i < 8; ++i) map.rgb.insert(map.rgb.end(), {0.125f * float(i), 0.0f, 0.0f});
  writeImage(testDir() / "uv_map.exr", map);
  GltfLoadOptions options;
  options.recenter = false;
  const Scene s = loadText(doc(R"("objects": [
      {"type": "sdf", "shape": "sphere", "resolution": 8, "transform": {"translate": [0, 2, 0]},
       "instances": [{"translate": [5, 0, 0]}, {"scale": [1, 2, 3]}, {"rotate": [0, 0, 1, 90]}]},
      {"type": "displaced", "mesh": "uv_square.ply", "displacement": "uv_map.exr", "scale": 0.5, "offset": -0.25,
       "transform": {"translate": [0, 0, 1]},
       "instances": [{"translate": [-3, 0, 0]}, {"rotate": [0, 0, 1, 90], "scale": 2}]}])"), options).scene;
  ASSERT_EQ(s.sdfGrids.size(), 3u);
  ASSERT_EQ(s.displacedMeshes.size(), 2u);
  ASSERT_EQ(s.primitiveInstances.size(), 5u);
  for (std::uint32_t k = 0; k < 5; ++k) {
    const PrimitiveInstance& c = s.primitiveInstances[k];
    EXPECT_EQ(c.type, k < 3 ? WT_PRIM_SDF_GRID : WT_PRIM_DISPLACED);
    EXPECT_EQ(c.first, k < 3 ? k : k - 3);
    EXPECT_EQ(c.count, 1u);
    EXPECT_EQ(c.geometry, s.primitiveInstances[k < 3 ? 0 : 3].geometry);
  }
  // the grid's lattice centre (the sphere at the object's origin) moved by each copy after the object's own
  auto centre = [&](std::size_t i) {
    const SdfGrid& g = s.sdfGrids[i];
    return glm::dvec3(g.latticeToScene * glm::dvec4(glm::dvec3(g.cells) * 0.5, 1.0));
  };
  EXPECT_LT(glm::distance(centre(0), glm::dvec3(5, 2, 0)), 1e-9);
  EXPECT_LT(glm::distance(centre(1), glm::dvec3(0, 4, 0)), 1e-9);
  EXPECT_LT(glm::distance(centre(2), glm::dvec3(-2, 0, 0)), 1e-9);
  EXPECT_EQ(s.sdfGrids[1].values, s.sdfGrids[0].values);
  // the square's corner (1, 0, 0) after its transform: moved, or turned and scaled by 2 with its displacement
  EXPECT_LT(glm::distance(glm::dvec3(s.displacedMeshes[0].positions[1]), glm::dvec3(-2, 0, 1)), 1e-6);
  EXPECT_LT(glm::distance(glm::dvec3(s.displacedMeshes[1].positions[1]), glm::dvec3(0, 2, 2)), 1e-6);
  EXPECT_FLOAT_EQ(s.displacedMeshes[0].scale, 0.5f);
  EXPECT_FLOAT_EQ(s.displacedMeshes[1].scale, 1.0f);
  EXPECT_FLOAT_EQ(s.displacedMeshes[1].offset, -0.5f);
  EXPECT_LT(glm::distance(s.displacedMeshes[1].normals[0], s.displacedMeshes[0].normals[0]), 1e-6f);  // (0, 0, 1) both
}

// ---------------------------------------------------------------------------
// errors: each names the file, the JSON path and the problem

/// "instances" place a sphere, spheres or curves object once per transform:
/// every copy is the object's own coordinates moved by its transform (radii
/// by its scale, children the same in every copy), recorded as
/// PrimitiveInstances of one geometry per object, relative to the origin.
TEST(SceneFile, SpheresAndCurvesPlacedAsInstances) {
  const std::string text = doc(R"("camera": {"from": [100, 0, 10], "to": [100, 0, 0]}, "objects": [
      {"type": "sphere", "center": [1, 0, 0], "radius": 0.5,
       "instances": [{"translate": [100, 0, 0]}, {"translate": [100, 5, 0], "scale": -2}]},
      {"type": "spheres", "centers": [[0, 0, 0], [0, 1, 0]], "radii": [0.1, 0.2],
       "instances": [{"rotate": [0, 0, 1, 90]}, {"translate": [3, 0, 0], "scale": 3}, {"translate": [0, 0, 9]}]},
      {"type": "curves", "strands": [[[0, 0, 0, 0.1], [0, 1, 0, 0.05]]], "children": 2, "child_radius": 0.2,
       "transform": {"translate": [50, 0, 0]},
       "instances": [{"translate": [10, 0, 0]}, {"translate": [0, 0, 10], "rotate": [1, 0, 0, 90], "scale": 0.5}]}])");
  const Scene s = loadText(text).scene;
  ASSERT_EQ(s.spheres.size(), 2u + 6u);
  ASSERT_EQ(s.curves.size(), 2u * 3u);
  ASSERT_EQ(s.primitiveInstances.size(), 2u + 3u + 2u);
  EXPECT_EQ(s.origin, glm::dvec3(100, 0, 10));
  auto centre = [&](std::uint32_t i) { return s.origin + glm::dvec3(s.spheres[i].center); };
  // the sphere: translated, then mirrored and scaled by 2 (radius 1)
  EXPECT_EQ(centre(0), glm::dvec3(101, 0, 0));
  EXPECT_EQ(centre(1), glm::dvec3(98, 5, 0));
  EXPECT_FLOAT_EQ(s.spheres[1].radius, 1.0f);
  // the spheres: turned about z, scaled by 3, moved along z
  EXPECT_LT(glm::distance(centre(3), glm::dvec3(-1, 0, 0)), 1e-5);
  EXPECT_EQ(centre(5), glm::dvec3(3, 3, 0));
  EXPECT_FLOAT_EQ(s.spheres[5].radius, 0.6f);
  EXPECT_EQ(centre(7), glm::dvec3(0, 1, 9));
  // one geometry per object, its copies' transforms from its own coordinates to the scene's
  const PrimitiveInstance &a = s.primitiveInstances[0], &b = s.primitiveInstances[3];
  EXPECT_EQ(a.type, std::uint32_t(WT_PRIM_SPHERE));
  EXPECT_EQ(a.first, 0u);
  EXPECT_EQ(a.count, 1u);
  EXPECT_EQ(b.first, 4u);
  EXPECT_EQ(b.count, 2u);
  EXPECT_NE(a.geometry, b.geometry);
  EXPECT_EQ(s.primitiveInstances[2].geometry, b.geometry);
  EXPECT_EQ(glm::dvec3(b.transform * glm::dvec4(0, 1, 0, 1)), glm::dvec3(s.spheres[5].center));
  // the curves: copy 1 is copy 0 moved by their transforms' difference, children included
  const PrimitiveInstance &c0 = s.primitiveInstances[5], &c1 = s.primitiveInstances[6];
  EXPECT_EQ(c0.type, std::uint32_t(WT_PRIM_CURVE));
  EXPECT_EQ(c0.first, 0u);
  EXPECT_EQ(c0.count, 3u);
  EXPECT_EQ(c1.first, 3u);
  EXPECT_EQ(c0.geometry, c1.geometry);
  const glm::dmat4 relative = c1.transform * glm::inverse(c0.transform);
  for (std::uint32_t c = 0; c < 3; ++c)
    for (std::uint32_t i = 0; i < 2; ++i) {
      const WtVec4 p = s.curvePoints[s.curves[c].firstPoint + i], q = s.curvePoints[s.curves[3 + c].firstPoint + i];
      const glm::dvec3 moved(relative * glm::dvec4(p.x, p.y, p.z, 1.0));
      EXPECT_LT(glm::distance(moved, glm::dvec3(q.x, q.y, q.z)), 1e-4) << "curve " << c << ", point " << i;
      EXPECT_FLOAT_EQ(q.w, 0.5f * p.w);
    }
  // the guide's root: the object's transform, then the copy's
  const WtVec4 root = s.curvePoints[s.curves[3].firstPoint];
  EXPECT_LT(glm::distance(s.origin + glm::dvec3(root.x, root.y, root.z), glm::dvec3(25, 0, 10)), 1e-4);
  // the flattened copies are in the bounds
  EXPECT_GE(s.bounds().hi.y + s.origin.y, 6.0 - 1e-4);
}

struct BadFile {
  const char* name;
  std::string json;
  std::string message;  ///< expected after "scene.json: "
};

void PrintTo(const BadFile& c, std::ostream* out) { *out << c.name; }

class SceneFileErrors : public ::testing::TestWithParam<BadFile> {};

TEST_P(SceneFileErrors, NameTheFileAndTheField) {
  writeTriangle();
  writeFile(testDir() / "sky.hdr", "x");
  writeFile(testDir() / "square.ply", plySquare());
  writeFile(testDir() / "map.exr", "x");
  writeFile(testDir() / "ball.raw", std::string(32, '\0'));
  const BadFile& c = GetParam();
  EXPECT_CONTAINS(errorOf(c.json), "scene.json: " + c.message);
}

const std::string kSphere = R"({"type": "sphere", "center": [0, 0, 0], "radius": 1})";
std::string objects(const std::string& list) { return doc("\"objects\": [" + list + "]"); }
std::string sphere(const std::string& more) {
  return objects(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1)" + more + "}");
}
std::string material(const std::string& fields) { return doc(R"("materials": {"m": {)" + fields + "}}"); }
std::string transform(const std::string& t) { return objects(gltfObject(t)); }

const BadFile kBadFiles[] = {
        // the document
        BadFile{"Empty", "", "the file is empty"},
        BadFile{"Malformed", "{\"version\": 1,\n \"objects\": [}", "malformed JSON at byte 29: parse error at line 2, column 14"},
        BadFile{"TooDeep", doc("\"objects\": " + std::string(100, '[') + std::string(100, ']')),
                [] {  // the top-level object and "objects" are two of the 64 levels
                  std::string path = "objects";
                  for (int i = 0; i < 63; ++i) path += "[0]";
                  return path + ": nested more than 64 levels deep";
                }()},
        BadFile{"DuplicateKey", objects(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "radius": 2})"),
                "objects[0].radius: duplicate key"},
        BadFile{"NotAnObject", "[1, 2]", "the top level must be an object, got [1,2]"},
        BadFile{"NoVersion", "{}", "version: missing (required; this wavetrace reads version 1)"},
        BadFile{"WrongVersion", "{\"version\": 2}", "version: unsupported version 2 (this wavetrace reads version 1)"},
        BadFile{"UnknownTopLevel", doc("\"objetcs\": []"),
                "objetcs: unknown field (expected one of: version, camera, environment, materials, objects, render)"},
        BadFile{"ObjectsNotAnArray", doc("\"objects\": {}"), "objects: must be an array, got {}"},
        // objects
        BadFile{"UnknownField", objects(kSphere + "," + kSphere + "," + kSphere + R"(, {"type": "sphere", "radus": 1})"),
                "objects[3].radus: unknown field (expected one of: type, center, radius, material, instances)"},
        BadFile{"NegativeRadius", objects(kSphere + "," + kSphere + "," + kSphere +
                                          R"(, {"type": "sphere", "center": [0, 0, 0], "radius": -1})"),
                "objects[3].radius: must be > 0, got -1"},
        BadFile{"RadiusNotANumber", objects(R"({"type": "sphere", "center": [0, 0, 0], "radius": "abc"})"),
                "objects[0].radius: must be a number, got \"abc\""},
        BadFile{"RadiusNotFinite", objects(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e999})"),
                "objects[0].radius: must be a finite number, got 1e999 (beyond the range of a double)"},
        BadFile{"NumberOverflowInAnArray", objects(R"({"type": "sphere", "center": [0, -1e400, 0], "radius": 1})"),
                "objects[0].center[1]: must be a finite number, got -1e400"},
        BadFile{"RadiusBeyondFloat", objects(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1e300})"),
                "objects[0]: the radius 1e+300 is out of the range of a float"},
        BadFile{"CenterBeyondFloat", objects(R"({"type": "sphere", "center": [1e300, 0, 0], "radius": 1})"),
                "objects[0]: the centre lies beyond the range of a float"},
        BadFile{"MissingCenter", objects(R"({"type": "sphere", "radius": 1})"), "objects[0].center: missing (required)"},
        BadFile{"ShortCenter", objects(R"({"type": "sphere", "center": [0, 0], "radius": 1})"),
                "objects[0].center: must be an array of 3 numbers, got [0,0]"},
        BadFile{"CenterElement", objects(R"({"type": "sphere", "center": [0, true, 0], "radius": 1})"),
                "objects[0].center[1]: must be a number, got true"},
        BadFile{"MissingType", objects(R"({"center": [0, 0, 0]})"),
                "objects[0].type: missing (required: gltf, mesh, sphere, spheres, curves, sdf or displaced)"},
        BadFile{"UnknownType", objects(R"({"type": "cube"})"),
                "objects[0].type: unknown type \"cube\" (expected one of: gltf, mesh, sphere, spheres, curves, sdf, "
                "displaced)"},
        // displaced meshes
        BadFile{"DisplacedMissingScale", objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "map.exr"})"),
                "objects[0].scale: missing (required: world units per unit of the map)"},
        BadFile{"DisplacedLevel",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "map.exr", "scale": 1, "level": 11})"),
                "objects[0].level: must be an integer in [0, 10], got 11"},
        BadFile{"DisplacedMeshType",
                objects(R"({"type": "displaced", "mesh": "square.obj", "displacement": "map.exr", "scale": 1})"),
                "objects[0].mesh: must be a .gltf, .glb or .ply file, got \"square.obj\""},
        BadFile{"DisplacedMapType",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "sky.hdr", "scale": 1})"),
                "objects[0].displacement: must be a .png, .jpg or .exr file, got \"sky.hdr\""},
        BadFile{"DisplacedMissingMap",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "nowhere.png", "scale": 1})"),
                "objects[0].displacement: no such file: "},
        BadFile{"DisplacedNoUv",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "map.exr", "scale": 1})"),
                "objects[0].mesh: square.ply has no texture coordinates (the map needs them)"},
        // meshes
        BadFile{"MeshFileType", objects(R"({"type": "mesh", "file": "head.obj"})"),
                "objects[0].file: must be a .ply file, got \"head.obj\""},
        BadFile{"MeshMissingFile", objects(R"({"type": "mesh", "file": "nowhere.ply"})"), "objects[0].file: no such file: "},
        BadFile{"MeshUnknownMaterial", objects(R"({"type": "mesh", "file": "a.ply", "material": "chrome"})"),
                "objects[0].material: unknown material \"chrome\""},
        // curves
        BadFile{"CurvesFileAndStrands", objects(R"({"type": "curves", "file": "a.hair", "strands": []})"),
                "objects[0]: give \"file\" (a .hair or .ply file) or \"strands\" (points), not both"},
        BadFile{"CurvesNoStrands", objects(kSphere + R"(, {"type": "curves"})"),
                "objects[1].strands: missing (required: \"strands\", or a \"file\" of strands)"},
        BadFile{"CurvesFileType", objects(R"({"type": "curves", "file": "hair.bin"})"),
                "objects[0].file: must be a .hair or .ply file, got \"hair.bin\""},
        BadFile{"CurvesMissingFile", objects(R"({"type": "curves", "file": "nowhere.hair"})"),
                "objects[0].file: no such file: "},
        BadFile{"CurvesBasis", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]], "basis": "bezier"})"),
                "objects[0].basis: must be \"linear\" or \"bspline\", got \"bezier\""},
        BadFile{"CurvesShortStrand", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]], [[0, 0, 0, 1]]]})"),
                "objects[0].strands[1]: must be an array of at least 2 points, got [[0,0,0,1]]"},
        BadFile{"CurvesShortBSpline", objects(R"({"type": "curves", "basis": "bspline", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]]})"),
                "objects[0].strands[0]: must be an array of at least 4 points (a B-spline segment takes 4)"},
        BadFile{"CurvesPointWithoutRadius", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0]]]})"),
                "objects[0].strands[0][1]: has no radius: give [x, y, z, radius], or the object's \"radius\""},
        BadFile{"CurvesNegativeRadius", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, -1]]]})"),
                "objects[0].strands[0][1][3]: must be >= 0, got -1"},
        BadFile{"CurvesShortPoint", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0]]]})"),
                "objects[0].strands[0][1]: must be [x, y, z] or [x, y, z, radius], got [1,0]"},
        BadFile{"CurvesZeroRadius", objects(R"({"type": "curves", "strands": [[[0, 0, 0], [1, 0, 0]]], "radius": 0})"),
                "objects[0].radius: must be > 0, got 0"},
        BadFile{"CurvesChildrenWithoutRadius", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]], "children": 4})"),
                "objects[0].child_radius: missing (required with \"children\": how far children stray from their guide)"},
        BadFile{"CurvesChildRadiusAlone", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]], "child_radius": 4})"),
                "objects[0].child_radius: applies only with \"children\" > 0"},
        BadFile{"CurvesTooManyChildren", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]], "children": 1000000, "child_radius": 1})"),
                "objects[0].children: must be an integer in [0, 100000], got 1000000"},
        BadFile{"CurvesUnknownField", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]], "width": 1})"),
                "objects[0].width: unknown field (expected one of: type, file, strands, basis, radius, radius_scale, transform, "
                "material, children, child_radius, seed, instances)"},
        BadFile{"CurvesPointBeyondFloat", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1e300, 0, 0, 1]]]})"),
                "objects[0]: strand 0, point 1 lies beyond the range of a float from the scene's origin"},
        BadFile{"ObjectNotAnObject", objects("3"), "objects[0]: must be an object, got 3"},
        BadFile{"UnknownMaterial", doc(R"("materials": {"red": {}, "blue": {}}, "objects": [)" +
                                       std::string(R"({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "green"}])")),
                "objects[0].material: unknown material \"green\" (defined: blue, red)"},
        BadFile{"NoMaterials", sphere(R"(, "material": "green")"),
                "objects[0].material: unknown material \"green\" (the file defines no materials)"},
        BadFile{"SpheresRadiiCount", objects(R"({"type": "spheres", "centers": [[0, 0, 0], [1, 0, 0]], "radii": [1]})"),
                "objects[0].radii: must be an array of 2 numbers (one per centre), got [1]"},
        BadFile{"SpheresRadiusAndRadii", objects(R"({"type": "spheres", "centers": [], "radii": [], "radius": 1})"),
                "objects[0]: give \"radius\" (one for all) or \"radii\" (one per centre), not both"},
        BadFile{"SpheresNoRadius", objects(R"({"type": "spheres", "centers": []})"),
                "objects[0].radius: missing (required: \"radius\", or \"radii\" with one per centre)"},
        BadFile{"SpheresBadCentre", objects(R"({"type": "spheres", "centers": [[0, 0, 0], [1, 0]], "radius": 1})"),
                "objects[0].centers[1]: must be an array of 3 numbers, got [1,0]"},
        BadFile{"SpheresBadRadius", objects(R"({"type": "spheres", "centers": [[0, 0, 0], [1, 0, 0]], "radii": [1, 0]})"),
                "objects[0].radii[1]: must be > 0, got 0"},
        // glTF includes
        BadFile{"MissingGltf", objects(gltfObject("", "nowhere.gltf")), "objects[0].file: no such file: "},
        BadFile{"GltfNotAGltf", objects(gltfObject("", "mesh.obj")),
                "objects[0].file: must be a .gltf or .glb file, got \"mesh.obj\""},
        BadFile{"GltfMissingFile", objects(R"({"type": "gltf"})"), "objects[0].file: missing (required)"},
        BadFile{"TransformUnknown", transform(R"({"translation": [1, 2, 3]})"),
                "objects[0].transform.translation: unknown field (expected one of: translate, rotate, quaternion, scale, matrix)"},
        BadFile{"ZeroScale", transform(R"({"scale": [1, 0, 1]})"),
                "objects[0].transform.scale: must not be 0 (the object would be flat)"},
        BadFile{"ScaleNotANumber", transform(R"({"scale": "big"})"),
                "objects[0].transform.scale: must be an array of 3 numbers, got \"big\""},
        BadFile{"RotateZeroAxis", transform(R"({"rotate": [0, 0, 0, 45]})"),
                "objects[0].transform.rotate: the axis must not be (0, 0, 0)"},
        BadFile{"RotateShort", transform(R"({"rotate": [0, 1, 0]})"),
                "objects[0].transform.rotate: must be an array of 4 numbers (axis x, y, z and degrees), got [0,1,0]"},
        BadFile{"RotateAndQuaternion", transform(R"({"rotate": [0, 1, 0, 5], "quaternion": [0, 0, 0, 1]})"),
                "objects[0].transform: give \"rotate\" or \"quaternion\", not both"},
        BadFile{"ZeroQuaternion", transform(R"({"quaternion": [0, 0, 0, 0]})"),
                "objects[0].transform.quaternion: must not be (0, 0, 0, 0)"},
        BadFile{"MatrixAndTranslate", transform(R"({"translate": [0, 0, 0], "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]})"),
                "objects[0].transform.matrix: cannot be combined with translate, rotate, quaternion or scale"},
        BadFile{"MatrixNotAffine", transform(R"({"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,1, 0,0,0,1]})"),
                "objects[0].transform.matrix: must be affine"},
        BadFile{"MatrixSingular", transform(R"({"matrix": [1,0,0,0, 0,1,0,0, 0,0,0,0, 0,0,0,1]})"),
                "objects[0].transform: is singular or not finite (determinant 0)"},
        BadFile{"MatrixShort", transform(R"({"matrix": [1, 0, 0]})"),
                "objects[0].transform.matrix: must be an array of 16 numbers (column-major, as glTF), got [1,0,0]"},
        // instances
        BadFile{"InstancesNotAnArray", sphere(R"(, "instances": {"translate": [1, 0, 0]})"),
                "objects[0].instances: must be a non-empty array of transforms (each as \"transform\"), got {"},
        BadFile{"InstancesEmpty", sphere(R"(, "instances": [])"),
                "objects[0].instances: must be a non-empty array of transforms (each as \"transform\"), got []"},
        BadFile{"InstanceNotAnObject", sphere(R"(, "instances": [{"translate": [1, 0, 0]}, 5])"),
                "objects[0].instances[1]: must be an object, got 5"},
        BadFile{"InstanceUnknownField", sphere(R"(, "instances": [{"move": [1, 0, 0]}])"),
                "objects[0].instances[0].move: unknown field (expected one of: translate, rotate, quaternion, scale, matrix)"},
        BadFile{"InstanceUnevenScale", sphere(R"(, "instances": [{"translate": [1, 0, 0]}, {"scale": [1, 2, 1]}])"),
                "objects[0].instances[1]: must keep spheres and curves round: a rotation, one scale for all axes and a "
                "translation (its axes are scaled by 1, 2, 1)"},
        BadFile{"InstanceSheared", sphere(R"(, "instances": [{"matrix": [1,0,0,0, 0.6,0.8,0,0, 0,0,1,0, 0,0,0,1]}])"),
                "objects[0].instances[0]: must keep spheres and curves round: a rotation, one scale for all axes and a "
                "translation (its axes are scaled by 1, 1, 1 and are not perpendicular)"},
        BadFile{"InstanceZeroScale", sphere(R"(, "instances": [{"scale": 0}])"),
                "objects[0].instances[0].scale: must not be 0"},
        BadFile{"InstancesOfSdfNotAnArray", objects(R"({"type": "sdf", "shape": "sphere", "resolution": 8,
                "instances": {"translate": [1, 0, 0]}})"),
                "objects[0].instances: must be a non-empty array of transforms (each as \"transform\"), got {"},
        BadFile{"InstanceOfSdfFlat", objects(R"({"type": "sdf", "shape": "sphere", "resolution": 8,
                "instances": [{"translate": [1, 0, 0]}, {"scale": [1, 0, 1]}]})"),
                "objects[0].instances[1].scale: must not be 0"},
        BadFile{"InstanceOfSdfBeyondFloat", objects(R"({"type": "sdf", "shape": "sphere", "resolution": 8,
                "instances": [{"translate": [0, 0, 0]}, {"translate": [1e39, 0, 0]}]})"),
                "objects[0].instances[1]: the grid's box lies beyond the range of a float from the scene's origin"},
        BadFile{"InstancesOfDisplacedEmpty", objects(R"({"type": "displaced", "mesh": "square.ply",
                "displacement": "map.exr", "scale": 1, "instances": []})"),
                "objects[0].instances: must be a non-empty array of transforms (each as \"transform\"), got []"},
        BadFile{"InstanceOfDisplacedUneven", objects(R"({"type": "displaced", "mesh": "square.ply",
                "displacement": "map.exr", "scale": 1, "instances": [{"translate": [1, 0, 0]}, {"scale": [1, 2, 1]}]})"),
                "objects[0].instances[1]: must keep displacements along the normals: a rotation, one scale for all "
                "axes and a translation (its axes are scaled by 1, 2, 1)"},
        BadFile{"InstanceOfDisplacedUnknownField", objects(R"({"type": "displaced", "mesh": "square.ply",
                "displacement": "map.exr", "scale": 1, "instances": [{"shift": [1, 0, 0]}]})"),
                "objects[0].instances[0].shift: unknown field (expected one of: translate, rotate, quaternion, scale, matrix)"},
        BadFile{"InstancesOfSpheresUneven", objects(R"({"type": "spheres", "centers": [[0, 0, 0]], "radius": 1,
                "instances": [{"scale": [2, 2, -3]}]})"),
                "objects[0].instances[0]: must keep spheres and curves round"},
        BadFile{"InstancesOfCurvesUneven", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]],
                "instances": [{"translate": [0, 0, 0]}, {"quaternion": [0, 0, 0, 1], "scale": [1, 1, 2]}]})"),
                "objects[0].instances[1]: must keep spheres and curves round"},
        BadFile{"InstanceBeyondFloat", sphere(R"(, "instances": [{"translate": [1e39, 0, 0]}])"),
                "objects[0].instances[0]: the centre lies beyond the range of a float from the scene's origin"},
        BadFile{"InstanceOfSpheresBeyondFloat", objects(R"({"type": "spheres", "centers": [[0, 0, 0], [1, 0, 0]],
                "radius": 1, "instances": [{"translate": [0, 0, 0]}, {"translate": [1e39, 0, 0]}]})"),
                "objects[0].instances[1] (centers[0]): the centre lies beyond the range of a float"},
        BadFile{"InstanceOfCurvesBeyondFloat", objects(R"({"type": "curves", "strands": [[[0, 0, 0, 1], [1, 0, 0, 1]]],
                "instances": [{"translate": [0, 0, 0]}, {"translate": [1e39, 0, 0]}]})"),
                "objects[0].instances[1]: strand 0, point 0 lies beyond the range of a float from the scene's origin"},
        BadFile{"InstancesOnAMesh", objects(R"({"type": "mesh", "file": "square.ply", "instances": []})"),
                "objects[0].instances: unknown field"},
        // camera
        BadFile{"CameraNoFrom", doc(R"("camera": {"to": [0, 0, 0]})"), "camera.from: missing (required)"},
        BadFile{"CameraFovRange", doc(R"("camera": {"from": [0, 0, 1], "to": [0, 0, 0], "fov": 180})"),
                "camera.fov: must be in (0, 180) degrees, got 180"},
        BadFile{"CameraToIsFrom", doc(R"("camera": {"from": [1, 2, 3], "to": [1, 2, 3]})"),
                "camera.to: must differ from camera.from"},
        BadFile{"CameraUpParallel", doc(R"("camera": {"from": [0, 5, 0], "to": [0, 0, 0]})"),
                "camera.up: is parallel to the view direction"},
        BadFile{"CameraUpZero", doc(R"("camera": {"from": [0, 0, 1], "to": [0, 0, 0], "up": [0, 0, 0]})"),
                "camera.up: must not be (0, 0, 0)"},
        BadFile{"CameraUnknown", doc(R"("camera": {"from": [0, 0, 1], "to": [0, 0, 0], "yfov": 1})"),
                "camera.yfov: unknown field (expected one of: from, to, up, fov)"},
        // environment
        BadFile{"EnvironmentBoth", doc(R"("environment": {"color": [1, 1, 1], "map": "sky.hdr"})"),
                "environment: give \"color\" or \"map\", not both"},
        BadFile{"EnvironmentNeither", doc(R"("environment": {"hidden": true})"),
                "environment: needs \"color\" (a constant environment) or \"map\""},
        BadFile{"EnvironmentMissingMap", doc(R"("environment": {"map": "nowhere.exr"})"),
                "environment.map: no such file: "},
        BadFile{"EnvironmentMapFormat", doc(R"("environment": {"map": "sky.png"})"),
                "environment.map: must be a .hdr or .exr file, got \"sky.png\""},
        BadFile{"EnvironmentIntensityWithColor", doc(R"("environment": {"color": [1, 1, 1], "intensity": 2})"),
                "environment.intensity: applies to a \"map\" only"},
        BadFile{"EnvironmentNegativeColor", doc(R"("environment": {"color": [1, -1, 1]})"),
                "environment.color[1]: must be >= 0, got -1"},
        BadFile{"EnvironmentHiddenType", doc(R"("environment": {"map": "sky.hdr", "hidden": 1})"),
                "environment.hidden: must be true or false, got 1"},
        BadFile{"EnvironmentNegativeIntensity", doc(R"("environment": {"map": "sky.hdr", "intensity": -2})"),
                "environment.intensity: must be >= 0, got -2"},
        // render
        BadFile{"RenderWidth", doc(R"("render": {"width": 0})"), "render.width: must be an integer in [1, 16384], got 0"},
        BadFile{"RenderSppFraction", doc(R"("render": {"spp": 1.5})"), "render.spp: must be an integer, got 1.5"},
        BadFile{"RenderIntegrator", doc(R"("render": {"integrator": "fast"})"),
                "render.integrator: must be \"path\" or \"minimal\", got \"fast\""},
        BadFile{"RenderTonemap", doc(R"("render": {"tonemap": "filmic"})"),
                "render.tonemap: must be one of linear, reinhard, reinhard-modified, hable, aces, aces-narkowicz, agx, "
                "pbr-neutral, got \"filmic\""},
        BadFile{"RenderSeed", doc(R"("render": {"seed": -1})"), "render.seed: must be an integer in [0, 4294967295], got -1"},
        BadFile{"RenderExposureWord", doc(R"("render": {"exposure": "bright"})"),
                "render.exposure: must be a number of stops in [-1000, 1000], \"auto\", \"auto+STOPS\" or "
                "\"auto-STOPS\", got \"bright\""},
        BadFile{"RenderExposureAutoSuffix", doc(R"("render": {"exposure": "auto*2"})"), "render.exposure: must be"},
        BadFile{"RenderExposureAutoHuge", doc(R"("render": {"exposure": "auto+1e9"})"), "render.exposure: must be"},
        BadFile{"RenderExposureHuge", doc(R"("render": {"exposure": -2000})"), "render.exposure: must be"},
        BadFile{"RenderUnknown", doc(R"("render": {"samples": 4})"),
                "render.samples: unknown field (expected one of: width, height, spp, max_bounces, seed, exposure, integrator, tonemap)"},
        // materials
        BadFile{"MaterialsNotAnObject", doc(R"("materials": [])"), "materials: must be an object, got []"},
        BadFile{"MaterialBaseColor", material(R"("base_color": [0.5, 1.2, 0.5])"),
                "materials.m.base_color[1]: must be in [0, 1], got 1.2"},
        BadFile{"MaterialRoughness", material(R"("roughness": 2)"), "materials.m.roughness: must be in [0, 1], got 2"},
        BadFile{"MaterialIor", material(R"("transmission": 1, "ior": 0.5)"), "materials.m.ior: must be in [1, 10], got 0.5"},
        BadFile{"MaterialType", material(R"("type": "glossy")"),
                "materials.m.type: must be \"pbr\" or \"lambert\", got \"glossy\""},
        BadFile{"LambertHasNoMetallic", material(R"("type": "lambert", "metallic": 1)"),
                "materials.m.metallic: unknown field (expected one of: type, base_color, emission, emission_strength, "
                "double_sided)"},
        BadFile{"MaterialAttenuationDistance", material(R"("transmission": 1, "attenuation_distance": 0)"),
                "materials.m.attenuation_distance: must be > 0, got 0"},
        BadFile{"MaterialNegativeEmission", material(R"("emission": [1, 1, -1])"),
                "materials.m.emission[2]: must be >= 0, got -1"},
        BadFile{"MaterialUnknown", material(R"("colour": [1, 1, 1])"), "materials.m.colour: unknown field"},
        BadFile{"MaterialNameQuoted", doc(R"("materials": {"my glass": {"ior": "x"}})"),
                "materials[\"my glass\"].ior: must be a number, got \"x\""},
        BadFile{"MaterialNameEmpty", doc(R"("materials": {"": {"roughness": 0.5}})"),
                "materials[\"\"]: a material needs a name"},
        BadFile{"MaterialEmissionBeyondFloat", material(R"("emission": [1e39, 0, 0])"),
                "materials.m.emission: is beyond the range of a float"},
        // the paths that every reader shares: a name that is not a string, an empty file name
        BadFile{"MaterialNameNotAString", sphere(R"(, "material": 3)"), "objects[0].material: must be a string, got 3"},
        BadFile{"GltfFileEmpty", objects(R"({"type": "gltf", "file": ""})"), "objects[0].file: must name a file, got \"\""},
        BadFile{"MeshFileEmpty", objects(R"({"type": "mesh", "file": ""})"), "objects[0].file: must name a file, got \"\""},
        BadFile{"CurvesFileEmpty", objects(R"({"type": "curves", "file": ""})"),
                "objects[0].file: must name a file, got \"\""},
        BadFile{"SdfFileEmpty", objects(R"({"type": "sdf", "file": ""})"), "objects[0].file: must name a file, got \"\""},
        BadFile{"DisplacedMeshEmpty", objects(R"({"type": "displaced", "mesh": "", "displacement": "map.exr", "scale": 1})"),
                "objects[0].mesh: must name a file, got \"\""},
        BadFile{"DisplacedMapEmpty",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "", "scale": 1})"),
                "objects[0].displacement: must name a file, got \"\""},
        BadFile{"DisplacedScaleBeyondFloat",
                objects(R"({"type": "displaced", "mesh": "square.ply", "displacement": "map.exr", "scale": 1e39})"),
                "objects[0]: scale and offset must be within the range of a float"},
        BadFile{"EnvironmentMapEmpty", doc(R"("environment": {"map": ""})"), "environment.map: must name a file, got \"\""},
        BadFile{"EnvironmentIntensityBeyondFloat", doc(R"("environment": {"map": "sky.hdr", "intensity": 1e39})"),
                "environment.intensity: is beyond the range of a float"},
        BadFile{"SpheresCentresNotAnArray", objects(R"({"type": "spheres", "centers": 3, "radius": 1})"),
                "objects[0].centers: must be an array of [x, y, z] centres, got 3"},
        BadFile{"CurvesStrandsNotAnArray", objects(R"({"type": "curves", "strands": 3})"),
                "objects[0].strands: must be an array of strands"},
        BadFile{"CurvesStrandsEmpty", objects(R"({"type": "curves", "strands": []})"),
                "objects[0].strands: must be an array of strands"},
        BadFile{"SdfBoxInsideOut", objects(R"({"type": "sdf", "file": "ball.raw", "resolution": [2, 2, 2], "box": [0, 0, 0, 1, 0, 1]})"),
                "objects[0].box: the maximum must exceed the minimum on every axis"},
};

INSTANTIATE_TEST_SUITE_P(All, SceneFileErrors, ::testing::ValuesIn(kBadFiles),
                         [](const ::testing::TestParamInfo<BadFile>& info) { return std::string(info.param.name); });

TEST(SceneFileErrorsMore, GltfErrorsAreNested) {
  writeFile(testDir() / "broken.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"mesh\": 4}]}");
  EXPECT_CONTAINS(errorOf(objects(gltfObject("", "broken.gltf"))),
                  "scene.json: objects[0].file: broken.gltf: node 0: references missing mesh 4");
}

TEST(SceneFileErrorsMore, CurveFileErrorsAreNested) {
  writeFile(testDir() / "broken.hair", hairFile(NAN));
  EXPECT_CONTAINS(errorOf(objects(R"({"type": "curves", "file": "broken.hair"})")),
                  "scene.json: objects[0].file: broken.hair: strand 0, point 1: coordinate is not finite (nan)");
  writeFile(testDir() / "short.hair", hairFile().substr(0, 150));
  EXPECT_CONTAINS(errorOf(objects(R"({"type": "curves", "file": "short.hair"})")),
                  "scene.json: objects[0].file: short.hair: the file ends at byte 150, inside the points array");
  writeFile(testDir() / "strands.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                       "property float z\nelement strand 1\nproperty ushort nsegs\nend_header\n0 0 0\n1 0 0\n1\n");
  EXPECT_CONTAINS(errorOf(objects(R"({"type": "curves", "file": "strands.ply"})")),
                  "scene.json: objects[0].radius: missing (required: strands.ply gives no radii)");
  EXPECT_EQ(loadText(objects(R"({"type": "curves", "file": "strands.ply", "radius": 0.1})")).scene.curves.size(), 1u);
}

TEST(SceneFileErrorsMore, MissingSceneFile) {
  try {
    loadSceneFile("/nonexistent/dir/scene.json");
    ADD_FAILURE() << "expected a SceneError";
  } catch (const SceneError& e) {
    EXPECT_CONTAINS(e.what(), "scene.json: cannot open /nonexistent/dir/scene.json (no such file)");
  }
}

TEST(SceneFileErrorsMore, FlattenedSceneIsLimited) {
  writeTriangle();
  GltfLoadOptions options;
  options.maxTriangles = 2;
  loadText(objects(gltfObject("") + "," + gltfObject("")), options);  // two triangles: fine
  EXPECT_CONTAINS(errorOf(objects(gltfObject("") + "," + gltfObject("") + "," + gltfObject("")), options),
                  "scene.json: objects[2]: brings the scene to 9 vertices and 3 triangles, more than the 268435456 and 2 supported");
}

/// "instances" is limited to 2^20 transforms an object, and the copies
/// count towards the scene's 2^28 spheres (checked before they are made).
TEST(SceneFileErrorsMore, InstancesAreLimited) {
  auto identities = [](std::size_t n) {
    std::string list = "[";
    for (std::size_t i = 0; i < n; ++i) list += i ? ",{}" : "{}";
    return list + "]";
  };
  EXPECT_CONTAINS(errorOf(sphere(", \"instances\": " + identities((1u << 20) + 1))),
                  "scene.json: objects[0].instances: holds 1048577 transforms, more than the 1048576 supported");
  std::string centers = "[";
  for (int i = 0; i < 257; ++i) centers += std::string(i ? "," : "") + "[" + std::to_string(i) + ", 0, 0]";
  centers += "]";
  EXPECT_CONTAINS(errorOf(objects(kSphere + R"(, {"type": "spheres", "radius": 0.1, "centers": )" + centers +
                                  R"(, "instances": )" + identities(1u << 20) + "}")),
                  "scene.json: objects[1]: brings the scene to 269484033 spheres (copies included), more than the "
                  "268435456 supported");
}

TEST(SceneFileErrorsMore, GltfOptionsWarnWhenSet) {
  GltfLoadOptions options;
  options.cameraIndex = 2;
  const Scene s = loadText(objects(kSphere), options).scene;
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_CONTAINS(s.warnings[0], "camera index applies to .gltf/.glb files");
}

// ---------------------------------------------------------------------------
// mutations: every input loads into a consistent scene or throws a SceneError
// that names the file

TEST(SceneFileFuzz, MutatedFilesNeverCrash) {
  const fs::path dir = testDir();
  writeTriangle();
  writeFile(dir / "sky.hdr", "x");
  const std::string text = doc(R"(
    "camera": {"from": [0, 1, 5], "to": [0, 1, 0], "up": [0, 1, 0], "fov": 30},
    "environment": {"map": "sky.hdr", "intensity": 2, "rotation": 15, "hidden": false},
    "render": {"width": 64, "height": 48, "spp": 4, "max_bounces": 3, "seed": 7, "exposure": 0.5, "integrator": "path"},
    "materials": {"a": {"base_color": [0.5, 0.5, 0.5], "metallic": 0.5, "roughness": 0.25, "emission": [1, 1, 1],
                        "emission_strength": 2, "double_sided": true, "transmission": 0.5, "ior": 1.4,
                        "thin_walled": false, "attenuation_color": [0.5, 0.5, 0.5], "attenuation_distance": 3},
                  "b": {"type": "lambert", "base_color": [0.1, 0.2, 0.3]}},
    "objects": [
      {"type": "gltf", "file": "triangle.gltf", "transform": {"translate": [1, 2, 3], "rotate": [0, 1, 0, 30], "scale": 2}},
      {"type": "gltf", "file": "triangle.gltf", "transform": {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 4,5,6,1]}},
      {"type": "sphere", "center": [0, -100, 0], "radius": 100, "material": "a"},
      {"type": "spheres", "centers": [[1, 0, 0], [2, 0, 0]], "radii": [0.5, 0.25], "material": "b"}
    ])");
  ASSERT_EQ(loadSceneFileFromMemory(text, "fuzz.json", dir.string()).scene.spheres.size(), 3u);
  std::mt19937 rng(20240611);
  auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  const std::string alphabet = "0123456789-+.eE[]{},:\" tfnaluxyz";
  int loaded = 0;
  for (int i = 0; i < 1500; ++i) {
    std::string mutant = text;
    for (std::size_t k = 1 + pick(3); k > 0; --k) {
      const std::size_t at = pick(mutant.size());
      switch (pick(4)) {
        case 0: mutant[at] = alphabet[pick(alphabet.size())]; break;
        case 1: mutant.erase(at, 1 + pick(8)); break;
        case 2: mutant.insert(at, 1, alphabet[pick(alphabet.size())]); break;
        default: mutant[at] = char(pick(256)); break;
      }
    }
    try {
      const Scene s = loadSceneFileFromMemory(mutant, "fuzz.json", dir.string()).scene;
      expectConsistent(s);
      ++loaded;
    } catch (const SceneError& e) {
      const std::string message = e.what();
      ASSERT_EQ(message.rfind("fuzz.json: ", 0), 0u) << "iteration " << i << ": " << message;
    }
  }
  EXPECT_GT(loaded, 0);  // the mutations also reach the end of the loader
}

}  // namespace
}  // namespace wt
