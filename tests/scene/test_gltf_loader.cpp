// glTF loader tests on files the tests write themselves: geometry and
// transforms checked numerically, every validation error checked for the
// file and element it names, and a mutation fuzz that must never crash.
#include "device/program.h"
#include "scene/generators.h"
#include "scene/gltf_doc.h"
#include "scene/gltf_loader.h"

#include "attribute_grid.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <stb_image_write.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace wt {
namespace {

using namespace gltf_doc;

constexpr float kEps = 1e-5f;

/// One triangle in the z = 0 plane, counter-clockwise seen from +z.
GltfDoc triangleDoc(bool indexed = true, const std::string& nodeExtra = "") {
  GltfDoc doc;
  int pos = doc.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  std::string prim = "{\"attributes\":{\"POSITION\":" + str(std::size_t(pos)) + "}";
  if (indexed) prim += ",\"indices\":" + str(std::size_t(doc.addIndices<std::uint16_t>({0, 1, 2})));
  doc.addMesh(prim + "}");
  doc.addNode("{\"mesh\":0" + nodeExtra + "}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  return doc;
}

/// A scratch file named after the running test, so parallel tests never share one.
std::filesystem::path scratchFile(const std::string& suffix) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : name)
    if (c == '/') c = '_';
  return test::scratchDir("gltf") / (name + suffix);
}

std::filesystem::path writeFile(const std::string& suffix, const std::string& contents) {
  std::filesystem::path path = scratchFile(suffix);
  std::ofstream(path, std::ios::binary).write(contents.data(), std::streamsize(contents.size()));
  return path;
}
std::filesystem::path writeFile(const std::string& suffix, const std::vector<unsigned char>& bytes) {
  return writeFile(suffix, std::string(bytes.begin(), bytes.end()));
}

Scene loadDoc(const GltfDoc& doc, const GltfLoadOptions& options = {}) {
  return loadGltf(writeFile(".gltf", doc.embedded()).string(), options);
}

/// The SceneError message of `load` (a failure when it throws none).
template <typename F>
std::string errorOf(F&& load) {
  try {
    load();
  } catch (const SceneError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a SceneError";
  return "";
}

/// The message names the file first, then the element.
std::string docError(const GltfDoc& doc, const GltfLoadOptions& options = {}) {
  std::string message = errorOf([&] { loadDoc(doc, options); });
  std::string file = scratchFile(".gltf").filename().string();
  EXPECT_EQ(message.rfind(file + ": ", 0), 0u) << "message does not start with the file name: " << message;
  return message;
}

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

/// World position of vertex v (the loader stores positions relative to Scene::origin).
glm::vec3 pos(const Scene& s, std::uint32_t v) {
  return glm::vec3(s.origin + glm::dvec3(s.positions[v].x, s.positions[v].y, s.positions[v].z));
}
/// World position of the camera.
glm::vec3 cameraPosition(const Scene& s) { return glm::vec3(s.origin + glm::dvec3(s.camera->cameraToWorld[3])); }
glm::vec3 nrm(const Scene& s, std::uint32_t v) {
  return {s.normals[v].x, s.normals[v].y, s.normals[v].z};
}
glm::vec3 geometricNormal(const Scene& s, std::size_t tri) {
  const WtTriangle& t = s.triangles[tri];
  return glm::cross(pos(s, t.v1) - pos(s, t.v0), pos(s, t.v2) - pos(s, t.v0));
}

void expectNear(const glm::vec3& actual, const glm::vec3& expected, float eps = kEps) {
  EXPECT_NEAR(actual.x, expected.x, eps);
  EXPECT_NEAR(actual.y, expected.y, eps);
  EXPECT_NEAR(actual.z, expected.z, eps);
}

/// What every loaded scene must satisfy, whatever the file said.
void expectConsistent(const Scene& s) {
  ASSERT_EQ(s.normals.size(), s.positions.size());
  ASSERT_EQ(s.texcoords.size(), s.positions.size());
  ASSERT_FALSE(s.materials.empty());
  ASSERT_EQ(s.materialNames.size(), s.materials.size());
  for (const WtTriangle& t : s.triangles) {
    ASSERT_LT(t.v0, s.positions.size());
    ASSERT_LT(t.v1, s.positions.size());
    ASSERT_LT(t.v2, s.positions.size());
    ASSERT_LT(t.material, s.materials.size());
  }
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    ASSERT_TRUE(std::isfinite(s.positions[i].x) && std::isfinite(s.positions[i].y) &&
                std::isfinite(s.positions[i].z));
    glm::vec3 n = nrm(s, std::uint32_t(i));
    float length = glm::length(n);
    ASSERT_TRUE(length == 0.0f || std::fabs(length - 1.0f) < 1e-4f) << "normal " << i;
  }
  for (const WtMaterial& m : s.materials) {
    for (float c : {m.base_color.x, m.base_color.y, m.base_color.z}) {
      ASSERT_GE(c, 0.0f);
      ASSERT_LE(c, 1.0f);
    }
  }
}

// ---------------------------------------------------------------------------
// geometry

TEST(GltfLoader, SingleTriangleIndexed) {
  Scene s = loadDoc(triangleDoc(true));
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 1u);
  ASSERT_EQ(s.positions.size(), 3u);
  const WtTriangle& t = s.triangles[0];
  expectNear(pos(s, t.v0), {0, 0, 0});
  expectNear(pos(s, t.v1), {1, 0, 0});
  expectNear(pos(s, t.v2), {0, 1, 0});
  // no NORMAL / TEXCOORD_0: the "none" values
  expectNear(nrm(s, 0), {0, 0, 0});
  EXPECT_EQ(s.texcoords[2], glm::vec2(0.0f));
  // no material: the specification's default (white, metallic 1, roughness 1)
  ASSERT_EQ(s.materials.size(), 1u);
  EXPECT_EQ(s.materialNames[0], "default");
  EXPECT_EQ(s.materials[0].model, WT_MATERIAL_PBR);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.y, 1.0f);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.w, 1.0f);
  EXPECT_FLOAT_EQ(s.materials[0].roughness, 1.0f);
  EXPECT_EQ(t.material, 0u);
  EXPECT_FALSE(s.camera.has_value());
  EXPECT_NE(s.sourceName.find(".gltf"), std::string::npos);
  EXPECT_TRUE(s.warnings.empty());
}

TEST(GltfLoader, GpuInstancingPlacesTheMeshOncePerInstance) {
  // EXT_mesh_gpu_instancing: world x T x R x S per instance, under the node's own transform
  GltfDoc doc = triangleDoc(true);
  int t = doc.addVec3({{10, 0, 0}, {0, 20, 0}, {0, 0, 30}});
  // (x, y, z, w): none, a quarter turn about z, none
  int r = doc.addAccessor(doc.addView(std::vector<glm::vec4>{{0, 0, 0, 1}, {0, 0, 0.70710678f, 0.70710678f}, {0, 0, 0, 1}}),
                          gltf_doc::kFloat, 3, "VEC4");
  int sc = doc.addVec3({{1, 1, 1}, {1, 1, 1}, {2, 2, 2}});
  doc.nodes[0] = "{\"mesh\":0,\"translation\":[0,0,-1],\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":"
                 "{\"TRANSLATION\":" + str(std::size_t(t)) + ",\"ROTATION\":" + str(std::size_t(r)) + ",\"SCALE\":" +
                 str(std::size_t(sc)) + "}}}}";
  doc.extensionsUsed = "[\"EXT_mesh_gpu_instancing\"]";
  GltfLoadOptions options;
  options.recenter = false;
  Scene s = loadDoc(doc, options);
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 3u);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
  // corner (1, 0, 0) of each copy
  expectNear(pos(s, s.triangles[0].v1), {11, 0, -1});
  expectNear(pos(s, s.triangles[1].v1), {0, 21, -1});  // turned onto +y
  expectNear(pos(s, s.triangles[2].v1), {2, 0, 29});   // scaled by 2
  // the copies are one geometry placed three times
  ASSERT_EQ(s.instances.size(), 3u);
  EXPECT_EQ(s.instances[0].geometry, s.instances[2].geometry);
}

TEST(GltfLoader, GpuInstancingErrorsNameTheNodeAndAttribute) {
  GltfDoc doc = triangleDoc(true);
  int t = doc.addVec3({{1, 0, 0}, {2, 0, 0}});
  int sc = doc.addVec3({{1, 1, 1}, {1, 1, 1}, {1, 1, 1}});
  doc.nodes[0] = "{\"mesh\":0,\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":{\"TRANSLATION\":" +
                 str(std::size_t(t)) + ",\"SCALE\":" + str(std::size_t(sc)) + "}}}}";
  EXPECT_CONTAINS(docError(doc), "node 0: EXT_mesh_gpu_instancing: ");
  EXPECT_CONTAINS(docError(doc), "instances");
  doc.nodes[0] = "{\"mesh\":0,\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":{}}}}";
  EXPECT_CONTAINS(docError(doc), "node 0: EXT_mesh_gpu_instancing: no TRANSLATION, ROTATION or SCALE");
  doc.nodes[0] = "{\"mesh\":0,\"extensions\":{\"EXT_mesh_gpu_instancing\":{\"attributes\":{\"ROTATION\":" +
                 str(std::size_t(t)) + "}}}}";
  EXPECT_CONTAINS(docError(doc), "ROTATION accessor has type VEC3, expected VEC4");
}

TEST(GltfLoader, SingleTriangleWithoutIndices) {
  Scene s = loadDoc(triangleDoc(false));
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_GT(geometricNormal(s, 0).z, 0.0f);
}

TEST(GltfLoader, GlbAndGltfGiveTheSameTriangle) {
  GltfDoc doc = triangleDoc();
  Scene fromGlb = loadGltf(writeFile(".glb", doc.glb()).string());
  ASSERT_EQ(fromGlb.triangles.size(), 1u);
  expectNear(pos(fromGlb, 1), {1, 0, 0});
  // the magic decides, not the extension
  Scene misnamed = loadGltf(writeFile(".gltf", doc.glb()).string());
  EXPECT_EQ(misnamed.triangles.size(), 1u);
  // a .glb without the magic is refused
  std::string message =
      errorOf([&] { loadGltf(writeFile("_text.glb", doc.embedded()).string()); });
  EXPECT_CONTAINS(message, "_text.glb: ");
  EXPECT_CONTAINS(message, "magic");
}

TEST(GltfLoader, GlbFromMemoryReadsWhatTheFileGives) {
  GltfDoc doc = triangleDoc();
  const std::vector<unsigned char> glb = doc.glb();
  Scene fromFile = loadGltf(writeFile(".glb", glb).string());
  Scene fromMemory = loadGlbFromMemory(glb, "memory.glb", ".");
  ASSERT_EQ(fromMemory.triangles.size(), fromFile.triangles.size());
  ASSERT_EQ(fromMemory.positions.size(), fromFile.positions.size());
  for (std::uint32_t v = 0; v < fromFile.positions.size(); ++v) expectNear(pos(fromMemory, v), pos(fromFile, v));
  EXPECT_EQ(fromMemory.sourceName, "memory.glb");
  // text is refused, as a .glb file without the magic is
  const std::string text = doc.embedded();
  std::string message = errorOf([&] {
    loadGlbFromMemory({reinterpret_cast<const unsigned char*>(text.data()), text.size()}, "text.glb", ".");
  });
  EXPECT_EQ(message.rfind("text.glb: ", 0), 0u) << message;
  EXPECT_CONTAINS(message, "magic");
  EXPECT_CONTAINS(errorOf([&] { loadGlbFromMemory({}, "empty.glb", "."); }), "empty.glb: ");
}

TEST(GltfLoader, ExternalBinBuffer) {
  GltfDoc doc = triangleDoc();
  std::string binName = scratchFile(".bin").filename().string();
  writeFile(".bin", doc.bin);
  std::filesystem::path gltf = writeFile(".gltf", doc.json(binName));
  Scene s = loadGltf(gltf.string());
  ASSERT_EQ(s.triangles.size(), 1u);
  expectNear(pos(s, 2), {0, 1, 0});

  // in memory, buffers resolve against baseDir
  Scene m = loadGltfFromMemory(doc.json(binName), "memory.gltf", gltf.parent_path().string());
  EXPECT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.sourceName, "memory.gltf");

  std::string message = errorOf([&] { loadGltfFromMemory(doc.json(binName), "memory.gltf", "/nonexistent"); });
  EXPECT_CONTAINS(message, "memory.gltf: ");
  EXPECT_CONTAINS(message, binName);
}

TEST(GltfLoader, NodeHierarchyTrsAndMatrix) {
  GltfDoc doc;
  int position = doc.addVec3({{1, 0, 0}, {0, 1, 0}, {0, 0, 0}});
  int normal = doc.addVec3({{1, 0, 0}, {1, 0, 0}, {1, 0, 0}});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + ",\"NORMAL\":" + str(normal) + "}}");
  // parent: T (1,2,3) * R (90 degrees about +z) * S 2; child: matrix translating by (0,0,5)
  const float h = std::sqrt(0.5f);
  doc.addNode("{\"translation\":[1,2,3],\"rotation\":[0,0," + num(h) + "," + num(h) +
              "],\"scale\":[2,2,2],\"children\":[1]}");
  doc.addNode("{\"matrix\":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,5,1],\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.positions.size(), 3u);
  // (1,0,0) -> child (1,0,5) -> scale (2,0,10) -> rotate (0,2,10) -> translate (1,4,13)
  expectNear(pos(s, 0), {1, 4, 13});
  // (0,1,0) -> (0,1,5) -> (0,2,10) -> (-2,0,10) -> (-1,2,13)
  expectNear(pos(s, 1), {-1, 2, 13});
  expectNear(pos(s, 2), {1, 2, 13});
  // normals rotate with the node and stay unit length
  expectNear(nrm(s, 0), {0, 1, 0});
}

TEST(GltfLoader, NormalsUseTheInverseTranspose) {
  GltfDoc doc;
  int position = doc.addVec3({{0, 0, 0}, {1, -1, 0}, {0, 0, 1}});
  const float r = std::sqrt(0.5f);
  // a unit normal, an unnormalized one, a zero one
  int normal = doc.addVec3({{r, r, 0}, {0, 0, 3}, {0, 0, 0}});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + ",\"NORMAL\":" + str(normal) + "}}");
  doc.addNode("{\"mesh\":0,\"scale\":[2,1,1]}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  expectConsistent(s);
  // the plane x + y = 0 becomes x/2 + y = 0, whose normal is (0.5, 1, 0)
  expectNear(nrm(s, 0), glm::normalize(glm::vec3(0.5f, 1.0f, 0.0f)));
  expectNear(nrm(s, 1), {0, 0, 1});
  expectNear(nrm(s, 2), {0, 0, 0});
}

TEST(GltfLoader, InterleavedByteStride) {
  struct Vertex {
    float position[3];
    float normal[3];
    float uv[2];
  };
  std::vector<Vertex> vertices = {
      {{0, 0, 0}, {0, 0, 1}, {0.0f, 0.25f}},
      {{2, 0, 0}, {0, 0, 1}, {0.5f, 0.75f}},
      {{0, 3, 0}, {0, 0, 1}, {1.0f, 1.0f}},
  };
  GltfDoc doc;
  int view = doc.addView(vertices, sizeof(Vertex));
  int position = doc.addAccessor(view, kFloat, 3, "VEC3");
  int normal = doc.addAccessor(view, kFloat, 3, "VEC3", ",\"byteOffset\":12");
  int uv = doc.addAccessor(view, kFloat, 3, "VEC2", ",\"byteOffset\":24");
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + ",\"NORMAL\":" + str(normal) +
              ",\"TEXCOORD_0\":" + str(uv) + "}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.positions.size(), 3u);
  expectNear(pos(s, 1), {2, 0, 0});
  expectNear(pos(s, 2), {0, 3, 0});
  expectNear(nrm(s, 1), {0, 0, 1});
  EXPECT_FLOAT_EQ(s.texcoords[1].x, 0.5f);
  EXPECT_FLOAT_EQ(s.texcoords[1].y, 0.75f);
  EXPECT_FLOAT_EQ(s.texcoords[0].y, 0.25f);
}

class GltfIndexType : public ::testing::TestWithParam<int> {};

TEST_P(GltfIndexType, QuadFromIndices) {
  GltfDoc doc;
  int position = doc.addVec3({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  // the indices start one byte into their view, to exercise accessor byteOffset
  std::vector<std::uint32_t> quad = {0, 1, 2, 0, 2, 3};
  int componentType = GetParam();
  std::vector<unsigned char> bytes(1, 0xEE);
  std::size_t size = componentType == kUByte ? 1 : componentType == kUShort ? 2 : 4;
  for (std::uint32_t i : quad)
    for (std::size_t b = 0; b < size; ++b) bytes.push_back(static_cast<unsigned char>(i >> (8 * b)));
  int view = doc.addView(bytes);
  int indices = doc.addAccessor(view, componentType, quad.size(), "SCALAR", ",\"byteOffset\":1");
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + "},\"indices\":" + str(indices) + "}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.triangles[1].v0, 0u);
  EXPECT_EQ(s.triangles[1].v1, 2u);
  EXPECT_EQ(s.triangles[1].v2, 3u);
  EXPECT_GT(geometricNormal(s, 0).z, 0.0f);
  EXPECT_GT(geometricNormal(s, 1).z, 0.0f);
}

INSTANTIATE_TEST_SUITE_P(ComponentTypes, GltfIndexType, ::testing::Values(kUByte, kUShort, kUInt),
                         [](const auto& info) {
                           return info.param == kUByte    ? std::string("UnsignedByte")
                                  : info.param == kUShort ? std::string("UnsignedShort")
                                                          : std::string("UnsignedInt");
                         });

TEST(GltfLoader, SparseAccessorOverBufferView) {
  GltfDoc doc;
  int base = doc.addView(std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}});
  int sparseIndices = doc.addView(std::vector<std::uint16_t>{1, 3});
  int sparseValues = doc.addView(std::vector<glm::vec3>{{2, 0, 0}, {7, 8, 9}});
  int position = doc.addAccessor(
      base, kFloat, 4, "VEC3",
      ",\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":" + str(sparseIndices) +
          ",\"componentType\":5123},\"values\":{\"bufferView\":" + str(sparseValues) + "}}");
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + "}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":" + str(position) +
                  "},\"indices\":" + str(doc.addIndices<std::uint8_t>({0, 1, 3})) + "}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.positions.size(), 4u);
  expectNear(pos(s, 0), {0, 0, 0});  // untouched
  expectNear(pos(s, 1), {2, 0, 0});  // replaced
  expectNear(pos(s, 2), {0, 1, 0});  // untouched
  expectNear(pos(s, 3), {7, 8, 9});  // replaced
}

TEST(GltfLoader, SparseAccessorWithoutBufferView) {
  GltfDoc doc;
  int sparseIndices = doc.addView(std::vector<std::uint8_t>{1, 2});
  int sparseValues = doc.addView(std::vector<glm::vec3>{{1, 0, 0}, {0, 1, 0}});
  int position = doc.addAccessor(
      -1, kFloat, 3, "VEC3",
      ",\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":" + str(sparseIndices) +
          ",\"componentType\":5121},\"values\":{\"bufferView\":" + str(sparseValues) + "}}");
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + "}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 1u);
  expectNear(pos(s, 0), {0, 0, 0});  // zeros where no sparse value lands
  expectNear(pos(s, 1), {1, 0, 0});
  expectNear(pos(s, 2), {0, 1, 0});
}

/// Five vertices zig-zagging along +x in the z = 0 plane; `mode` draws them.
GltfDoc fiveVertexDoc(int mode, const std::vector<glm::vec3>& vertices) {
  GltfDoc doc;
  int position = doc.addVec3(vertices);
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + "},\"mode\":" + str(mode) + "}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  return doc;
}

TEST(GltfLoader, TriangleStrip) {
  Scene s = loadDoc(fiveVertexDoc(5, {{0, 0, 0}, {0, -1, 0}, {1, 0, 0}, {1, -1, 0}, {2, 0, 0}}));
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 3u);
  // The first triangle (0,0,0) (0,-1,0) (1,0,0) is counter-clockwise seen
  // from +z; every other strip triangle is reversed, so all face +z.
  for (std::size_t t = 0; t < 3; ++t) EXPECT_GT(geometricNormal(s, t).z, 0.0f) << "triangle " << t;
  // triangle i uses vertices i, i+1, i+2
  for (std::size_t t = 0; t < 3; ++t) {
    const WtTriangle& tri = s.triangles[t];
    EXPECT_EQ(std::min({tri.v0, tri.v1, tri.v2}), t);
    EXPECT_EQ(std::max({tri.v0, tri.v1, tri.v2}), t + 2);
  }
}

TEST(GltfLoader, TriangleFan) {
  Scene s = loadDoc(fiveVertexDoc(6, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {-1, 1, 0}}));
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 3u);
  for (std::size_t t = 0; t < 3; ++t) {
    EXPECT_GT(geometricNormal(s, t).z, 0.0f) << "triangle " << t;
    const WtTriangle& tri = s.triangles[t];
    EXPECT_TRUE(tri.v0 == 0 || tri.v1 == 0 || tri.v2 == 0) << "fan triangle without the hub";
  }
}

TEST(GltfLoader, NonTriangleModesAreSkippedWithAWarning) {
  GltfDoc doc = triangleDoc();
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":1},"
                  "{\"attributes\":{\"POSITION\":0},\"mode\":0},"
                  "{\"attributes\":{\"POSITION\":0}}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  EXPECT_EQ(s.triangles.size(), 1u);
  ASSERT_EQ(s.warnings.size(), 2u);
  EXPECT_CONTAINS(s.warnings[0], "LINES");
  EXPECT_CONTAINS(s.warnings[1], "POINTS");
}

TEST(GltfLoader, NegativeScaleKeepsFrontFaces) {
  // Seen from +z the triangle is counter-clockwise, with normal +z.
  // Mirroring x keeps it facing +z; mirroring z turns it to face -z.
  struct Case {
    const char* scale;
    float facing;
  };
  for (Case c : {Case{"[1,1,1]", 1.0f}, Case{"[-1,1,1]", 1.0f}, Case{"[1,1,-1]", -1.0f}}) {
    SCOPED_TRACE(c.scale);
    GltfDoc doc;
    int position = doc.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    int normal = doc.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
    doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + ",\"NORMAL\":" + str(normal) + "}}");
    doc.addNode(std::string("{\"mesh\":0,\"scale\":") + c.scale + "}");
    doc.scenes.push_back("{\"nodes\":[0]}");
    Scene s = loadDoc(doc);
    ASSERT_EQ(s.triangles.size(), 1u);
    glm::vec3 geometric = glm::normalize(geometricNormal(s, 0));
    expectNear(geometric, {0, 0, c.facing});
    // and the shading normal agrees with the winding
    expectNear(nrm(s, s.triangles[0].v0), {0, 0, c.facing});
  }
}

TEST(GltfLoader, SharedMeshIsInstancedPerNode) {
  GltfDoc doc = triangleDoc();
  doc.addNode("{\"mesh\":0,\"translation\":[10,0,0]}");
  doc.scenes[0] = "{\"nodes\":[0,1]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 2u);
  expectNear(pos(s, s.triangles[1].v1), {11, 0, 0});
}

TEST(GltfLoader, PlacedCopiesShareAGeometry) {
  // nodes 0 and 1 place mesh 0; mesh 1 reads mesh 0's accessors (as
  // MetalRoughSpheres' 98 spheres do); mesh 2 has its own positions
  GltfDoc doc = triangleDoc();
  doc.addNode("{\"mesh\":0,\"translation\":[10,0,0]}");
  doc.addMesh("{\"attributes\":{\"POSITION\":0},\"indices\":1}");
  doc.addNode("{\"mesh\":1,\"translation\":[0,10,0]}");
  const int other = doc.addVec3({{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(other)) + "},\"indices\":" +
              str(std::size_t(doc.addIndices<std::uint16_t>({0, 1, 2, 1, 3, 2}))) + "}");
  doc.addNode("{\"mesh\":2}");
  doc.scenes[0] = "{\"nodes\":[0,1,2,3]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.triangles.size(), 5u);
  ASSERT_EQ(s.instances.size(), 4u);
  std::uint32_t covered = 0;
  for (const GeometryInstance& copy : s.instances) {
    EXPECT_EQ(copy.firstTriangle, covered);  // in triangle order, no gaps
    covered += copy.triangleCount;
  }
  EXPECT_EQ(covered, 5u);
  EXPECT_EQ(s.instances[0].geometry, s.instances[1].geometry);
  EXPECT_EQ(s.instances[0].geometry, s.instances[2].geometry);
  EXPECT_NE(s.instances[0].geometry, s.instances[3].geometry);
  EXPECT_EQ(s.instances[3].triangleCount, 2u);
}

// One mesh with every per-vertex attribute placed twice (turned; turned,
// scaled unevenly and mirrored): nodes sharing it, EXT_mesh_gpu_instancing
// and the mesh written out once per copy load the same vertices, and
// placeCopies places the mesh loaded alone the same way (within the float
// rounding of the loader's double placement). On the mirrored copy the
// bitangent's side flips, so the placed bitangent still points where the
// mesh's bitangent went.
TEST(GltfLoader, EveryLayoutAndPlaceCopiesKeepTheVertexAttributesOfEachCopy) {
  const test::Placement placements[] = {
      {{1.0f, 2.0f, 3.0f}, glm::angleAxis(0.7f, glm::normalize(glm::vec3(1.0f, 2.0f, 3.0f))), {1.0f, 1.0f, 1.0f}},
      {{-2.0f, 0.5f, 1.0f}, glm::angleAxis(-0.9f, glm::vec3(0.0f, 1.0f, 0.0f)), {1.5f, 0.5f, -2.0f}}};
  GltfLoadOptions options;
  options.recenter = false;
  const test::Placement identity;
  const Scene mesh = loadDoc(test::attributeGridDoc(2, std::span(&identity, 1), test::GridLayout::kNodesShareAMesh), options);
  ASSERT_EQ(mesh.positions.size(), 9u);
  ASSERT_EQ(mesh.colors.size(), 9u);
  ASSERT_EQ(mesh.tangents.size(), 9u);
  ASSERT_EQ(mesh.texcoords1.size(), 9u);
  const glm::mat4 transforms[] = {placements[0].matrix(), placements[1].matrix()};
  const Scene placed = placeCopies(mesh, transforms);
  const float eps = 1e-5f;  // float rounding of coordinates below 10
  const auto same = [&](glm::vec4 a, glm::vec4 b, const std::string& what) {
    return glm::all(glm::lessThanEqual(glm::abs(a - b), glm::vec4(eps))) ? ::testing::AssertionSuccess()
                                                                         : ::testing::AssertionFailure() << what;
  };
  const auto vec = [](const WtVec4& v) { return glm::vec4(v.x, v.y, v.z, v.w); };
  for (test::GridLayout layout :
       {test::GridLayout::kNodesShareAMesh, test::GridLayout::kGpuInstancing, test::GridLayout::kMeshPerCopy}) {
    SCOPED_TRACE("layout " + std::to_string(int(layout)));
    const Scene s = loadDoc(test::attributeGridDoc(2, placements, layout), options);
    expectConsistent(s);
    ASSERT_EQ(s.positions.size(), placed.positions.size());
    ASSERT_EQ(s.colors.size(), placed.colors.size());
    ASSERT_EQ(s.tangents.size(), placed.tangents.size());
    ASSERT_EQ(s.texcoords1.size(), placed.texcoords1.size());
    ASSERT_EQ(s.triangles.size(), placed.triangles.size());
    ASSERT_EQ(s.instances.size(), 2u);
    EXPECT_EQ(s.instances[0].geometry == s.instances[1].geometry, layout != test::GridLayout::kMeshPerCopy);
    for (std::size_t t = 0; t < s.triangles.size(); ++t) {
      const WtTriangle &a = s.triangles[t], &b = placed.triangles[t];
      EXPECT_TRUE(a.v0 == b.v0 && a.v1 == b.v1 && a.v2 == b.v2 && a.material == b.material) << "triangle " << t;
    }
    for (std::size_t v = 0; v < s.positions.size(); ++v) {
      const std::string at = "vertex " + std::to_string(v);
      EXPECT_TRUE(same(vec(s.positions[v]), vec(placed.positions[v]), "position at " + at));
      EXPECT_TRUE(same(vec(s.normals[v]), vec(placed.normals[v]), "normal at " + at));
      EXPECT_TRUE(same(glm::vec4(s.texcoords[v], s.texcoords1[v]), glm::vec4(placed.texcoords[v], placed.texcoords1[v]),
                       "texture coordinates at " + at));
      EXPECT_TRUE(same(s.colors[v], placed.colors[v], "colour at " + at));
      EXPECT_TRUE(same(s.tangents[v], placed.tangents[v], "tangent at " + at));
      // the copy's own data: the mesh's colour, and its bitangent carried along
      const std::size_t source = v % mesh.positions.size();
      EXPECT_EQ(placed.colors[v], mesh.colors[source]) << at;
      const glm::mat3 linear(transforms[v / mesh.positions.size()]);
      const glm::vec4 t = mesh.tangents[source];
      const glm::vec3 n(vec(mesh.normals[source])), bitangent = t.w * glm::cross(n, glm::vec3(t));
      const glm::vec4 tp = s.tangents[v];
      const glm::vec3 np(vec(s.normals[v])), placedBitangent = tp.w * glm::cross(np, glm::vec3(tp));
      EXPECT_GT(glm::dot(placedBitangent, linear * bitangent), 0.0f) << "the bitangent turned over at " << at;
    }
  }
}

TEST(GltfLoader, DeepHierarchyDoesNotOverflowTheStack) {
  GltfDoc doc = triangleDoc();
  const std::size_t depth = 50000;
  doc.nodes.clear();
  for (std::size_t i = 0; i + 1 < depth; ++i)
    doc.addNode("{\"translation\":[1,0,0],\"children\":[" + str(i + 1) + "]}");
  doc.addNode("{\"mesh\":0}");
  Scene s = loadDoc(doc);
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(pos(s, 0).x, float(depth - 1));  // exact: small integers
}

TEST(GltfLoader, NormalizedTexcoords) {
  GltfDoc doc = triangleDoc();
  int bytes = doc.addView(std::vector<std::uint8_t>{0, 255, 255, 0, 51, 102});
  int ubyteUv = doc.addAccessor(bytes, kUByte, 3, "VEC2", ",\"normalized\":true");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":" + str(ubyteUv) + "}}]}";
  Scene s = loadDoc(doc);
  EXPECT_FLOAT_EQ(s.texcoords[0].x, 0.0f);
  EXPECT_FLOAT_EQ(s.texcoords[0].y, 1.0f);
  EXPECT_FLOAT_EQ(s.texcoords[2].x, 0.2f);
  EXPECT_FLOAT_EQ(s.texcoords[2].y, 0.4f);

  int shorts = doc.addView(std::vector<std::uint16_t>{65535, 0, 0, 0, 0, 13107});
  int ushortUv = doc.addAccessor(shorts, kUShort, 3, "VEC2", ",\"normalized\":true");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":" + str(ushortUv) + "}}]}";
  s = loadDoc(doc);
  EXPECT_FLOAT_EQ(s.texcoords[0].x, 1.0f);
  EXPECT_FLOAT_EQ(s.texcoords[2].y, 0.2f);

  // integers must be normalized to be texture coordinates
  doc.accessors[std::size_t(ushortUv)] =
      "{\"bufferView\":" + str(shorts) + ",\"componentType\":5123,\"count\":3,\"type\":\"VEC2\"}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: TEXCOORD_0 accessor has UNSIGNED_SHORT components that are not normalized");
}

TEST(GltfLoader, EmptySceneIsNotAnError) {
  GltfDoc doc = triangleDoc();
  doc.scenes[0] = "{\"nodes\":[]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  EXPECT_TRUE(s.triangles.empty());
  EXPECT_EQ(s.materials.size(), 1u);  // never empty
}

TEST(GltfLoader, NoScenesDrawsRootNodes) {
  GltfDoc doc = triangleDoc();
  doc.scenes.clear();
  Scene s = loadDoc(doc);
  EXPECT_EQ(s.triangles.size(), 1u);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_CONTAINS(s.warnings[0], "no scenes");
}

TEST(GltfLoader, SceneSelection) {
  GltfDoc doc = triangleDoc();
  doc.addNode("{\"mesh\":0,\"translation\":[0,0,1]}");
  doc.scenes.push_back("{\"nodes\":[0,1]}");
  doc.scene = 1;
  EXPECT_EQ(loadDoc(doc).triangles.size(), 2u);  // the default scene
  GltfLoadOptions options;
  options.sceneIndex = 0;
  EXPECT_EQ(loadDoc(doc, options).triangles.size(), 1u);
  options.sceneIndex = 2;
  EXPECT_CONTAINS(docError(doc, options), "scene 2 out of range (2 scenes)");
  doc.scene = 5;
  EXPECT_CONTAINS(docError(doc), "default scene 5 does not exist");
}

// ---------------------------------------------------------------------------
// cameras

GltfDoc cameraDoc() {
  GltfDoc doc = triangleDoc();
  doc.cameras.push_back(
      "{\"type\":\"perspective\",\"name\":\"persp\",\"perspective\":{\"yfov\":0.7,\"aspectRatio\":1.5,"
      "\"znear\":0.01,\"zfar\":100}}");
  doc.cameras.push_back(
      "{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":2,\"ymag\":3,\"znear\":0.5,\"zfar\":10}}");
  doc.addNode("{\"camera\":0,\"translation\":[0.5,0.5,3]}");
  doc.addNode("{\"camera\":1,\"name\":\"orthoNode\",\"translation\":[0,0,-4]}");
  doc.scenes[0] = "{\"nodes\":[0,1,2]}";
  return doc;
}

TEST(GltfLoader, PerspectiveCamera) {
  Scene s = loadDoc(cameraDoc());
  ASSERT_TRUE(s.camera.has_value());
  const CameraDesc& c = *s.camera;
  EXPECT_FALSE(c.orthographic);
  EXPECT_FLOAT_EQ(c.yfov, 0.7f);
  EXPECT_FLOAT_EQ(c.aspectRatio, 1.5f);
  EXPECT_FLOAT_EQ(c.znear, 0.01f);
  EXPECT_EQ(c.name, "persp");
  expectNear(cameraPosition(s), {0.5f, 0.5f, 3.0f});
}

TEST(GltfLoader, OrthographicCameraByIndex) {
  GltfLoadOptions options;
  options.cameraIndex = 1;
  Scene s = loadDoc(cameraDoc(), options);
  ASSERT_TRUE(s.camera.has_value());
  const CameraDesc& c = *s.camera;
  EXPECT_TRUE(c.orthographic);
  EXPECT_FLOAT_EQ(c.xmag, 2.0f);
  EXPECT_FLOAT_EQ(c.ymag, 3.0f);
  EXPECT_FLOAT_EQ(c.znear, 0.5f);
  EXPECT_EQ(c.name, "orthoNode");  // the camera has no name; the node has
  expectNear(cameraPosition(s), {0, 0, -4});

  options.cameraIndex = 2;
  EXPECT_CONTAINS(docError(cameraDoc(), options), "camera 2 out of range (2 camera nodes");
}

// The scene is stored relative to the camera in double precision: the same
// scene under a root node 1e6 units away gives the very same float
// coordinates (bit for bit), although 1e6 + 0.1 has no float of its own.
TEST(GltfLoader, SceneIsStoredRelativeToTheCameraExactly) {
  auto placed = [](const std::string& rootTranslation) {
    GltfDoc doc;
    doc.addVec3({{0.1f, 0.2f, -0.3f}, {1.3f, 0.1f, -0.2f}, {0.2f, 1.7f, 0.05f}});
    doc.addMesh("{\"attributes\":{\"POSITION\":0}}");
    doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.01}}");
    doc.addNode("{\"mesh\":0,\"rotation\":[0,0.2588190451,0,0.9659258263]}");
    doc.addNode("{\"camera\":0,\"translation\":[0.25,0.5,3]}");
    doc.addNode("{\"children\":[0,1]" + rootTranslation + "}");
    doc.scenes.push_back("{\"nodes\":[2]}");
    return loadDoc(doc);
  };
  Scene here = placed(""), far = placed(",\"translation\":[1000000,-1000000,1000000]");
  ASSERT_EQ(here.positions.size(), far.positions.size());
  for (std::size_t v = 0; v < here.positions.size(); ++v) {
    EXPECT_EQ(here.positions[v].x, far.positions[v].x) << "vertex " << v;
    EXPECT_EQ(here.positions[v].y, far.positions[v].y) << "vertex " << v;
    EXPECT_EQ(here.positions[v].z, far.positions[v].z) << "vertex " << v;
  }
  EXPECT_EQ(glm::vec3(far.camera->cameraToWorld[3]), glm::vec3(0.0f));
  EXPECT_EQ(far.origin, glm::dvec3(1000000.25, -999999.5, 1000003.0));
  expectNear(cameraPosition(far), {1000000.25f, -999999.5f, 1000003.0f}, 0.07f);
}

TEST(GltfLoader, WithoutACameraTheOriginIsTheCentreOfTheGeometry) {
  Scene s = loadDoc(triangleDoc(true, ",\"translation\":[100,0,-50]"));
  EXPECT_EQ(s.origin, glm::dvec3(100.5, 0.5, -50.0));
  expectNear(pos(s, 1), {101, 0, -50});
  GltfLoadOptions options;
  options.recenter = false;  // world coordinates as the file has them
  Scene world = loadDoc(triangleDoc(true, ",\"translation\":[100,0,-50]"), options);
  EXPECT_EQ(world.origin, glm::dvec3(0.0));
  EXPECT_EQ(world.positions[1].x, 101.0f);
}

TEST(GltfLoader, LightsMoveWithTheOrigin) {
  GltfDoc doc = triangleDoc(true, ",\"translation\":[5000,0,0]");
  doc.extensionsUsed = "[\"KHR_lights_punctual\"]";
  doc.addNode("{\"translation\":[5000,2,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");
  doc.scenes[0] = "{\"nodes\":[0,1]}";
  std::string text = doc.embedded();
  text.insert(text.size() - 1, ",\"extensions\":{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"point\"}]}}");
  Scene s = loadGltf(writeFile(".gltf", text).string());
  ASSERT_EQ(s.lights.size(), 1u);
  expectNear(glm::vec3(s.origin + glm::dvec3(s.lights[0].position)), {5000, 2, 0});
  expectNear(glm::vec3(s.lights[0].position), {-0.5f, 1.5f, 0.0f});
}

TEST(GltfLoader, ZeroScaleAndZeroAreaTrianglesLoadWithAWarning) {
  Scene flat = loadDoc(triangleDoc(true, ",\"scale\":[1,0,1]"));
  EXPECT_EQ(flat.triangles.size(), 1u);
  ASSERT_GE(flat.warnings.size(), 1u);
  EXPECT_CONTAINS(::testing::PrintToString(flat.warnings), "node 0: its transform is singular");
  EXPECT_CONTAINS(::testing::PrintToString(flat.warnings), "1 of 1 triangles have zero area");
  for (std::size_t v = 0; v < flat.normals.size(); ++v) EXPECT_TRUE(std::isfinite(flat.normals[v].x));

  GltfDoc doc;
  doc.addVec3({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0, 1, 0}});
  doc.addIndices<std::uint16_t>({0, 1, 2, 0, 1, 3, 3, 3, 3});
  doc.addMesh("{\"attributes\":{\"POSITION\":0},\"indices\":1}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  Scene s = loadDoc(doc);
  EXPECT_EQ(s.triangles.size(), 3u);
  EXPECT_CONTAINS(::testing::PrintToString(s.warnings),
                  "2 of 3 triangles have zero area (repeated or collinear corners, first: mesh 0, primitive 0 "
                  "(node 0), triangle 0)");
}

TEST(GltfLoader, CameraUnderARotatedParent) {
  GltfDoc doc = cameraDoc();
  // rotate the perspective camera 90 degrees about +y: it now looks down -x
  const float h = std::sqrt(0.5f);
  doc.addNode("{\"rotation\":[0," + num(h) + ",0," + num(h) + "],\"children\":[1]}");
  doc.scenes[0] = "{\"nodes\":[0,3]}";
  Scene s = loadDoc(doc);
  ASSERT_TRUE(s.camera.has_value());
  glm::vec3 forward = -glm::vec3(s.camera->cameraToWorld[2]);
  expectNear(forward, {-1, 0, 0});
  expectNear(cameraPosition(s), {3, 0.5f, -0.5f});
}

// A scene scaled by 1e-3 with its camera: the near plane is a distance in the
// camera node's units, so it shrinks with the scene. Unscaled (0.1 in the
// world) it lay beyond the triangle 0.05 away and the image was black.
TEST(GltfLoader, CameraNearPlaneFollowsTheNodeScale) {
  GltfDoc doc = triangleDoc();
  doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.1,\"zfar\":100}}");
  doc.addNode("{\"camera\":0,\"translation\":[0.25,0.25,50]}");
  doc.addNode("{\"scale\":[0.001,0.001,0.001],\"children\":[0,1]}");
  doc.scenes[0] = "{\"nodes\":[2]}";
  Scene s = loadDoc(doc);
  ASSERT_TRUE(s.camera.has_value());
  const CameraDesc& c = *s.camera;
  expectNear(cameraPosition(s), {0.00025f, 0.00025f, 0.05f}, 1e-7f);
  EXPECT_NEAR(c.znear, 1e-4f, 1e-9f);
  EXPECT_FLOAT_EQ(c.yfov, 0.7f);  // an angle: no scale

  // the centre ray starts at tmin = forward.w (generate.cl) and must reach the triangle
  WtCamera cam = makeCamera(c, 64, 32);
  const float triangleDistance = 0.05f;  // world, from the camera to the z = 0 plane
  EXPECT_LT(cam.forward.w, triangleDistance);
  EXPECT_NEAR(cam.forward.w, 1e-4f, 1e-9f);
  expectNear({cam.forward.x, cam.forward.y, cam.forward.z}, {0, 0, -1});
  // the frustum is the file's: unit axes times tan(yfov/2), the image's aspect
  const float tanHalf = std::tan(0.35f);
  expectNear({cam.up.x, cam.up.y, cam.up.z}, {0, tanHalf, 0});
  expectNear({cam.right.x, cam.right.y, cam.right.z}, {2.0f * tanHalf, 0, 0});

  // an orthographic camera's extents are in the node's units too
  doc.cameras[0] = "{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":2,\"ymag\":3,\"znear\":0.1,\"zfar\":10}}";
  Scene ortho = loadDoc(doc);
  ASSERT_TRUE(ortho.camera.has_value());
  EXPECT_TRUE(ortho.camera->orthographic);
  EXPECT_NEAR(ortho.camera->znear, 1e-4f, 1e-9f);
  EXPECT_NEAR(ortho.camera->xmag, 2e-3f, 1e-8f);
  EXPECT_NEAR(ortho.camera->ymag, 3e-3f, 1e-8f);
}

// A non-uniform parent scale under a rotated camera shears its axes: the
// view direction is kept, the basis made orthonormal (glTF camera nodes are
// meant to be rigid), and the near plane scales with the node's -Z axis.
TEST(GltfLoader, ShearedCameraNodeKeepsItsViewDirectionWithRigidAxes) {
  GltfDoc doc = triangleDoc();
  doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.1}}");
  const float halfAngle = 0.5f * glm::radians(45.0f);  // 45 degrees about +x
  doc.addNode("{\"camera\":0,\"rotation\":[" + num(std::sin(halfAngle)) + ",0,0," + num(std::cos(halfAngle)) +
              "],\"translation\":[0,0,5]}");
  doc.addNode("{\"scale\":[1,4,1],\"children\":[1]}");
  doc.scenes[0] = "{\"nodes\":[0,2]}";
  Scene s = loadDoc(doc);
  ASSERT_TRUE(s.camera.has_value());
  const glm::mat4& m = s.camera->cameraToWorld;
  const glm::vec3 x(m[0]), y(m[1]), z(m[2]);
  // the node's -Z: (0, sin 45, -cos 45) rotated, then y times 4
  expectNear(-z, glm::normalize(glm::vec3(0, 4, -1)));
  EXPECT_NEAR(glm::length(x), 1.0f, kEps);
  EXPECT_NEAR(glm::length(y), 1.0f, kEps);
  EXPECT_NEAR(glm::dot(x, y), 0.0f, kEps);
  EXPECT_NEAR(glm::dot(y, z), 0.0f, kEps);
  EXPECT_NEAR(glm::dot(x, z), 0.0f, kEps);
  EXPECT_NEAR(glm::dot(glm::cross(x, y), z), 1.0f, kEps);  // still right-handed
  EXPECT_GT(y.y, 0.0f);                                     // up stays up
  EXPECT_NEAR(s.camera->znear, 0.1f * std::sqrt(8.5f), 1e-6f);  // |node Z| = |(0, -4 sin 45, cos 45)|
  expectNear(cameraPosition(s), {0, 0, 5});
}

// ---------------------------------------------------------------------------
// materials and warnings

TEST(GltfLoader, EmissiveStrength) {
  GltfDoc doc = triangleDoc();
  doc.materials.push_back(
      "{\"name\":\"lamp\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
      "\"emissiveFactor\":[1,0.5,0],\"extensions\":{"
      "\"KHR_materials_emissive_strength\":{\"emissiveStrength\":4}}}");
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"emissiveFactor\":[0.25,0.5,1]}");
  doc.extensionsUsed = "[\"KHR_materials_emissive_strength\"]";
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.materials.size(), 2u);  // no default needed
  EXPECT_EQ(s.materialNames[0], "lamp");
  EXPECT_FLOAT_EQ(s.materials[0].emission.x, 4.0f);
  EXPECT_FLOAT_EQ(s.materials[0].emission.y, 2.0f);
  EXPECT_FLOAT_EQ(s.materials[0].emission.z, 0.0f);
  EXPECT_FLOAT_EQ(s.materials[1].emission.z, 1.0f);  // strength defaults to 1
  EXPECT_FLOAT_EQ(s.materials[0].base_color.x, 1.0f);  // baseColorFactor defaults to 1
  EXPECT_EQ(s.triangles[1].material, 1u);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings[0];
}

// KHR_materials_transmission, _ior and _volume: the factor, the index, a
// volume boundary or a thin wall, and the absorption coefficient from the
// attenuation colour and distance (-ln(colour) / distance).
TEST(GltfLoader, TransmissionIorAndVolume) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_materials_transmission\",\"KHR_materials_ior\",\"KHR_materials_volume\"]";
  doc.materials.push_back(
      "{\"name\":\"glass\",\"pbrMetallicRoughness\":{\"metallicFactor\":0,\"roughnessFactor\":0.1},"
      "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":0.75},"
      "\"KHR_materials_ior\":{\"ior\":1.33},"
      "\"KHR_materials_volume\":{\"thicknessFactor\":0.5,\"attenuationDistance\":2,"
      "\"attenuationColor\":[0.5,0.25,1]}}}");
  doc.materials.push_back(  // no volume: a thin wall
      "{\"name\":\"window\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
      "\"extensions\":{\"KHR_materials_transmission\":{\"transmissionFactor\":1}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.materials.size(), 2u);
  const WtMaterial& g = s.materials[0];
  EXPECT_FLOAT_EQ(g.transmission, 0.75f);
  EXPECT_FLOAT_EQ(g.ior, 1.33f);
  EXPECT_EQ(g.volume.w, 1.0f);
  EXPECT_NEAR(g.volume.x, std::log(2.0) / 2.0, 1e-6);
  EXPECT_NEAR(g.volume.y, std::log(4.0) / 2.0, 1e-6);
  EXPECT_EQ(g.volume.z, 0.0f);
  const WtMaterial& w = s.materials[1];
  EXPECT_FLOAT_EQ(w.transmission, 1.0f);
  EXPECT_FLOAT_EQ(w.ior, 1.5f);
  EXPECT_EQ(w.volume.w, 0.0f);
  // ior 1.33 on a material that is a quarter opaque: its opaque part's F0 follows it too, nothing to warn about
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.at(0);
}

TEST(GltfLoader, BadTransmissionValuesAreClampedOrRefused) {
  auto load = [](const std::string& extensions) {
    GltfDoc doc = triangleDoc();
    doc.extensionsUsed = "[\"KHR_materials_transmission\",\"KHR_materials_ior\",\"KHR_materials_volume\"]";
    doc.materials.push_back("{\"name\":\"m\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{" +
                            extensions + "}}");
    doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
    return doc;
  };
  const std::string t = "\"KHR_materials_transmission\":{\"transmissionFactor\":1}";
  Scene clamped = loadDoc(load("\"KHR_materials_transmission\":{\"transmissionFactor\":1.5},"
                               "\"KHR_materials_ior\":{\"ior\":0.5}"));
  EXPECT_EQ(clamped.materials[0].transmission, 1.0f);
  EXPECT_EQ(clamped.materials[0].ior, 1.0f);
  ASSERT_EQ(clamped.warnings.size(), 2u);
  EXPECT_CONTAINS(clamped.warnings[0], "transmissionFactor 1.500000 is outside [0,1]; clamped");
  EXPECT_CONTAINS(clamped.warnings[1], "ior 0.500000 is outside [1,10]; clamped");
  Scene zero = loadDoc(load(t + ",\"KHR_materials_ior\":{\"ior\":0}"));
  EXPECT_EQ(zero.materials[0].ior, 1.5f);
  EXPECT_CONTAINS(zero.warnings.at(0), "ior 0");
  Scene thin = loadDoc(load(t + ",\"KHR_materials_volume\":{\"attenuationDistance\":1,\"attenuationColor\":[0.5,0.5,0.5]}"));
  EXPECT_EQ(thin.materials[0].volume.w, 0.0f);
  EXPECT_CONTAINS(thin.warnings.at(0), "attenuation of a thin-walled material (thicknessFactor 0) has no effect");
  Scene black = loadDoc(load(t + ",\"KHR_materials_volume\":{\"thicknessFactor\":1,\"attenuationDistance\":1,"
                                 "\"attenuationColor\":[0,1,1]}"));
  EXPECT_GT(black.materials[0].volume.x, 100.0f);  // no light left after any distance worth the name
  EXPECT_TRUE(std::isfinite(black.materials[0].volume.x));
  Scene unused = loadDoc(load("\"KHR_materials_volume\":{\"thicknessFactor\":1}"));
  EXPECT_CONTAINS(unused.warnings.at(0), "KHR_materials_volume without transmission has no effect");
  EXPECT_CONTAINS(docError(load(t + ",\"KHR_materials_volume\":{\"thicknessFactor\":1,\"attenuationDistance\":0}")),
                  "material 0 'm' KHR_materials_volume: attenuationDistance 0.000000 is not positive");
  EXPECT_CONTAINS(docError(load(t + ",\"KHR_materials_volume\":{\"thicknessFactor\":-1}")),
                  "thicknessFactor -1.000000 is negative");
  EXPECT_CONTAINS(docError(load("\"KHR_materials_transmission\":{\"transmissionFactor\":\"x\"}")),
                  "material 0 'm' KHR_materials_transmission: transmissionFactor is not a finite number");
  EXPECT_CONTAINS(docError(load(t + ",\"KHR_materials_volume\":{\"thicknessFactor\":1,\"attenuationColor\":[1,1]}")),
                  "attenuationColor is not an array of 3 numbers");
}

// The nested-dielectric priority from the material's extras
// (docs/materials.md, "Nested dielectrics"): 0 without it, a warning where
// it cannot matter, an error naming the material where it is no integer.
TEST(GltfLoader, NestedPriorityComesFromTheMaterialExtras) {
  auto load = [](const std::string& extras, bool volume = true) {
    GltfDoc doc = triangleDoc();
    doc.extensionsUsed = "[\"KHR_materials_transmission\",\"KHR_materials_volume\"]";
    doc.materials.push_back("{\"name\":\"m\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{"
                            "\"KHR_materials_transmission\":{\"transmissionFactor\":1}" +
                            std::string(volume ? ",\"KHR_materials_volume\":{\"thicknessFactor\":1}" : "") + "}" +
                            (extras.empty() ? "" : ",\"extras\":" + extras) + "}");
    doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
    return doc;
  };
  EXPECT_EQ(loadDoc(load("")).materials[0].priority, 0u);
  EXPECT_EQ(loadDoc(load("{\"author\":\"x\"}")).materials[0].priority, 0u);
  Scene glass = loadDoc(load("{\"wavetrace\":{\"priority\":7}}"));
  EXPECT_EQ(glass.materials[0].priority, 7u);
  EXPECT_TRUE(glass.warnings.empty()) << glass.warnings.at(0);
  EXPECT_EQ(loadDoc(load("{\"wavetrace\":{\"priority\":2147483647}}")).materials[0].priority, 2147483647u);
  Scene thin = loadDoc(load("{\"wavetrace\":{\"priority\":3}}", false));
  EXPECT_CONTAINS(thin.warnings.at(0), "material 0 'm' extras.wavetrace.priority has no effect");
  for (const char* bad : {"-1", "1.5", "\"high\"", "2147483648"})
    EXPECT_CONTAINS(docError(load(std::string("{\"wavetrace\":{\"priority\":") + bad + "}}")),
                    "material 0 'm' extras.wavetrace.priority is not an integer in [0, 2147483647]")
        << bad;
  EXPECT_CONTAINS(docError(load("{\"wavetrace\":3}")), "material 0 'm' extras.wavetrace is not an object");
}

// KHR_materials_dispersion: 20 / Abbe number on a volume boundary; a
// warning elsewhere, an error naming the material when negative.
TEST(GltfLoader, DispersionIsReadOnVolumeBoundaries) {
  auto load = [](const std::string& dispersion, bool volume = true) {
    GltfDoc doc = triangleDoc();
    doc.extensionsUsed = "[\"KHR_materials_transmission\",\"KHR_materials_volume\",\"KHR_materials_dispersion\"]";
    doc.materials.push_back("{\"name\":\"m\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"extensions\":{"
                            "\"KHR_materials_transmission\":{\"transmissionFactor\":1}," +
                            std::string(volume ? "\"KHR_materials_volume\":{\"thicknessFactor\":1}," : "") +
                            "\"KHR_materials_dispersion\":{" + dispersion + "}}}");
    doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
    return doc;
  };
  Scene glass = loadDoc(load("\"dispersion\":0.33"));
  EXPECT_FLOAT_EQ(glass.materials[0].dispersion, 0.33f);
  EXPECT_TRUE(glass.warnings.empty()) << glass.warnings.at(0);  // a supported extension: no warning
  EXPECT_EQ(loadDoc(load("")).materials[0].dispersion, 0.0f);
  Scene thin = loadDoc(load("\"dispersion\":1", false));
  EXPECT_EQ(thin.materials[0].dispersion, 0.0f);
  EXPECT_CONTAINS(thin.warnings.at(0), "material 0 'm' KHR_materials_dispersion has no effect on a material that bounds no volume");
  EXPECT_CONTAINS(docError(load("\"dispersion\":-0.5")), "material 0 'm' KHR_materials_dispersion: dispersion -0.500000 is negative");
  EXPECT_CONTAINS(docError(load("\"dispersion\":\"x\"")), "dispersion is not a finite number");
}

// KHR_materials_specular, _clearcoat, _sheen and _ior without
// transmission: their factors (defaults where absent), their textures
// warned about like every material texture.
TEST(GltfLoader, LayerExtensionsReadTheirFactors) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_materials_specular\",\"KHR_materials_clearcoat\",\"KHR_materials_sheen\","
                       "\"KHR_materials_ior\"]";
  doc.materials.push_back(
      "{\"name\":\"velvet\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
      "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0.3,\"specularColorFactor\":[1,0.5,2]},"
      "\"KHR_materials_ior\":{\"ior\":1.8},"
      "\"KHR_materials_clearcoat\":{\"clearcoatFactor\":0.7,\"clearcoatRoughnessFactor\":0.2},"
      "\"KHR_materials_sheen\":{\"sheenColorFactor\":[0.9,0.4,0.1],\"sheenRoughnessFactor\":0.6}}}");
  doc.materials.push_back(  // every property at its default
      "{\"name\":\"defaults\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
      "\"extensions\":{\"KHR_materials_specular\":{},\"KHR_materials_clearcoat\":{},\"KHR_materials_sheen\":{}}}");
  doc.materials.push_back(  // a Lambertian wall: specularFactor 0
      "{\"name\":\"wall\",\"pbrMetallicRoughness\":{\"metallicFactor\":0},"
      "\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1},{\"attributes\":{\"POSITION\":0},\"material\":2}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.materials.size(), 3u);
  const WtMaterial& v = s.materials[0];
  EXPECT_EQ(v.model, WT_MATERIAL_PBR);
  EXPECT_FLOAT_EQ(v.specular.w, 0.3f);
  EXPECT_FLOAT_EQ(v.specular.x, 1.0f);
  EXPECT_FLOAT_EQ(v.specular.y, 0.5f);
  EXPECT_FLOAT_EQ(v.specular.z, 2.0f);  // specularColorFactor has no upper bound (F0 is capped at 1)
  EXPECT_FLOAT_EQ(v.ior, 1.8f);         // the opaque dielectric's F0 follows it
  EXPECT_FLOAT_EQ(v.clearcoat, 0.7f);
  EXPECT_FLOAT_EQ(v.clearcoat_roughness, 0.2f);
  EXPECT_FLOAT_EQ(v.sheen.x, 0.9f);
  EXPECT_FLOAT_EQ(v.sheen.y, 0.4f);
  EXPECT_FLOAT_EQ(v.sheen.z, 0.1f);
  EXPECT_FLOAT_EQ(v.sheen.w, 0.6f);
  const WtMaterial& d = s.materials[1];
  EXPECT_EQ(d.specular.w, 1.0f);
  EXPECT_EQ(d.specular.x, 1.0f);
  EXPECT_EQ(d.clearcoat, 0.0f);
  EXPECT_EQ(d.clearcoat_roughness, 0.0f);
  EXPECT_EQ(d.sheen.x + d.sheen.y + d.sheen.z + d.sheen.w, 0.0f);
  EXPECT_EQ(d.ior, 1.5f);
  EXPECT_EQ(s.materials[2].specular.w, 0.0f);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.at(0);
  // the scene's kernels compile every layer in
  KernelFeatures features;
  setMaterialFeatures(features, s.materials);
  EXPECT_TRUE(features.specular && features.clearcoat && features.sheen);

  // textures of the extensions: read into their slots, the coat's normal map with its scale;
  // a primitive with TEXCOORD_0 and no TANGENT gets tangents for the coat's normal map alone
  GltfDoc textured = triangleDoc();
  const int uv = textured.addVec2({{0, 0}, {1, 0}, {0, 1}});
  textured.images.push_back(
      "{\"uri\":\"data:image/png;base64,"
      "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==\"}");
  textured.textures.push_back("{\"source\":0}");
  textured.materials.push_back(
      "{\"extensions\":{\"KHR_materials_specular\":{\"specularTexture\":{\"index\":0}},"
      "\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1,\"clearcoatNormalTexture\":{\"index\":0,\"scale\":0.5}},"
      "\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,1,1],\"sheenRoughnessTexture\":{\"index\":0}}}}");
  textured.meshes[0] =
      "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"TEXCOORD_0\":" + str(std::size_t(uv)) + "},\"material\":0}]}";
  Scene t = loadDoc(textured);
  expectConsistent(t);
  EXPECT_EQ(t.materials[0].clearcoat, 1.0f);
  EXPECT_EQ(t.materials[0].sheen.x, 1.0f);
  EXPECT_TRUE(t.warnings.empty()) << t.warnings.at(0);
  EXPECT_EQ(t.materials[0].texture_mask, (1u << WT_TEXTURE_SLOT_SPECULAR) | (1u << WT_TEXTURE_SLOT_SHEEN_ROUGHNESS) |
                                             (1u << WT_TEXTURE_SLOT_CLEARCOAT_NORMAL));
  ASSERT_EQ(t.materialTextures.size(), std::size_t(WT_TEXTURE_SLOTS));
  EXPECT_EQ(t.materialTextures[WT_TEXTURE_SLOT_CLEARCOAT_NORMAL].scale, 0.5f);
  ASSERT_EQ(t.tangents.size(), t.positions.size());
  for (const glm::vec4& tangent : t.tangents) EXPECT_NEAR(glm::length(glm::vec3(tangent)), 1.0f, 1e-5f);
  // the normal map takes the feature that compiles normal mapping in
  KernelFeatures coated;
  setMaterialFeatures(coated, t.materials);
  EXPECT_TRUE(coated.clearcoat);
}

// KHR_materials_anisotropy: strength and rotation (defaults 0), the
// texture with its texCoord, listed among the scene's features; a primitive
// without TEXCOORD_0 gets no generated tangents and says its direction is arbitrary.
TEST(GltfLoader, AnisotropyReadsStrengthRotationAndTexture) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_materials_anisotropy\"]";
  doc.images.push_back(
      "{\"uri\":\"data:image/png;base64,"
      "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==\"}");
  doc.textures.push_back("{\"source\":0}");
  doc.materials.push_back(
      "{\"name\":\"brushed\",\"pbrMetallicRoughness\":{\"metallicFactor\":1,\"roughnessFactor\":0.2},"
      "\"extensions\":{\"KHR_materials_anisotropy\":{\"anisotropyStrength\":0.6,\"anisotropyRotation\":1.25,"
      "\"anisotropyTexture\":{\"index\":0,\"texCoord\":1}}}}");
  doc.materials.push_back("{\"name\":\"defaults\",\"extensions\":{\"KHR_materials_anisotropy\":{}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_FLOAT_EQ(s.materials[0].anisotropy, 0.6f);
  EXPECT_FLOAT_EQ(s.materials[0].anisotropy_rotation, 1.25f);
  EXPECT_EQ(s.materials[0].texture_mask, 1u << WT_TEXTURE_SLOT_ANISOTROPY);
  ASSERT_GE(s.materialTextures.size(), std::size_t(WT_TEXTURE_SLOTS));
  EXPECT_EQ(s.materialTextures[WT_TEXTURE_SLOT_ANISOTROPY].texcoord, 1u);
  EXPECT_EQ(s.materials[1].anisotropy, 0.0f);
  EXPECT_EQ(s.materials[1].anisotropy_rotation, 0.0f);
  EXPECT_EQ(s.materials[1].texture_mask, 0u);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_CONTAINS(s.warnings[0], "material 'brushed': KHR_materials_anisotropy on a primitive without TANGENT or TEXCOORD_0");
  KernelFeatures features;
  setMaterialFeatures(features, s.materials);
  EXPECT_TRUE(features.anisotropy);
  bool defined = false;
  for (const std::string& d : kernelDefines(features)) defined |= d == "-D WT_HAS_ANISOTROPY=1";
  EXPECT_TRUE(defined);
  // out-of-range strength is clamped with a warning; a rotation that is not a number is an error naming it
  GltfDoc bad = triangleDoc();
  bad.materials.push_back("{\"name\":\"m\",\"extensions\":{\"KHR_materials_anisotropy\":{\"anisotropyStrength\":1.5}}}");
  bad.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  Scene clamped = loadDoc(bad);
  EXPECT_EQ(clamped.materials[0].anisotropy, 1.0f);
  EXPECT_CONTAINS(clamped.warnings.at(0), "material 0 'm' KHR_materials_anisotropy anisotropyStrength 1.500000 is outside [0,1]; clamped");
  bad.materials[0] = "{\"name\":\"m\",\"extensions\":{\"KHR_materials_anisotropy\":{\"anisotropyRotation\":\"x\"}}}";
  EXPECT_CONTAINS(docError(bad), "material 0 'm' KHR_materials_anisotropy: anisotropyRotation is not a finite number");
}

// KHR_materials_iridescence: factor, film ior, thickness range (defaults 0,
// 1.3, 100, 400), the intensity and thickness textures with their texCoord,
// listed among the scene's features; bad values warn or fail by name.
TEST(GltfLoader, IridescenceReadsFactorsAndTextures) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_materials_iridescence\"]";
  doc.images.push_back(
      "{\"uri\":\"data:image/png;base64,"
      "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==\"}");
  doc.textures.push_back("{\"source\":0}");
  doc.materials.push_back(
      "{\"name\":\"soap\",\"extensions\":{\"KHR_materials_iridescence\":{\"iridescenceFactor\":0.7,"
      "\"iridescenceIor\":1.8,\"iridescenceThicknessMinimum\":250,\"iridescenceThicknessMaximum\":120,"
      "\"iridescenceTexture\":{\"index\":0,\"texCoord\":1},\"iridescenceThicknessTexture\":{\"index\":0}}}}");
  doc.materials.push_back("{\"name\":\"defaults\",\"extensions\":{\"KHR_materials_iridescence\":{}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1}]}";
  Scene s = loadDoc(doc);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materials[0].model, WT_MATERIAL_PBR);
  EXPECT_FLOAT_EQ(s.materials[0].iridescence.x, 0.7f);
  EXPECT_FLOAT_EQ(s.materials[0].iridescence.y, 1.8f);
  EXPECT_FLOAT_EQ(s.materials[0].iridescence.z, 250.0f);  // the minimum may exceed the maximum
  EXPECT_FLOAT_EQ(s.materials[0].iridescence.w, 120.0f);
  EXPECT_EQ(s.materials[0].texture_mask,
            (1u << WT_TEXTURE_SLOT_IRIDESCENCE) | (1u << WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS));
  ASSERT_GE(s.materialTextures.size(), std::size_t(WT_TEXTURE_SLOTS));
  EXPECT_EQ(s.materialTextures[WT_TEXTURE_SLOT_IRIDESCENCE].texcoord, 1u);
  EXPECT_EQ(s.materialTextures[WT_TEXTURE_SLOT_IRIDESCENCE_THICKNESS].texcoord, 0u);
  EXPECT_EQ(s.materials[1].iridescence.x, 0.0f);
  EXPECT_FLOAT_EQ(s.materials[1].iridescence.y, 1.3f);
  EXPECT_FLOAT_EQ(s.materials[1].iridescence.z, 100.0f);
  EXPECT_FLOAT_EQ(s.materials[1].iridescence.w, 400.0f);
  EXPECT_EQ(s.materials[1].texture_mask, 0u);
  KernelFeatures features;
  setMaterialFeatures(features, s.materials);
  EXPECT_TRUE(features.iridescence);
  bool defined = false;
  for (const std::string& d : kernelDefines(features)) defined |= d == "-D WT_HAS_IRIDESCENCE=1";
  EXPECT_TRUE(defined);
  // factor 0 (the default) compiles nothing in
  KernelFeatures none;
  setMaterialFeatures(none, std::vector<WtMaterial>{s.materials[1]});
  EXPECT_FALSE(none.iridescence);
  GltfDoc bad = triangleDoc();
  bad.materials.push_back("{\"name\":\"m\",\"extensions\":{\"KHR_materials_iridescence\":{\"iridescenceFactor\":2}}}");
  bad.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  Scene clamped = loadDoc(bad);
  EXPECT_EQ(clamped.materials[0].iridescence.x, 1.0f);
  EXPECT_CONTAINS(clamped.warnings.at(0), "material 0 'm' KHR_materials_iridescence iridescenceFactor 2.000000 is outside [0,1]; clamped");
  bad.materials[0] = "{\"name\":\"m\",\"extensions\":{\"KHR_materials_iridescence\":{\"iridescenceIor\":0.5}}}";
  EXPECT_CONTAINS(docError(bad), "material 0 'm' KHR_materials_iridescence: iridescenceIor 0.500000 is below 1");
  bad.materials[0] = "{\"name\":\"m\",\"extensions\":{\"KHR_materials_iridescence\":{\"iridescenceThicknessMaximum\":\"x\"}}}";
  EXPECT_CONTAINS(docError(bad), "material 0 'm' KHR_materials_iridescence: iridescenceThicknessMaximum is not a finite number");
}

TEST(GltfLoader, BadLayerValuesAreClampedOrRefused) {
  auto load = [](const std::string& extensions, float metallic = 0.0f) {
    GltfDoc doc = triangleDoc();
    doc.materials.push_back("{\"name\":\"m\",\"pbrMetallicRoughness\":{\"metallicFactor\":" + num(metallic) +
                            "},\"extensions\":{" + extensions + "}}");
    doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
    return doc;
  };
  Scene clamped = loadDoc(load("\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1.5,\"clearcoatRoughnessFactor\":-1},"
                               "\"KHR_materials_sheen\":{\"sheenColorFactor\":[1.5,-1,0.5],\"sheenRoughnessFactor\":2},"
                               "\"KHR_materials_specular\":{\"specularFactor\":-0.5,\"specularColorFactor\":[2,-1,0]}"));
  const WtMaterial& m = clamped.materials[0];
  EXPECT_EQ(m.clearcoat, 1.0f);
  EXPECT_EQ(m.clearcoat_roughness, 0.0f);
  EXPECT_EQ(m.sheen.x, 1.0f);
  EXPECT_EQ(m.sheen.y, 0.0f);
  EXPECT_EQ(m.sheen.z, 0.5f);
  EXPECT_EQ(m.sheen.w, 1.0f);
  EXPECT_EQ(m.specular.w, 0.0f);
  EXPECT_EQ(m.specular.x, 2.0f);
  EXPECT_EQ(m.specular.y, 0.0f);
  ASSERT_EQ(clamped.warnings.size(), 6u);
  EXPECT_CONTAINS(clamped.warnings[0], "material 0 'm' KHR_materials_specular specularFactor -0.500000 is outside [0,1]; clamped");
  EXPECT_CONTAINS(clamped.warnings[1], "specularColorFactor");
  EXPECT_CONTAINS(clamped.warnings[1], "is outside [0,inf); clamped");
  EXPECT_CONTAINS(clamped.warnings[2], "KHR_materials_clearcoat clearcoatFactor 1.500000 is outside [0,1]; clamped");
  EXPECT_CONTAINS(clamped.warnings[3], "clearcoatRoughnessFactor -1.000000 is outside [0,1]; clamped");
  EXPECT_CONTAINS(clamped.warnings[4], "KHR_materials_sheen: sheenColorFactor");
  EXPECT_CONTAINS(clamped.warnings[5], "sheenRoughnessFactor 2.000000 is outside [0,1]; clamped");
  // a specular extension on a metal does nothing, and says so
  Scene metal = loadDoc(load("\"KHR_materials_specular\":{\"specularFactor\":0.5}", 1.0f));
  EXPECT_CONTAINS(metal.warnings.at(0), "KHR_materials_specular has no effect on a metal");
  // wrong types: errors naming the file (docError checks), the material, the extension and the property
  EXPECT_CONTAINS(docError(load("\"KHR_materials_specular\":{\"specularFactor\":\"x\"}")),
                  "material 0 'm' KHR_materials_specular: specularFactor is not a finite number");
  EXPECT_CONTAINS(docError(load("\"KHR_materials_specular\":{\"specularColorFactor\":[1,1]}")),
                  "material 0 'm' KHR_materials_specular: specularColorFactor is not an array of 3 numbers");
  EXPECT_CONTAINS(docError(load("\"KHR_materials_clearcoat\":{\"clearcoatRoughnessFactor\":[0.5]}")),
                  "material 0 'm' KHR_materials_clearcoat: clearcoatRoughnessFactor is not a finite number");
  EXPECT_CONTAINS(docError(load("\"KHR_materials_sheen\":{\"sheenColorFactor\":[1,\"a\",1]}")),
                  "material 0 'm' KHR_materials_sheen: sheenColorFactor is not an array of 3 finite numbers");
  EXPECT_CONTAINS(docError(load("\"KHR_materials_sheen\":{\"sheenRoughnessFactor\":true}")),
                  "material 0 'm' KHR_materials_sheen: sheenRoughnessFactor is not a finite number");
  // (an extension that is not an object never reaches the loader: tinygltf 2.7 drops it while parsing)
}

// KHR_materials_unlit: a black Lambertian that emits its base colour, from
// both faces when double-sided; every other property is a fallback and
// ignored, the other extensions said to be so.
TEST(GltfLoader, UnlitIsABlackEmitterOfItsBaseColour) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_materials_unlit\",\"KHR_materials_clearcoat\"]";
  doc.materials.push_back(
      "{\"name\":\"sky\",\"doubleSided\":true,\"emissiveFactor\":[1,1,1],"
      "\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.2,0.4,0.6,1],\"metallicFactor\":1,\"roughnessFactor\":0.1},"
      "\"extensions\":{\"KHR_materials_unlit\":{}}}");
  doc.materials.push_back(
      "{\"name\":\"sign\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,0.5,0,1]},"
      "\"extensions\":{\"KHR_materials_unlit\":{},\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  const WtMaterial& sky = s.materials[0];
  EXPECT_EQ(sky.model, WT_MATERIAL_DIFFUSE);
  EXPECT_EQ(sky.base_color.x + sky.base_color.y + sky.base_color.z, 0.0f);
  EXPECT_FLOAT_EQ(sky.emission.x, 0.2f);
  EXPECT_FLOAT_EQ(sky.emission.y, 0.4f);
  EXPECT_FLOAT_EQ(sky.emission.z, 0.6f);
  EXPECT_EQ(sky.emission.w, 1.0f);  // both faces
  const WtMaterial& sign = s.materials[1];
  EXPECT_EQ(sign.model, WT_MATERIAL_DIFFUSE);
  EXPECT_EQ(sign.clearcoat, 0.0f);
  EXPECT_FLOAT_EQ(sign.emission.y, 0.5f);
  EXPECT_EQ(sign.emission.w, 0.0f);  // the front face only
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_CONTAINS(s.warnings[0], "material 1 'sign': KHR_materials_clearcoat has no effect on a KHR_materials_unlit material");
  // the unlit triangles are emitters: they light the scene
  EXPECT_EQ(std::count_if(s.materials.begin(), s.materials.end(),
                          [](const WtMaterial& m) { return m.emission.x > 0.0f; }),
            2);
}

TEST(GltfLoader, AlbedoIsClampedWithAWarning) {
  GltfDoc doc = triangleDoc();
  doc.materials.push_back("{\"name\":\"hot\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1.5,-0.2,0.5,1],"
                          "\"metallicFactor\":0}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.x, 1.0f);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.y, 0.0f);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.z, 0.5f);
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_CONTAINS(s.warnings[0], "'hot'");
  EXPECT_CONTAINS(s.warnings[0], "clamped");
}

TEST(GltfLoader, DefaultMaterialIsAppendedOnce) {
  GltfDoc doc = triangleDoc();
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.1,0.2,0.3,1]}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0}},{\"attributes\":{\"POSITION\":0},"
                  "\"material\":0},{\"attributes\":{\"POSITION\":0}}]}";
  Scene s = loadDoc(doc);
  expectConsistent(s);
  ASSERT_EQ(s.materials.size(), 2u);
  EXPECT_EQ(s.materialNames[0], "material 0");
  EXPECT_EQ(s.materialNames[1], "default");
  EXPECT_EQ(s.triangles[0].material, 1u);
  EXPECT_EQ(s.triangles[1].material, 0u);
  EXPECT_EQ(s.triangles[2].material, 1u);
  EXPECT_FLOAT_EQ(s.materials[0].base_color.z, 0.3f);
}

TEST(GltfLoader, UnsupportedFeaturesWarnOnceEach) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"VENDOR_not_implemented\",\"KHR_materials_emissive_strength\",\"KHR_materials_anisotropy\",\"KHR_materials_iridescence\","
                       "\"KHR_materials_clearcoat\",\"KHR_materials_sheen\",\"KHR_materials_specular\",\"KHR_materials_unlit\"]";
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"alphaMode\":\"BLEND\"}");
  doc.materials.push_back("{\"pbrMetallicRoughness\":{},\"doubleSided\":true}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  Scene s = loadDoc(doc);
  EXPECT_EQ(s.triangles.size(), 1u);
  auto count = [&](const std::string& part) {
    return std::count_if(s.warnings.begin(), s.warnings.end(),
                         [&](const std::string& w) { return w.find(part) != std::string::npos; });
  };
  EXPECT_EQ(count("VENDOR_not_implemented is not supported; ignored"), 1);
  EXPECT_EQ(count("KHR_materials_iridescence"), 0);  // drawn
  EXPECT_EQ(count("KHR_materials_anisotropy"), 0);  // drawn
  EXPECT_EQ(count("KHR_materials_clearcoat"), 0);  // drawn (factors only: textures warn as above)
  EXPECT_EQ(count("KHR_materials_sheen"), 0);
  EXPECT_EQ(count("KHR_materials_specular"), 0);
  EXPECT_EQ(count("KHR_materials_unlit"), 0);
  EXPECT_EQ(count("emissive_strength"), 0);
  EXPECT_EQ(count("metallic"), 0);  // the metallic-roughness model draws metallicFactor
  EXPECT_EQ(count("alphaMode"), 0);  // drawn since 2026-12 (kernels/materials/alpha.cl)
  EXPECT_EQ(count("doubleSided"), 0);
}

TEST(GltfLoader, AlphaModeAndCutoffAreRead) {
  GltfDoc doc = triangleDoc();
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.25]}}");
  doc.materials.push_back("{\"alphaMode\":\"OPAQUE\",\"alphaCutoff\":0.9}");
  doc.materials.push_back("{\"alphaMode\":\"MASK\"}");
  doc.materials.push_back("{\"alphaMode\":\"MASK\",\"alphaCutoff\":0.75}");
  doc.materials.push_back("{\"alphaMode\":\"BLEND\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[1,1,1,0.3]}}");
  doc.materials.push_back("{\"alphaMode\":\"MASK\",\"alphaCutoff\":0}");
  Scene s = loadDoc(doc);
  ASSERT_EQ(s.materials.size(), 6u);
  EXPECT_EQ(s.materials[0].alpha_mode, WT_ALPHA_OPAQUE);  // the default
  EXPECT_FLOAT_EQ(s.materials[0].alpha, 0.25f);
  EXPECT_FLOAT_EQ(s.materials[0].alpha_cutoff, 0.5f);
  EXPECT_EQ(s.materials[1].alpha_mode, WT_ALPHA_OPAQUE);
  EXPECT_EQ(s.materials[2].alpha_mode, WT_ALPHA_MASK);
  EXPECT_FLOAT_EQ(s.materials[2].alpha_cutoff, 0.5f);  // the specification's default
  EXPECT_EQ(s.materials[3].alpha_mode, WT_ALPHA_MASK);
  EXPECT_FLOAT_EQ(s.materials[3].alpha_cutoff, 0.75f);
  EXPECT_EQ(s.materials[4].alpha_mode, WT_ALPHA_BLEND);
  EXPECT_FLOAT_EQ(s.materials[4].alpha, 0.3f);
  EXPECT_EQ(s.materials[5].alpha_mode, WT_ALPHA_MASK);
  EXPECT_FLOAT_EQ(s.materials[5].alpha_cutoff, 0.0f);
  EXPECT_TRUE(s.warnings.empty()) << s.warnings.front();
}

TEST(GltfLoader, BadAlphaModesAndCutoffsNameTheMaterial) {
  GltfDoc doc = triangleDoc();
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  doc.materials.push_back("{\"name\":\"fuzzy\",\"alphaMode\":\"DITHER\"}");
  doc.materials.push_back("{\"name\":\"sieve\",\"alphaMode\":\"MASK\",\"alphaCutoff\":-0.5}");
  doc.materials.push_back("{\"alphaMode\":\"mask\"}");  // names are case-sensitive
  Scene s = loadDoc(doc);
  ASSERT_EQ(s.materials.size(), 3u);
  EXPECT_EQ(s.materials[0].alpha_mode, WT_ALPHA_OPAQUE);
  EXPECT_EQ(s.materials[1].alpha_mode, WT_ALPHA_MASK);
  EXPECT_FLOAT_EQ(s.materials[1].alpha_cutoff, 0.0f);
  EXPECT_EQ(s.materials[2].alpha_mode, WT_ALPHA_OPAQUE);
  auto has = [&](const std::string& part) {
    return std::any_of(s.warnings.begin(), s.warnings.end(),
                       [&](const std::string& w) { return w.find(part) != std::string::npos; });
  };
  EXPECT_TRUE(has("material 0 'fuzzy': alphaMode 'DITHER' is not OPAQUE, MASK or BLEND; drawn as OPAQUE"));
  EXPECT_TRUE(has("material 1 'sieve': alphaCutoff -0.5"));
  EXPECT_TRUE(has("is negative; 0 used"));
  EXPECT_TRUE(has("material 2: alphaMode 'mask'"));
  EXPECT_EQ(s.warnings.size(), 3u);
}

TEST(GltfLoader, TextureProblemsNameTheirElement) {
  GltfDoc doc = triangleDoc();
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0}]}";
  EXPECT_CONTAINS(docError(doc), "material 0 baseColorTexture references missing texture 0");
  doc.textures.push_back("{\"source\":0}");
  EXPECT_CONTAINS(docError(doc), "texture 0 references missing image 0");
  // a file that is not there is an error naming it, not a white material
  doc.images.push_back("{\"uri\":\"does_not_exist.png\"}");
  EXPECT_CONTAINS(docError(doc), "image 0 ('does_not_exist.png'): no image data");
  // a format we do not decode (WebP's magic): a warning, and the factors stand
  doc.images[0] = "{\"uri\":\"data:application/octet-stream;base64,UklGRgAAAABXRUJQ\"}";
  Scene s = loadDoc(doc);
  EXPECT_EQ(s.materials[0].texture_mask, 0u);
  EXPECT_EQ(std::count_if(s.warnings.begin(), s.warnings.end(),
                          [](const std::string& w) { return w.find("image 0 is WebP, which is not supported") != std::string::npos; }),
            1);
  // garbage that claims to be a PNG: an error naming the image
  doc.images[0] = "{\"uri\":\"data:application/octet-stream;base64,iVBORw0KGgoAAAAA\"}";
  EXPECT_CONTAINS(docError(doc), "image 0");
}

/// A PNG (or a JPEG at quality 90) of w x h RGBA pixels of a seeded pattern,
/// written next to the test's .gltf; returns its file name for a uri.
std::string writeImageFile(const std::string& suffix, int w, int h, unsigned seed, bool jpeg = false) {
  std::mt19937 rng(seed);
  std::vector<unsigned char> pixels(std::size_t(w) * h * 4), bytes;
  for (unsigned char& v : pixels) v = static_cast<unsigned char>(rng() & 255u);
  auto append = [](void* context, void* data, int size) {
    auto* out = static_cast<std::vector<unsigned char>*>(context);
    out->insert(out->end(), static_cast<unsigned char*>(data), static_cast<unsigned char*>(data) + size);
  };
  const int ok = jpeg ? stbi_write_jpg_to_func(append, &bytes, w, h, 4, pixels.data(), 90)
                      : stbi_write_png_to_func(append, &bytes, w, h, 4, pixels.data(), w * 4);
  EXPECT_NE(ok, 0);
  return writeFile(suffix, bytes).filename().string();
}

/// Three materials over six images (textures 0-5 read images 0-5): PNGs of odd and even sizes, a JPEG, one
/// image read both as sRGB and linear, and a WebP (warned about) between them.
GltfDoc manyTexturesDoc() {
  GltfDoc doc = triangleDoc();
  const std::string files[] = {
      writeImageFile(".a.png", 37, 23, 1), writeImageFile(".b.png", 64, 64, 2), writeImageFile(".c.png", 3, 50, 3),
      writeImageFile(".d.jpg", 40, 31, 4, true), writeImageFile(".e.png", 1, 1, 5)};
  for (const std::string& f : files) doc.images.push_back("{\"uri\":\"" + f + "\"}");
  doc.images.insert(doc.images.begin() + 2, "{\"uri\":\"data:application/octet-stream;base64,UklGRgAAAABXRUJQ\"}");
  for (int i = 0; i < 6; ++i) doc.textures.push_back("{\"source\":" + std::to_string(i) + "}");
  doc.samplers.push_back("{\"wrapS\":33071,\"minFilter\":9728}");
  doc.textures[3] = "{\"source\":3,\"sampler\":0}";
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}},\"normalTexture\":{\"index\":1}}");
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":2},"
                          "\"metallicRoughnessTexture\":{\"index\":5}},\"emissiveTexture\":{\"index\":4},"
                          "\"emissiveFactor\":[1,1,1]}");
  doc.materials.push_back("{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":1}},"
                          "\"occlusionTexture\":{\"index\":3},\"normalTexture\":{\"index\":3}}");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":0},"
                  "{\"attributes\":{\"POSITION\":0},\"material\":1},{\"attributes\":{\"POSITION\":0},\"material\":2}]}";
  return doc;
}

// The images are decoded and their mips built on several threads: any
// thread count gives the same scene, bit for bit, warnings in the same order.
TEST(GltfLoader, TexturesLoadTheSameOnAnyThreadCount) {
  const GltfDoc doc = manyTexturesDoc();
  GltfLoadOptions one, many;
  one.textureThreads = 1;
  many.textureThreads = 4;
  const Scene a = loadDoc(doc, one), b = loadDoc(doc, many);
  ASSERT_EQ(a.textures.imageCount(), 6u);  // five decodable images, one of them read as sRGB and linear
  EXPECT_EQ(a.textures.imageCount(), b.textures.imageCount());
  EXPECT_EQ(a.textures.texels, b.textures.texels);
  ASSERT_EQ(a.textures.levels.size(), b.textures.levels.size());
  EXPECT_EQ(0, std::memcmp(a.textures.levels.data(), b.textures.levels.data(), a.textures.levels.size() * sizeof(WtTextureLevel)));
  ASSERT_EQ(a.textures.textures.size(), b.textures.textures.size());
  EXPECT_EQ(0, std::memcmp(a.textures.textures.data(), b.textures.textures.data(),
                           a.textures.textures.size() * sizeof(WtTexture)));
  ASSERT_EQ(a.materialTextures.size(), b.materialTextures.size());
  EXPECT_EQ(0, std::memcmp(a.materialTextures.data(), b.materialTextures.data(),
                           a.materialTextures.size() * sizeof(WtTextureRef)));
  EXPECT_EQ(a.warnings, b.warnings);
  EXPECT_EQ(std::count_if(a.warnings.begin(), a.warnings.end(),
                          [](const std::string& w) { return w.find("image 2 is WebP") != std::string::npos; }),
            1);
  // and the same as each image decoded and added alone, in the order met
  TextureSet serial;
  // images 0 (a), 1 (b), 5 (e), 4 (d), 1, 3 (c), as the materials meet them, and their encodings
  const std::pair<const char*, bool> order[] = {{".a.png", true},  {".b.png", false}, {".e.png", false},
                                                {".d.jpg", true},  {".b.png", true},  {".c.png", false}};
  for (const auto& [suffix, srgb] : order) {
    std::ifstream in(scratchFile(suffix), std::ios::binary);
    const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    serial.addImage(decodeImage(bytes.data(), bytes.size(), suffix), srgb);
  }
  EXPECT_EQ(serial.texels, b.textures.texels);
  ASSERT_EQ(serial.levels.size(), b.textures.levels.size());
  EXPECT_EQ(0, std::memcmp(serial.levels.data(), b.textures.levels.data(), serial.levels.size() * sizeof(WtTextureLevel)));
}

// A broken image among several decoded in parallel: the error names it (the
// first broken one in the order the materials meet them, as a serial load
// would), not another.
TEST(GltfLoader, BrokenImageAmongManyIsNamed) {
  GltfDoc doc = manyTexturesDoc();
  // the third of five met (images 0, 1, 5, 4, 3), and the fifth: PNGs cut
  // in the middle of their pixel data, so only decoding them fails
  for (int image : {5, 3}) {
    const std::string file = writeImageFile(".broken" + std::to_string(image) + ".png", 40, 40, unsigned(image));
    std::ifstream in(scratchFile(".broken" + std::to_string(image) + ".png"), std::ios::binary);
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bytes.resize(bytes.size() / 2);
    writeFile(".broken" + std::to_string(image) + ".png", bytes);
    doc.images[std::size_t(image)] = "{\"uri\":\"" + file + "\"}";
  }
  for (unsigned threads : {1u, 2u, 6u}) {
    GltfLoadOptions options;
    options.textureThreads = threads;
    const std::string message = docError(doc, options);
    EXPECT_CONTAINS(message, "image 5 ('" + scratchFile(".broken5.png").filename().string() + "'): cannot decode");
    EXPECT_EQ(message.find("broken3"), std::string::npos) << message;
  }
}

TEST(GltfLoader, RequiredGeometryExtensionIsAnError) {
  GltfDoc doc = triangleDoc();
  doc.extensionsUsed = "[\"KHR_draco_mesh_compression\"]";
  doc.extensionsRequired = "[\"KHR_draco_mesh_compression\"]";
  EXPECT_CONTAINS(docError(doc), "KHR_draco_mesh_compression");
  // merely used (with an uncompressed fallback): a warning
  doc.extensionsRequired.clear();
  Scene s = loadDoc(doc);
  EXPECT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.warnings.size(), 1u);
}

// ---------------------------------------------------------------------------
// validation: each error names the file and the element

TEST(GltfLoaderErrors, IndexOutOfRange) {
  GltfDoc doc = triangleDoc();
  doc.bin.clear();
  doc.bufferViews.clear();
  doc.accessors.clear();
  doc.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  doc.addIndices<std::uint16_t>({0, 1, 1234});
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: index 1234 out of range (3 vertices)");
}

TEST(GltfLoaderErrors, AccessorPastTheEndOfItsBufferView) {
  GltfDoc doc = triangleDoc();
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: extends past the end of buffer view 0 (needs 48 bytes, has 36)");
  doc.accessors[0] = "{\"bufferView\":0,\"byteOffset\":4,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: extends past the end of buffer view 0 (needs 40 bytes, has 36)");
}

TEST(GltfLoaderErrors, BufferViewPastTheEndOfItsBuffer) {
  GltfDoc doc = triangleDoc();
  doc.bufferViews[1] = "{\"buffer\":0,\"byteOffset\":36,\"byteLength\":600}";
  EXPECT_CONTAINS(docError(doc), "buffer view 1: extends past the end of buffer 0");
  doc.bufferViews[1] = "{\"buffer\":3,\"byteOffset\":36,\"byteLength\":6}";
  EXPECT_CONTAINS(docError(doc), "buffer view 1: references missing buffer 3");
}

TEST(GltfLoaderErrors, StrideSmallerThanElement) {
  GltfDoc doc = triangleDoc();
  doc.bufferViews[0] = "{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36,\"byteStride\":8}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: byteStride 8 of buffer view 0 is smaller than the element size 12");
}

TEST(GltfLoaderErrors, CountTimesStrideOverflows) {
  GltfDoc doc = triangleDoc();
  doc.accessors[0] =
      "{\"bufferView\":0,\"componentType\":5126,\"count\":4611686018427387904,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: count 4611686018427387904 with stride 12 overflows");
}

TEST(GltfLoaderErrors, WrongAccessorTypes) {
  GltfDoc doc = triangleDoc();
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: POSITION accessor has type VEC2, expected VEC3");
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5123,\"count\":3,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc),
                  "mesh 0, primitive 0: POSITION accessor has component type UNSIGNED_SHORT, expected FLOAT");
  doc = triangleDoc();
  doc.accessors[1] = "{\"bufferView\":1,\"componentType\":5126,\"count\":1,\"type\":\"SCALAR\"}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: indices accessor has component type FLOAT");
}

TEST(GltfLoaderErrors, MissingReferences) {
  GltfDoc doc = triangleDoc();
  doc.nodes[0] = "{\"mesh\":9}";
  EXPECT_CONTAINS(docError(doc), "node 0: references missing mesh 9");
  doc.nodes[0] = "{\"mesh\":0,\"children\":[7]}";
  EXPECT_CONTAINS(docError(doc), "node 0: references missing node 7");
  doc.nodes[0] = "{\"camera\":2}";
  EXPECT_CONTAINS(docError(doc), "node 0: references missing camera 2");
  doc = triangleDoc();
  doc.scenes[0] = "{\"nodes\":[4]}";
  EXPECT_CONTAINS(docError(doc), "scene 0: references missing node 4");
  doc = triangleDoc();
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":8}}]}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: NORMAL references missing accessor 8");
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"material\":3}]}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: references missing material 3");
  doc = triangleDoc();
  doc.accessors[0] = "{\"bufferView\":6,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: references missing buffer view 6");
}

TEST(GltfLoaderErrors, NonFinitePosition) {
  GltfDoc doc;
  doc.addVec3({{0, 0, 0}, {std::numeric_limits<float>::quiet_NaN(), 0, 0}, {0, 1, 0}});
  doc.addMesh("{\"attributes\":{\"POSITION\":0}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  std::string message = docError(doc);
  EXPECT_CONTAINS(message, "mesh 0, primitive 0 (node 0): vertex 1 has a non-finite position");
  // finite in the file, infinite once placed
  doc.bin.clear();
  doc.bufferViews.clear();
  doc.accessors.clear();
  doc.addVec3({{0, 0, 0}, {1e30f, 0, 0}, {0, 1, 0}});
  doc.nodes[0] = "{\"mesh\":0,\"scale\":[1e30,1,1]}";
  EXPECT_CONTAINS(docError(doc), "vertex 1 has a non-finite position");
}

TEST(GltfLoaderErrors, IndexCountNotAMultipleOfThree) {
  GltfDoc doc = triangleDoc();
  doc.accessors[1] = "{\"bufferView\":1,\"componentType\":5123,\"count\":2,\"type\":\"SCALAR\"}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: 2 indices is not a multiple of 3 for TRIANGLES");
  doc = triangleDoc(false);
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: 2 vertices is not a multiple of 3");
}

TEST(GltfLoaderErrors, AttributeCountsDiffer) {
  GltfDoc doc = triangleDoc();
  int normal = doc.addVec3({{0, 0, 1}, {0, 0, 1}});
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":" + str(normal) + "}}]}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: NORMAL has 2 elements, POSITION has 3");
}

TEST(GltfLoaderErrors, InvalidMode) {
  GltfDoc doc = triangleDoc();
  doc.meshes[0] = "{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":9}]}";
  EXPECT_CONTAINS(docError(doc), "mesh 0, primitive 0: invalid mode 9");
}

TEST(GltfLoaderErrors, CycleInTheNodeGraph) {
  GltfDoc doc = triangleDoc();
  doc.nodes[0] = "{\"mesh\":0,\"children\":[1]}";
  doc.addNode("{\"children\":[2]}");
  doc.addNode("{\"children\":[1]}");
  EXPECT_CONTAINS(docError(doc), "node 1: is its own ancestor (cycle in the node graph)");
  doc.nodes[0] = "{\"mesh\":0,\"children\":[0]}";
  EXPECT_CONTAINS(docError(doc), "node 0: is its own ancestor");
}

TEST(GltfLoaderErrors, FlattenedSceneIsLimitedBeforeDecoding) {
  // five instances of one triangle: 15 vertices, 5 triangles
  GltfDoc doc = triangleDoc();
  for (int i = 1; i <= 4; ++i) doc.addNode("{\"mesh\":0,\"translation\":[" + str(std::size_t(i)) + ",0,0]}");
  doc.scenes[0] = "{\"nodes\":[0,1,2,3,4]}";
  GltfLoadOptions options;
  options.maxVertices = 15;
  EXPECT_EQ(loadDoc(doc, options).triangles.size(), 5u);
  options.maxVertices = 14;
  EXPECT_CONTAINS(docError(doc, options),
                  "node 4: mesh 0 brings the flattened scene to 15 vertices and 5 triangles, more than the 14");
  options = {};
  options.maxTriangles = 4;
  EXPECT_CONTAINS(docError(doc, options), "node 4: mesh 0 brings the flattened scene to 15 vertices and 5 triangles");

  // A 300-byte file: 2^26 - 1 zero vertices without a buffer view (the most
  // an accessor may claim), placed by five nodes. Decoded and placed one
  // instance at a time that was about 14 GB of host arrays; now it is refused
  // from the counts alone, before anything is allocated.
  GltfDoc zeros;
  const std::size_t count = (std::size_t(1) << 26) - 1;  // a multiple of 3
  int position = zeros.addAccessor(-1, kFloat, count, "VEC3");
  zeros.addMesh("{\"attributes\":{\"POSITION\":" + str(std::size_t(position)) + "}}");
  for (int i = 0; i < 5; ++i) zeros.addNode("{\"mesh\":0}");
  zeros.scenes.push_back("{\"nodes\":[0,1,2,3,4]}");
  const auto start = std::chrono::steady_clock::now();
  EXPECT_CONTAINS(docError(zeros), "node 4: mesh 0 brings the flattened scene to " + str(5 * count) + " vertices");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 2.0);
}

TEST(GltfLoaderErrors, MalformedTransforms) {
  GltfDoc doc = triangleDoc();
  doc.nodes[0] = "{\"mesh\":0,\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0]}";
  EXPECT_CONTAINS(docError(doc), "node 0: matrix has 15 values, expected 16");
  doc.nodes[0] = "{\"mesh\":0,\"rotation\":[0,0,0,0]}";
  EXPECT_CONTAINS(docError(doc), "node 0: rotation is not a valid quaternion");
  doc.nodes[0] = "{\"mesh\":0,\"scale\":[1,1]}";
  EXPECT_CONTAINS(docError(doc), "node 0: scale has 2 values, expected 3");
}

TEST(GltfLoaderErrors, BadSparseAccessors) {
  GltfDoc doc;
  int base = doc.addView(std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  int indices = doc.addView(std::vector<std::uint16_t>{1, 3});
  int values = doc.addView(std::vector<glm::vec3>{{2, 0, 0}, {7, 8, 9}});
  auto sparse = [&](int count, int valuesView) {
    return ",\"sparse\":{\"count\":" + str(std::size_t(count)) + ",\"indices\":{\"bufferView\":" +
           str(indices) + ",\"componentType\":5123},\"values\":{\"bufferView\":" +
           str(std::size_t(valuesView)) + "}}";
  };
  doc.addAccessor(base, kFloat, 3, "VEC3", sparse(2, values));
  doc.addMesh("{\"attributes\":{\"POSITION\":0}}");
  doc.addNode("{\"mesh\":0}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  EXPECT_CONTAINS(docError(doc), "accessor 0: sparse index 3 out of range (3 elements)");
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"" + sparse(3, values) + "}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: sparse indices extend past the end of buffer view 1");
  doc.accessors[0] = "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"" + sparse(2, indices) + "}";
  EXPECT_CONTAINS(docError(doc), "accessor 0: sparse values extend past the end of buffer view 1 (needs 24 bytes, has 4)");
}

TEST(GltfLoaderErrors, CorruptJson) {
  std::string text = triangleDoc().embedded();
  text.resize(text.size() / 2);
  std::string message = errorOf([&] { loadGltf(writeFile(".gltf", text).string()); });
  EXPECT_EQ(message.rfind(scratchFile(".gltf").filename().string() + ": glTF parse error: ", 0), 0u) << message;
  EXPECT_GT(message.size(), 60u) << "tinygltf's own text is missing: " << message;

  message = errorOf([&] { loadGltfFromMemory("{\"asset\":{}}", "nover.gltf", "."); });
  EXPECT_CONTAINS(message, "nover.gltf: glTF parse error");
  EXPECT_CONTAINS(message, "asset");
}

TEST(GltfLoaderErrors, MissingFile) {
  std::string message = errorOf([] { loadGltf("/nonexistent/dir/box.gltf"); });
  EXPECT_EQ(message.rfind("box.gltf: cannot open", 0), 0u) << message;
  message = errorOf([] { loadGltf(test::scratchDir("gltf").string()); });
  EXPECT_CONTAINS(message, "cannot open");
  message = errorOf([&] { loadGltf(writeFile(".gltf", std::string()).string()); });
  EXPECT_CONTAINS(message, "empty");
}

TEST(GltfLoaderErrors, MissingExternalBuffer) {
  GltfDoc doc = triangleDoc();
  std::string message = errorOf([&] { loadGltf(writeFile(".gltf", doc.json("nowhere.bin")).string()); });
  EXPECT_CONTAINS(message, "glTF parse error");
  EXPECT_CONTAINS(message, "nowhere.bin");
}

TEST(GltfLoaderErrors, TruncatedGlb) {
  std::vector<unsigned char> glb = triangleDoc().glb();
  std::vector<unsigned char> half(glb.begin(), glb.begin() + std::ptrdiff_t(glb.size() / 2));
  std::string message = errorOf([&] { loadGltf(writeFile(".glb", half).string()); });
  EXPECT_EQ(message.rfind(scratchFile(".glb").filename().string() + ": truncated .glb", 0), 0u) << message;
  // every shorter prefix fails cleanly too
  for (std::size_t size = 0; size < glb.size(); ++size) {
    std::string_view prefix(reinterpret_cast<const char*>(glb.data()), size);
    EXPECT_THROW(loadGltfFromMemory(prefix, "cut.glb", "."), SceneError) << size << " bytes";
  }
  // a BIN chunk that claims more than the file holds
  std::vector<unsigned char> lying = glb;
  std::size_t jsonLength = lying[12] | (lying[13] << 8) | (lying[14] << 16) | (std::size_t(lying[15]) << 24);
  lying[20 + jsonLength] += 8;
  message = errorOf([&] {
    loadGltfFromMemory(std::string_view(reinterpret_cast<const char*>(lying.data()), lying.size()),
                       "lying.glb", ".");
  });
  EXPECT_CONTAINS(message, "lying.glb: truncated .glb: the BIN chunk");
}

// ---------------------------------------------------------------------------
// fuzz: mutated copies of a valid file load or throw SceneError, never crash

/// A document that touches most of the loader: hierarchy, normals,
/// texcoords, sparse positions, a strip, a camera and materials.
GltfDoc richDoc() {
  GltfDoc doc;
  int base = doc.addView(std::vector<glm::vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  int sparseIndices = doc.addView(std::vector<std::uint8_t>{2});
  int sparseValues = doc.addView(std::vector<glm::vec3>{{2, 2, 0}});
  int position = doc.addAccessor(
      base, kFloat, 4, "VEC3",
      ",\"sparse\":{\"count\":1,\"indices\":{\"bufferView\":" + str(sparseIndices) +
          ",\"componentType\":5121},\"values\":{\"bufferView\":" + str(sparseValues) + "}}");
  int normal = doc.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
  int uv = doc.addAccessor(doc.addView(std::vector<std::uint16_t>{0, 0, 65535, 0, 65535, 65535, 0, 65535}),
                           kUShort, 4, "VEC2", ",\"normalized\":true");
  int indices = doc.addIndices<std::uint16_t>({0, 1, 2, 0, 2, 3});
  doc.addMesh("{\"attributes\":{\"POSITION\":" + str(position) + ",\"NORMAL\":" + str(normal) +
              ",\"TEXCOORD_0\":" + str(uv) + "},\"indices\":" + str(indices) + ",\"material\":0},"
              "{\"attributes\":{\"POSITION\":" + str(position) + "},\"mode\":5}");
  doc.materials.push_back("{\"name\":\"m\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1]},"
                          "\"emissiveFactor\":[1,1,1]}");
  doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.1}}");
  doc.addNode("{\"translation\":[1,2,3],\"rotation\":[0,0,0,1],\"scale\":[1,-1,1],\"children\":[1,2]}");
  doc.addNode("{\"mesh\":0}");
  doc.addNode("{\"camera\":0,\"matrix\":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,9,1]}");
  doc.scenes.push_back("{\"nodes\":[0]}");
  doc.scene = 0;
  return doc;
}

/// Load `bytes`; success must give a consistent scene, failure a SceneError.
void loadMutant(const std::string& bytes, const std::string& name, int iteration) {
  try {
    Scene s = loadGltfFromMemory(bytes, name, test::scratchDir("gltf").string());
    expectConsistent(s);
  } catch (const SceneError& e) {
    std::string message = e.what();
    ASSERT_EQ(message.rfind(name + ": ", 0), 0u) << "iteration " << iteration << ": " << message;
  }
}

TEST(GltfLoaderFuzz, MutatedFilesNeverCrash) {
  GltfDoc doc = richDoc();
  const std::string text = doc.embedded();
  const std::vector<unsigned char> glbBytes = doc.glb();
  const std::string glb(glbBytes.begin(), glbBytes.end());
  {
    Scene s = loadGltfFromMemory(text, "rich.gltf", ".");
    ASSERT_EQ(s.triangles.size(), 4u);  // the valid file really loads
    ASSERT_TRUE(s.camera.has_value());
    ASSERT_EQ(loadGltfFromMemory(glb, "rich.glb", ".").triangles.size(), 4u);
  }
  // where the JSON's numbers are: mutating digits keeps most files parseable
  // and so reaches the loader's own checks rather than the JSON parser
  const std::size_t jsonEnd = text.find("\"buffers\"");
  std::vector<std::size_t> digits;
  for (std::size_t i = 0; i < jsonEnd; ++i)
    if (text[i] >= '0' && text[i] <= '9') digits.push_back(i);

  std::mt19937 rng(20240601);
  auto pick = [&](std::size_t n) { return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng); };
  auto byte = [&] { return char(std::uniform_int_distribution<int>(0, 255)(rng)); };
  for (int i = 0; i < 300; ++i) {
    std::string mutant = text;
    for (std::size_t k = 1 + pick(4); k > 0; --k) mutant[pick(mutant.size())] = byte();
    loadMutant(mutant, "bytes.gltf", i);
  }
  for (int i = 0; i < 400; ++i) {
    std::string mutant = text;
    for (std::size_t k = 1 + pick(2); k > 0; --k) {
      std::size_t at = digits[pick(digits.size())];
      mutant[at] = char('0' + pick(10));
      if (pick(4) == 0) mutant.insert(at, std::string(1 + pick(9), char('1' + pick(9))));
    }
    loadMutant(mutant, "digits.gltf", i);
  }
  for (int i = 0; i < 300; ++i) {
    std::string mutant = glb;
    for (std::size_t k = 1 + pick(4); k > 0; --k) mutant[pick(mutant.size())] = byte();
    if (pick(8) == 0) mutant.resize(pick(mutant.size()));
    loadMutant(mutant, "bytes.glb", i);
  }
}

}  // namespace
}  // namespace wt
