// Light selection and MIS on the device: the alias table reproduces its
// pmf (chi-square), the MIS weights of the two strategies sum to one, and
// spherical-triangle sampling is uniform in solid angle (chi-square) and as
// accurate as Arvo's formulas with library trigonometry.
#include "device/program.h"
#include "device_fixture.h"
#include "render/light_list.h"
#include "shared/rng.h"
#include "test_util.h"

#include <glm/glm.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

namespace wt {
namespace {

TEST(LightSampling, AliasTableReproducesItsPmf) {
  Context& ctx = test::deviceContext();
  // uneven weights, zeros included: a zero-weight light is never chosen
  std::vector<double> weights = {5.0, 0.0, 1.0, 0.25, 12.0, 3.0, 0.0, 0.5, 7.5, 2.0, 1e-3};
  std::vector<WtAliasSlot> table = buildAliasTable(weights);
  double sum = 0.0;
  for (double w : weights) sum += w;
  for (std::size_t i = 0; i < weights.size(); ++i) EXPECT_FLOAT_EQ(table[i].pmf, float(weights[i] / sum));

  // the rarest light (1e-3 of the weight) still expects 2 picks at the small size
  const cl_uint n = test::testSize(1 << 20, 1 << 16);
  cl::Buffer alias(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, table.size() * sizeof(WtAliasSlot), table.data());
  cl::Buffer chosen(ctx.context(), CL_MEM_WRITE_ONLY, n * 4), pmf(ctx.context(), CL_MEM_WRITE_ONLY, n * 4);
  cl::Kernel k(test::unitTestProgram(), "test_light_pick");
  k.setArg(0, n), k.setArg(1, alias), k.setArg(2, cl_uint(table.size())), k.setArg(3, chosen), k.setArg(4, pmf);
  ctx.launch("test_light_pick", k, n);
  std::vector<cl_uint> picks(n);
  std::vector<float> pmfs(n);
  ctx.queue().enqueueReadBuffer(chosen, CL_TRUE, 0, n * 4, picks.data());
  ctx.queue().enqueueReadBuffer(pmf, CL_TRUE, 0, n * 4, pmfs.data());

  std::vector<double> counts(weights.size(), 0.0);
  for (cl_uint i = 0; i < n; ++i) {
    ASSERT_LT(picks[i], weights.size());
    ASSERT_EQ(pmfs[i], table[picks[i]].pmf);  // the pmf returned is the chosen light's
    counts[picks[i]] += 1.0;
  }
  double chi2 = 0.0;
  int dof = -1;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    double expected = n * weights[i] / sum;
    if (weights[i] == 0.0) {
      EXPECT_EQ(counts[i], 0.0) << "light " << i << " has zero weight";
      continue;
    }
    chi2 += (counts[i] - expected) * (counts[i] - expected) / expected;
    ++dof;
  }
  // 8 degrees of freedom: P(chi2 > 26.1) = 0.001
  EXPECT_EQ(dof, 8);
  EXPECT_LT(chi2, 26.1) << "counts: " << ::testing::PrintToString(counts);
}

TEST(LightSampling, AliasTableOfOneAndOfNone) {
  std::vector<double> one = {3.0};
  std::vector<WtAliasSlot> t = buildAliasTable(one);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_FLOAT_EQ(t[0].pmf, 1.0f);
  EXPECT_FLOAT_EQ(t[0].threshold, 1.0f);
  std::vector<double> none = {0.0, 0.0};
  for (const WtAliasSlot& s : buildAliasTable(none)) EXPECT_EQ(s.pmf, 0.0f);
}

TEST(LightSampling, MisWeightsSumToOne) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> logu(-20.0f, 20.0f);
  std::vector<cl_float2> pdfs(4096);
  for (auto& p : pdfs) p = {{std::exp2(logu(rng)), std::exp2(logu(rng))}};
  pdfs[0] = {{1.0f, 0.0f}};  // one strategy cannot sample the direction
  const cl_uint n = cl_uint(pdfs.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 8, pdfs.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * 8);
  cl::Kernel k(test::unitTestProgram(), "test_mis");
  for (cl_uint flags : {0u, cl_uint(WT_FLAG_POWER_HEURISTIC)}) {
    k.setArg(0, n), k.setArg(1, in), k.setArg(2, flags), k.setArg(3, out);
    ctx.launch("test_mis", k, n);
    std::vector<cl_float2> w(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * 8, w.data());
    for (cl_uint i = 0; i < n; ++i) {
      EXPECT_NEAR(w[i].s[0] + w[i].s[1], 1.0f, 2e-6f) << "pdfs " << pdfs[i].s[0] << ", " << pdfs[i].s[1];
      EXPECT_GE(w[i].s[0], 0.0f);
    }
    EXPECT_EQ(w[0].s[0], 1.0f);
  }
}

// Spherical-triangle sampling (lights/light_sampling.cl). A triangle and a
// shading point, in double for the host's side of the checks.
struct TriangleView {
  glm::dvec3 p0, p1, p2, p;
};

/// Solid angle of (a, b, c) seen from p (Van Oosterom and Strackee), double.
double solidAngle(glm::dvec3 p, glm::dvec3 a, glm::dvec3 b, glm::dvec3 c) {
  a -= p, b -= p, c -= p;
  const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
  const double num = std::fabs(glm::dot(a, glm::cross(b, c)));
  const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(a, c) * lb + glm::dot(b, c) * la;
  return std::fabs(2.0 * std::atan2(num, den));
}

/// Barycentrics (b1, b2) where the ray p + t w meets the triangle's plane.
glm::dvec2 planeBarycentrics(const TriangleView& v, glm::dvec3 w) {
  const glm::dvec3 e1 = v.p1 - v.p0, e2 = v.p2 - v.p0, tv = v.p - v.p0;
  const glm::dvec3 pv = glm::cross(w, e2), qv = glm::cross(tv, e1);
  const double inv = 1.0 / glm::dot(e1, pv);
  return {glm::dot(tv, pv) * inv, glm::dot(w, qv) * inv};
}

/// The device's spherical-triangle directions for views[i] and uniforms u[i]:
/// per view (direction, solid angle) from the sampler, then the reference's.
std::vector<cl_float4> sampleSphericalTriangles(const std::vector<TriangleView>& views, const std::vector<cl_float2>& u) {
  Context& ctx = test::deviceContext();
  const cl_uint n = cl_uint(views.size());
  std::vector<cl_float4> verts, points;
  for (const TriangleView& v : views) {
    for (glm::dvec3 c : {v.p0, v.p1, v.p2}) verts.push_back({{float(c.x), float(c.y), float(c.z), 0.0f}});
    points.push_back({{float(v.p.x), float(v.p.y), float(v.p.z), 0.0f}});
  }
  cl::Buffer vb(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, verts.size() * 16, verts.data());
  cl::Buffer pb(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, points.size() * 16, points.data());
  cl::Buffer ub(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 8, const_cast<cl_float2*>(u.data()));
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 2 * n * 16);
  cl::Kernel k(test::unitTestProgram(), "test_spherical_triangle");
  k.setArg(0, n), k.setArg(1, vb), k.setArg(2, pb), k.setArg(3, ub), k.setArg(4, out);
  ctx.launch("test_spherical_triangle", k, n);
  std::vector<cl_float4> got(2 * n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, 2 * n * 16, got.data());
  return got;
}

/// Arvo's sampling in double: the reference both float versions are held to.
glm::dvec3 arvoDouble(const TriangleView& v, double u1, double u2) {
  const glm::dvec3 A = glm::normalize(v.p0 - v.p), B = glm::normalize(v.p1 - v.p), C = glm::normalize(v.p2 - v.p);
  auto ortho = [](glm::dvec3 a, glm::dvec3 b) {
    const glm::dvec3 w = a - glm::dot(a, b) * b;
    return glm::length(w) > 0.0 ? glm::normalize(w) : glm::dvec3(0.0);
  };
  const glm::dvec3 n_ab = ortho(B, A), n_ac = ortho(C, A);
  const double cos_alpha = std::clamp(glm::dot(n_ab, n_ac), -1.0, 1.0), sin_alpha = std::sqrt(1.0 - cos_alpha * cos_alpha);
  const double alpha = std::acos(cos_alpha), area = u1 * solidAngle(v.p, v.p0, v.p1, v.p2);
  const double s = -std::sin(area - alpha), t = -std::cos(area - alpha), cos_c = glm::dot(A, B);
  const double k1 = t + cos_alpha, k2 = s - sin_alpha * cos_c;
  const double cos_b = std::clamp((k2 + (k2 * t - k1 * s) * cos_alpha) / ((k2 * s + k1 * t) * sin_alpha), -1.0, 1.0);
  const glm::dvec3 c_prime = cos_b * A + std::sqrt(1.0 - cos_b * cos_b) * n_ac;
  const double cos_theta = 1.0 - u2 * (1.0 - glm::dot(c_prime, B));
  return glm::normalize(cos_theta * B + std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta)) * ortho(c_prime, B));
}

// The sampler (sin and cos of the area from one polynomial, the angle at A by
// its sine and cosine) computes Arvo's mapping as accurately as Arvo's
// formulas with the library's acos, sin and cos do: on random triangles and
// shading points whose solid angle spans the range it is used for, both
// float versions against the mapping in double, in barycentrics of the
// sampled point. The mapping is ill-conditioned where the sub-triangle's
// area u1 x solid angle is tiny (cos(area - alpha) + cos(alpha) cancels), so
// single points may be off by percent in either version; the test holds the
// sampler to the reference's error distribution: its median error below
// 1e-5 of the triangle's size and its points off by more than 1e-3 no more
// frequent than the library version's, up to counting noise.
TEST(LightSampling, SphericalTriangleSamplingIsAsAccurateAsArvosFormulas) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> box(-1.0, 1.0), unit(0.0, 1.0), logd(-2.5, 1.5);
  std::vector<TriangleView> views;
  std::vector<cl_float2> u;
  const std::size_t count = test::testSize(40000, 4000);
  while (views.size() < count) {
    TriangleView v{{box(rng), box(rng), box(rng)}, {box(rng), box(rng), box(rng)}, {box(rng), box(rng), box(rng)}, {}};
    const glm::dvec3 n = glm::cross(v.p1 - v.p0, v.p2 - v.p0);
    if (glm::length(n) < 1e-2) continue;
    // above a point of the triangle's plane near it, at a distance from 3e-3 to 30
    const double a = unit(rng), b = unit(rng) * (1.0 - a);
    const glm::dvec3 foot = v.p0 + 1.4 * (a * (v.p1 - v.p0) + b * (v.p2 - v.p0)) - 0.2 * (v.p1 - v.p0);
    v.p = foot + (unit(rng) < 0.5 ? -1.0 : 1.0) * std::pow(10.0, logd(rng)) * glm::normalize(n);
    // the corners and the point as the device sees them
    for (glm::dvec3* c : {&v.p0, &v.p1, &v.p2, &v.p}) *c = glm::dvec3(glm::vec3(*c));
    views.push_back(v);
    u.push_back({{float(unit(rng)), float(unit(rng))}});
  }
  const std::vector<cl_float4> got = sampleSphericalTriangles(views, u);
  int used = 0, far[2] = {0, 0};
  std::vector<double> errors[2];
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (!(got[2 * i].s[3] >= 1e-3f && got[2 * i].s[3] <= 6.2f)) continue;  // light_use_spherical
    ++used;
    const glm::dvec2 want = planeBarycentrics(views[i], arvoDouble(views[i], u[i].s[0], u[i].s[1]));
    for (int version = 0; version < 2; ++version) {
      const cl_float4 w = got[2 * i + std::size_t(version)];
      const glm::dvec2 b = planeBarycentrics(views[i], {w.s[0], w.s[1], w.s[2]});
      const double err = std::max(std::fabs(b.x - want.x), std::fabs(b.y - want.y));
      errors[version].push_back(err);
      far[version] += !(err <= 1e-3);
    }
  }
  EXPECT_GT(used, int(count / 2));
  for (std::vector<double>& e : errors) std::sort(e.begin(), e.end());
  EXPECT_LE(errors[0][errors[0].size() / 2], 1e-5) << "median error; the library version's: " << errors[1][errors[1].size() / 2];
  // counts of rare events: the sampler's may exceed the reference's by 3 standard deviations
  EXPECT_LE(far[0], far[1] + 3.0 * std::sqrt(double(far[0] + far[1]) + 1.0))
      << far[0] << " points off by more than 1e-3, the library version " << far[1] << " (of " << used << ")";
  std::printf("spherical triangles: %d views, median error %.3g (library %.3g), off by > 1e-3: %d (library %d)\n", used,
              errors[0][errors[0].size() / 2], errors[1][errors[1].size() / 2], far[0], far[1]);
}

// Directions are uniform in the triangle's solid angle: the triangle cut into
// 36 cells (a 6 x 6 barycentric grid), the counts per cell against each
// cell's solid angle over the whole (chi-square, P(fail) = 1e-4 per view),
// for a near, a far, a grazing and an almost-hemispherical view; every
// direction meets the triangle.
TEST(LightSampling, SphericalTriangleSamplingIsUniformInSolidAngle) {
  const int m = 6;
  const cl_uint perView = test::testSize(1 << 18, 1 << 16);
  const glm::dvec3 p0{0.0, 0.0, 0.0}, p1{1.0, 0.0, 0.0}, p2{0.3, 0.8, 0.0};
  const std::vector<TriangleView> shapes = {
      {p0, p1, p2, {0.4, 0.3, 0.25}},    // near: about 2 sr
      {p0, p1, p2, {0.5, -0.2, 6.0}},    // far: about 1e-2 sr
      {p0, p1, p2, {2.5, 1.5, 0.2}},     // grazing
      {p0, p1, p2, {0.4, 0.27, -0.01}},  // almost a hemisphere, from the back
  };
  std::vector<TriangleView> views;
  std::vector<cl_float2> u;
  for (const TriangleView& v : shapes)
    for (cl_uint i = 0; i < perView; ++i) {
      views.push_back(v);
      u.push_back({{rng_uniform(i, 0u, 0u, 0u, 5u), rng_uniform(i, 0u, 0u, 1u, 5u)}});
    }
  const std::vector<cl_float4> got = sampleSphericalTriangles(views, u);
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const TriangleView& v = shapes[s];
    const double omega = solidAngle(v.p, v.p0, v.p1, v.p2);
    ASSERT_TRUE(omega >= 1e-3 && omega <= 6.2) << "view " << s << " is not one the sampler is used for: " << omega;
    // cell (i, j, upper) of the barycentric grid, its corners, its solid angle
    auto corner = [&](double b1, double b2) { return v.p0 + b1 / m * (v.p1 - v.p0) + b2 / m * (v.p2 - v.p0); };
    std::vector<double> expected, counts;
    std::vector<std::array<int, 3>> cells;
    for (int i = 0; i < m; ++i)
      for (int j = 0; i + j < m; ++j)
        for (int upper = 0; upper < (i + j < m - 1 ? 2 : 1); ++upper) {
          const double cell = upper ? solidAngle(v.p, corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1))
                                    : solidAngle(v.p, corner(i, j), corner(i + 1, j), corner(i, j + 1));
          expected.push_back(perView * cell / omega);
          cells.push_back({i, j, upper});
        }
    ASSERT_EQ(expected.size(), std::size_t(m * m));
    counts.assign(expected.size(), 0.0);
    int outside = 0;
    for (cl_uint k = 0; k < perView; ++k) {
      const cl_float4 w = got[2 * (s * perView + k)];
      const glm::dvec2 b = planeBarycentrics(v, {w.s[0], w.s[1], w.s[2]});
      if (!(b.x >= -1e-4 && b.y >= -1e-4 && b.x + b.y <= 1.0 + 1e-4)) {
        ++outside;
        continue;
      }
      const double x = std::clamp(b.x * m, 0.0, m - 1e-9), y = std::clamp(b.y * m, 0.0, m - 1e-9);
      int i = int(x), j = int(y);
      if (i + j > m - 1) j = m - 1 - i;  // rounding past the far edge
      const int upper = (i + j < m - 1) && (x - i) + (y - j) >= 1.0;
      const auto at = std::find(cells.begin(), cells.end(), std::array<int, 3>{i, j, upper});
      counts[std::size_t(at - cells.begin())] += 1.0;
    }
    EXPECT_EQ(outside, 0) << "view " << s;
    double chi2 = 0.0;
    for (std::size_t c = 0; c < counts.size(); ++c) chi2 += (counts[c] - expected[c]) * (counts[c] - expected[c]) / expected[c];
    // 35 degrees of freedom: P(chi2 > 75.6) = 1e-4
    EXPECT_LT(chi2, 75.6) << "view " << s << " (solid angle " << omega << "): counts " << ::testing::PrintToString(counts)
                          << " expected " << ::testing::PrintToString(expected);
  }
}

}  // namespace
}  // namespace wt
