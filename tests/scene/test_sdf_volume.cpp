// SDF grids in scene files: procedural shapes read back (their values in
// voxel units), Mitsuba .vol grids written and read back, and every bad
// input refused naming the scene file, the field and the .vol file, or
// loaded with a warning where it merely draws nothing.
#include "geometry/primitives.h"
#include "scene/scene_file.h"
#include "scene/sdf_volume.h"

#include "test_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace wt {
namespace {

namespace fs = std::filesystem;

#define EXPECT_CONTAINS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

fs::path testDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = test::scratchDir("sdf_volume") / (std::string(info->test_suite_name()) + "." + info->name());
  fs::create_directories(dir);
  return dir;
}

SceneFile loadObject(const std::string& object) {
  const fs::path path = testDir() / "scene.json";
  std::ofstream(path) << R"({"version": 1, "objects": [)" + object + "]}";
  return loadSceneFile(path.string());
}

std::string errorOf(const std::string& object) {
  try {
    loadObject(object);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(loaded)";
}

/// A sphere of radius 0.3 in the unit box, `n` corners a side, in box units.
std::vector<float> sphereValues(std::uint32_t n) {
  std::vector<float> v;
  for (std::uint32_t z = 0; z < n; ++z)
    for (std::uint32_t y = 0; y < n; ++y)
      for (std::uint32_t x = 0; x < n; ++x) {
        const glm::dvec3 p = glm::dvec3(x, y, z) / double(n - 1) - 0.5;
        v.push_back(float(glm::length(p) - 0.3));
      }
  return v;
}

TEST(SdfScene, ProceduralShapesInVoxelUnits) {
  const SceneFile f = loadObject(
      R"({"type": "sdf", "shape": "sphere", "radius": 0.5, "resolution": 16, "transform": {"translate": [1, 2, 3], "scale": 2}})");
  ASSERT_EQ(f.scene.sdfGrids.size(), 1u);
  const SdfGrid& g = f.scene.sdfGrids[0];
  EXPECT_EQ(g.cells, glm::uvec3(16));
  ASSERT_EQ(g.values.size(), 17u * 17u * 17u);
  // the centre corner (8, 8, 8) lies 0.5 inside: 4 cells of 2 / 16
  EXPECT_NEAR(g.values[8 + 17 * (8 + 17 * 8)], -4.0f, 1e-5f);
  // the lattice spans [-1, 1]^3 scaled by 2 about (1, 2, 3), less the scene's origin
  const glm::dvec3 centre = glm::dvec3(g.latticeToScene * glm::dvec4(8.0, 8.0, 8.0, 1.0)) + f.scene.origin;
  EXPECT_NEAR(centre.x, 1.0, 1e-9);
  EXPECT_NEAR(centre.z, 3.0, 1e-9);
  const glm::dvec3 corner = glm::dvec3(g.latticeToScene * glm::dvec4(16.0, 16.0, 16.0, 1.0)) + f.scene.origin;
  EXPECT_NEAR(corner.y, 4.0, 1e-9);
  EXPECT_TRUE(f.scene.warnings.empty());
  for (const char* shape : {"torus", "box", "noisy_sphere"}) {
    const SceneFile s = loadObject(std::string(R"({"type": "sdf", "resolution": 8, "shape": ")") + shape + "\"}");
    ASSERT_EQ(s.scene.sdfGrids.size(), 1u) << shape;
    EXPECT_EQ(sdfSurfaceProblem(s.scene.sdfGrids[0].values), "") << shape;
  }
}

TEST(SdfScene, StorageIsSparseAboveTheStatedSize) {
  SdfGrid g;
  g.cells = glm::uvec3(64);
  EXPECT_FALSE(sdfGridSparse(g));
  g.cells = glm::uvec3(65, 64, 64);
  EXPECT_TRUE(sdfGridSparse(g));
  g.storage = SdfStorage::kDense;
  EXPECT_FALSE(sdfGridSparse(g));
  const SceneFile f = loadObject(R"({"type": "sdf", "shape": "box", "resolution": 4, "storage": "sparse"})");
  EXPECT_TRUE(sdfGridSparse(f.scene.sdfGrids[0]));
}

TEST(SdfScene, VolFilesReadBackInVoxelUnits) {
  const fs::path vol = testDir() / "ball.vol";
  writeVolFile(vol.string(), glm::uvec3(11), sphereValues(11), glm::dvec3(0.0), glm::dvec3(1.0));
  const SceneFile f = loadObject(R"({"type": "sdf", "file": "ball.vol"})");
  ASSERT_EQ(f.scene.sdfGrids.size(), 1u);
  const SdfGrid& g = f.scene.sdfGrids[0];
  EXPECT_EQ(g.cells, glm::uvec3(10));
  // the centre is 0.3 inside: 3 cells of 0.1
  EXPECT_NEAR(g.values[5 + 11 * (5 + 11 * 5)], -3.0f, 1e-5f);
  PrimitiveRows rows = gatherPrimitives(f.scene);
  EXPECT_GT(rows.count[WT_PRIM_SDF_GRID], 0u);
}

TEST(SdfScene, RawGridsReadBackInTheirBox) {
  // a sphere of radius 0.3 in the unit box, 10 cells a side, in box units
  const std::vector<float> values = sphereValues(11);
  std::ofstream(testDir() / "ball.raw", std::ios::binary)
      .write(reinterpret_cast<const char*>(values.data()), std::streamsize(values.size() * 4));
  const SceneFile f = loadObject(
      R"({"type": "sdf", "file": "ball.raw", "resolution": [10, 10, 10], "box": [0, 0, 0, 1, 1, 1]})");
  ASSERT_EQ(f.scene.sdfGrids.size(), 1u);
  const SdfGrid& g = f.scene.sdfGrids[0];
  EXPECT_EQ(g.cells, glm::uvec3(10));
  EXPECT_NEAR(g.values[5 + 11 * (5 + 11 * 5)], -3.0f, 1e-5f);
  const glm::dvec3 top = glm::dvec3(g.latticeToScene * glm::dvec4(10.0, 10.0, 10.0, 1.0)) + f.scene.origin;
  EXPECT_NEAR(top.x, 1.0, 1e-9);
  // the wrong shape for the file's size, a missing resolution, a box on a .vol
  const std::string wrong = errorOf(R"({"type": "sdf", "file": "ball.raw", "resolution": [10, 10, 9]})");
  EXPECT_CONTAINS(wrong, "objects[0].file: ball.raw: has 5324 bytes; 11 x 11 x 10 float32 corner values take 4840");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "file": "ball.raw"})"), "objects[0].resolution: missing");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "file": "ball.raw", "resolution": [10, 10, 10], "box": [0, 0, 0, 1, 0, 1]})"),
                  "objects[0].box");
  writeVolFile((testDir() / "ball.vol").string(), glm::uvec3(11), values, glm::dvec3(0.0), glm::dvec3(1.0));
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "file": "ball.vol", "box": [0, 0, 0, 1, 1, 1]})"), "objects[0].box");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "box", "resolution": 4, "box": [0, 0, 0, 1, 1, 1]})"),
                  "objects[0].box");
}

/// Writes `bytes` as bad.vol and returns the error of loading it.
std::string volError(const std::string& bytes) {
  std::ofstream(testDir() / "bad.vol", std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  return errorOf(R"({"type": "sdf", "file": "bad.vol"})");
}

std::string volBytes(int version, std::int32_t encoding, glm::ivec3 res, std::int32_t channels, std::size_t values,
                     float fill = 1.0f) {
  std::string s = "VOL";
  s += char(version);
  auto put = [&](const void* p, std::size_t n) { s.append(static_cast<const char*>(p), n); };
  const std::int32_t head[5] = {encoding, res.x, res.y, res.z, channels};
  put(head, sizeof(head));
  const float box[6] = {0, 0, 0, 1, 1, 1};
  put(box, sizeof(box));
  std::vector<float> v(values, fill);
  if (values > 3) v[3] = -1.0f;
  put(v.data(), v.size() * 4);
  return s;
}

TEST(SdfScene, BadVolFilesAreRefusedNamingTheFileAndTheProblem) {
  const std::string good = volBytes(3, 1, {3, 3, 3}, 1, 27);
  EXPECT_EQ(volError(good), "(loaded)");
  const std::string truncated = volError(good.substr(0, good.size() - 5));
  EXPECT_CONTAINS(truncated, "scene.json: objects[0].file");
  EXPECT_CONTAINS(truncated, "bad.vol");
  EXPECT_CONTAINS(truncated, "truncated");
  EXPECT_CONTAINS(volError(good.substr(0, 20)), "truncated");
  EXPECT_CONTAINS(volError("PNG whatever"), "does not start with \"VOL\"");
  EXPECT_CONTAINS(volError(volBytes(2, 1, {3, 3, 3}, 1, 27)), "version 2");
  EXPECT_CONTAINS(volError(volBytes(3, 2, {3, 3, 3}, 1, 27)), "encoding 2");
  EXPECT_CONTAINS(volError(volBytes(3, 1, {3, 3, 3}, 3, 81)), "3 channels");
  EXPECT_CONTAINS(volError(volBytes(3, 1, {1, 3, 3}, 1, 9)), "resolution x");
  std::string nan = volBytes(3, 1, {3, 3, 3}, 1, 27);
  const float q = std::nanf("");
  std::memcpy(&nan[48 + 4 * 13], &q, 4);
  const std::string nanError = volError(nan);
  EXPECT_CONTAINS(nanError, "value 13 (x 1, y 1, z 1) is NaN");
  EXPECT_CONTAINS(nanError, "bad.vol");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "file": "missing.vol"})"), "objects[0].file");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "file": "ball.npy"})"), "must be a .vol grid or a .raw grid");
}

TEST(SdfScene, BadFieldsAreRefusedNamingThem) {
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "cone", "resolution": 8})"), "objects[0].shape: unknown shape");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere"})"), "objects[0].resolution: missing");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 1})"), "objects[0].resolution");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 100000})"), "objects[0].resolution");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 8, "radius": -1})"), "objects[0].radius");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 8, "storage": "tiled"})"),
                  "objects[0].storage");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf"})"), "objects[0].shape: missing");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 8, "file": "a.vol"})"), "not both");
  EXPECT_CONTAINS(errorOf(R"({"type": "sdf", "shape": "sphere", "resolution": 8, "colour": 1})"),
                  "objects[0].colour: unknown field");
}

TEST(SdfScene, GridsWithoutSurfaceLoadWithAWarning) {
  // all inside (a sphere larger than its box) and all outside (one smaller than a cell's reach)
  for (const char* object : {R"({"type": "sdf", "shape": "sphere", "radius": 3, "resolution": 8})",
                             R"({"type": "sdf", "shape": "sphere", "radius": 0.01, "resolution": 3})"}) {
    const SceneFile f = loadObject(object);
    ASSERT_EQ(f.scene.warnings.size(), 1u) << object;
    EXPECT_CONTAINS(f.scene.warnings[0], "objects[0] has no surface");
    EXPECT_EQ(gatherPrimitives(f.scene).count[WT_PRIM_SDF_GRID], 0u);
  }
  const fs::path vol = testDir() / "flat.vol";
  writeVolFile(vol.string(), glm::uvec3(4), std::vector<float>(64, 0.5f), glm::dvec3(0.0), glm::dvec3(1.0));
  const SceneFile f = loadObject(R"({"type": "sdf", "file": "flat.vol"})");
  ASSERT_EQ(f.scene.warnings.size(), 1u);
  EXPECT_CONTAINS(f.scene.warnings[0], "positive or zero");
}

}  // namespace
}  // namespace wt
