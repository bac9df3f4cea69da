// PLY meshes (host/scene/ply.h): every format, polygons as fans, texture
// coordinates turned to glTF's convention, smooth normals when the file has
// none, and errors that name the file and the element.
#include "scene/ply.h"
#include "scene/scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

namespace wt {
namespace {

std::vector<std::uint8_t> bytesOf(const std::string& s) { return {s.begin(), s.end()}; }

/// A pyramid: a square base (one quad, facing -z) and four triangles up to
/// the apex (0.5, 0.5, 1); s, t texture coordinates; in `format`.
std::vector<std::uint8_t> pyramid(const std::string& format) {
  const float v[5][5] = {{0, 0, 0, 0, 0}, {1, 0, 0, 1, 0}, {1, 1, 0, 1, 1}, {0, 1, 0, 0, 1}, {0.5f, 0.5f, 1, 0.5f, 0.25f}};
  const std::vector<std::vector<int>> faces = {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};
  std::string out = "ply\nformat " + format + " 1.0\ncomment a pyramid\nelement vertex 5\n";
  out += "property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n";
  out += "element face 5\nproperty list uchar int vertex_indices\nend_header\n";
  const bool big = format == "binary_big_endian";
  auto put = [&](const void* p, std::size_t n) {
    std::string b(static_cast<const char*>(p), n);
    if (big) b.assign(b.rbegin(), b.rend());
    out += b;
  };
  for (const auto& row : v)
    for (float x : row) {
      if (format == "ascii") out += std::to_string(x) + " ";
      else put(&x, 4);
    }
  if (format == "ascii") out += "\n";
  for (const auto& f : faces) {
    const auto n = std::uint8_t(f.size());
    if (format == "ascii") out += std::to_string(f.size());
    else put(&n, 1);
    for (int i : f) {
      if (format == "ascii") out += " " + std::to_string(i);
      else put(&i, 4);
    }
    if (format == "ascii") out += "\n";
  }
  return bytesOf(out);
}

TEST(PlyMesh, ReadsEveryFormat) {
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    SCOPED_TRACE(format);
    const PlyMesh m = readPlyMesh(pyramid(format), "p.ply");
    ASSERT_EQ(m.positions.size(), 5u);
    // the quad as a fan of two triangles, then the four sides
    ASSERT_EQ(m.triangles.size(), 6u);
    EXPECT_EQ(m.triangles[0], (std::array<std::uint32_t, 3>{0, 3, 2}));
    EXPECT_EQ(m.triangles[1], (std::array<std::uint32_t, 3>{0, 2, 1}));
    EXPECT_EQ(m.triangles[5], (std::array<std::uint32_t, 3>{3, 0, 4}));
    EXPECT_EQ(m.positions[4], glm::dvec3(0.5, 0.5, 1.0));
    // t runs up in PLY (as in OBJ), v down in glTF
    ASSERT_EQ(m.texcoords.size(), 5u);
    EXPECT_EQ(m.texcoords[4], glm::vec2(0.5f, 0.75f));
    // smooth normals: the apex points up, a base corner down and out
    ASSERT_EQ(m.normals.size(), 5u);
    EXPECT_NEAR(m.normals[4].z, 1.0f, 1e-6f);
    EXPECT_NEAR(glm::length(m.normals[0]), 1.0f, 1e-6f);
    EXPECT_LT(m.normals[0].z, 0.0f);
    EXPECT_LT(m.normals[0].x, 0.0f);
    EXPECT_NEAR(m.normals[0].x, m.normals[0].y, 1e-6f);
  }
}

TEST(PlyMesh, KeepsTheFilesNormals) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
      "property float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar uint vertex_index\n"
      "end_header\n0 0 0 0 0 2\n1 0 0 0 3 0\n0 1 0 nan 0 1\n3 0 1 2\n";
  const PlyMesh m = readPlyMesh(bytesOf(text), "n.ply");
  ASSERT_EQ(m.normals.size(), 3u);
  EXPECT_EQ(m.normals[0], glm::vec3(0, 0, 1));  // made unit
  EXPECT_EQ(m.normals[1], glm::vec3(0, 1, 0));
  EXPECT_EQ(m.normals[2], glm::vec3(0, 0, 0));  // not finite: none
  EXPECT_TRUE(m.texcoords.empty());
}

std::string errorOf(const std::string& text) {
  try {
    readPlyMesh(bytesOf(text), "bad.ply");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(PlyMesh, ErrorsNameTheFileAndTheElement) {
  const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string faces = "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string corners = "0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_EQ(errorOf(header + faces + corners + "3 0 1 3\n"), "bad.ply: face 0: vertex index 3 out of range (3 vertices)");
  EXPECT_EQ(errorOf(header + faces + corners + "3 0 -1 2\n"), "bad.ply: face 0: vertex index -1 out of range (3 vertices)");
  EXPECT_EQ(errorOf(header + faces + corners + "2 0 1\n"), "bad.ply: face 0: 2 vertices (a face needs 3 or more)");
  EXPECT_EQ(errorOf(header + faces + "0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
            "bad.ply: vertex 1: coordinate is not finite (nan)");
  EXPECT_EQ(errorOf(header + "end_header\n" + corners),
            "bad.ply: no \"face\" element: a mesh needs its faces (a list \"vertex_indices\" per face)");
  EXPECT_EQ(errorOf(header + "element face 1\nproperty int vertex_indices\nend_header\n" + corners + "0\n"),
            "bad.ply: line 7: face needs a list \"vertex_indices\" (or \"vertex_index\")");
  EXPECT_EQ(errorOf(header + faces + corners + "3 0 1\n"), "bad.ply: face 0, vertex_indices: the file ends before this value (truncated)");
  // a binary count larger than the bytes that are there: refused before anything is allocated
  EXPECT_EQ(errorOf("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n"),
            "bad.ply: vertex: 4000000000 items do not fit in the 0 bytes left (truncated, or the count is wrong)");
  EXPECT_EQ(errorOf("plx\n"), "bad.ply: line 1: not a PLY file (it does not begin with \"ply\")");
}

}  // namespace
}  // namespace wt
