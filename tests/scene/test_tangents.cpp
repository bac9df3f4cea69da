// Generated tangents (host/scene/tangents.h): direction and handedness by
// glTF's convention, splits at mirrored seams, and fallbacks.
#include "scene/tangents.h"

#include <gtest/gtest.h>

#include <cmath>

namespace wt {
namespace {

void expectVec(glm::vec3 a, glm::vec3 b, float tol = 1e-5f) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

// A quad in the z = 0 plane facing +z, u along +x and v along -y (glTF's v
// runs down the image, so the image's up is +y): tangent +x, and the
// bitangent w cross(n, t) = +y = -dp/dv, so w = +1.
TEST(Tangents, FollowUAndPointTheBitangentUpTheImage) {
  std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  std::vector<glm::vec3> n(4, glm::vec3(0, 0, 1));
  std::vector<glm::vec2> uv = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  std::vector<std::uint32_t> corners = {0, 1, 2, 0, 2, 3};
  std::vector<glm::vec4> t;
  std::vector<std::uint32_t> sources = generateTangents(p, n, uv, corners, t);
  ASSERT_EQ(sources.size(), 4u);
  for (const glm::vec4& v : t) {
    expectVec(glm::vec3(v), glm::vec3(1, 0, 0));
    EXPECT_EQ(v.w, 1.0f);
    expectVec(v.w * glm::cross(glm::vec3(0, 0, 1), glm::vec3(v)), glm::vec3(0, 1, 0));
  }
  // v running up the image instead: the same tangent, the other hand
  for (glm::vec2& c : uv) c.y = 1.0f - c.y;
  generateTangents(p, n, uv, corners, t);
  for (const glm::vec4& v : t) {
    expectVec(glm::vec3(v), glm::vec3(1, 0, 0));
    EXPECT_EQ(v.w, -1.0f);
  }
}

// Two quads side by side sharing the edge x = 1, the right one with its u
// mirrored (a mirrored UV island): the two shared vertices are split, each
// side keeps its own tangent and hand, and no corner is lost.
TEST(Tangents, MirroredSeamSplitsTheSharedVertices) {
  std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {2, 0, 0}, {2, 1, 0}};
  std::vector<glm::vec3> n(6, glm::vec3(0, 0, 1));
  std::vector<glm::vec2> uv = {{0, 1}, {1, 1}, {1, 0}, {0, 0}, {0, 1}, {0, 0}};
  std::vector<std::uint32_t> corners = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2};
  std::vector<glm::vec4> t;
  std::vector<std::uint32_t> sources = generateTangents(p, n, uv, corners, t);
  ASSERT_EQ(sources.size(), 8u);
  EXPECT_EQ(sources[6], 1u);
  EXPECT_EQ(sources[7], 2u);
  ASSERT_EQ(t.size(), 8u);
  // left quad: +x, right-handed; right quad: -x (u grows leftwards), left-handed
  for (std::size_t c = 0; c < 6; ++c) {
    expectVec(glm::vec3(t[corners[c]]), glm::vec3(1, 0, 0));
    EXPECT_EQ(t[corners[c]].w, 1.0f);
  }
  for (std::size_t c = 6; c < 12; ++c) {
    expectVec(glm::vec3(t[corners[c]]), glm::vec3(-1, 0, 0));
    EXPECT_EQ(t[corners[c]].w, -1.0f);
    // both sides agree on the bitangent: up the image
    expectVec(t[corners[c]].w * glm::cross(glm::vec3(0, 0, 1), glm::vec3(t[corners[c]])), glm::vec3(0, 1, 0));
    EXPECT_EQ(p[sources[corners[c]]], p[corners[c] < 6 ? corners[c] : sources[corners[c]]]);
  }
}

// Curved normals: each tangent is orthogonal to its own vertex normal; a
// triangle without texture-space area (all uv equal) still gets unit
// tangents perpendicular to the normal, and nothing is NaN.
TEST(Tangents, OrthogonalToTheNormalWithFallbacks) {
  std::vector<glm::vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  std::vector<glm::vec3> n = {glm::normalize(glm::vec3(0.3f, 0, 1)), glm::normalize(glm::vec3(0, 0.5f, 1)),
                              glm::vec3(0, 0, 1)};
  std::vector<glm::vec2> uv = {{0, 1}, {1, 1}, {0, 0}};
  std::vector<std::uint32_t> corners = {0, 1, 2};
  std::vector<glm::vec4> t;
  generateTangents(p, n, uv, corners, t);
  for (std::size_t v = 0; v < 3; ++v) {
    EXPECT_NEAR(glm::length(glm::vec3(t[v])), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(glm::vec3(t[v]), n[v]), 0.0f, 1e-5f);
    EXPECT_GT(t[v].x, 0.9f);
  }
  uv.assign(3, glm::vec2(0.5f));
  generateTangents(p, n, uv, corners, t);
  for (std::size_t v = 0; v < 3; ++v) {
    EXPECT_NEAR(glm::length(glm::vec3(t[v])), 1.0f, 1e-5f);
    EXPECT_NEAR(glm::dot(glm::vec3(t[v]), n[v]), 0.0f, 1e-5f);
  }
  // no normals: the triangle's own
  generateTangents(p, {}, uv, corners, t);
  for (const glm::vec4& v : t) EXPECT_NEAR(v.z, 0.0f, 1e-6f);
}

}  // namespace
}  // namespace wt
