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
#include <numbers>
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

// Rectangle lights (lights/light_sampling.cl, light_sample_rect and
// light_quad_pdf): a rectangle (corner c, perpendicular edges e1, e2) and a
// shading point p, in double for the host's side of the checks.
struct RectView {
  glm::dvec3 p, c, e1, e2;
  bool twoSided = false;
};

double rectArea(const RectView& v) { return glm::length(glm::cross(v.e1, v.e2)); }

/// Solid angle of the rectangle seen from p: its two triangles'.
double rectSolidAngle(const RectView& v) {
  const glm::dvec3 d = v.c + v.e1 + v.e2;
  return solidAngle(v.p, v.c, v.c + v.e1, d) + solidAngle(v.p, v.c, d, v.c + v.e2);
}

/// Where the ray p + t w (unit w) meets the rectangle's plane: (s, t) along
/// e1 and e2, and the distance; distance <= 0 when it does not.
glm::dvec3 rectPlaneHit(const RectView& v, glm::dvec3 w) {
  const glm::dvec3 n = glm::cross(v.e1, v.e2);
  const double denom = glm::dot(n, w);
  if (denom == 0.0) return glm::dvec3(-1.0);
  const double t = glm::dot(n, v.c - v.p) / denom;
  const glm::dvec3 q = v.p + t * w - v.c;
  return {glm::dot(q, v.e1) / glm::dot(v.e1, v.e1), glm::dot(q, v.e2) / glm::dot(v.e2, v.e2), t};
}

/// The views as the kernels take them: (p, two-sided), (c, 1 / area), e1, e2,
/// rounded to float (and the doubles moved to what the device sees).
std::vector<cl_float4> packRects(std::vector<RectView>& views) {
  std::vector<cl_float4> packed;
  for (RectView& v : views) {
    for (glm::dvec3* x : {&v.p, &v.c, &v.e1, &v.e2}) *x = glm::dvec3(glm::vec3(*x));
    packed.push_back({{float(v.p.x), float(v.p.y), float(v.p.z), v.twoSided ? 1.0f : 0.0f}});
    packed.push_back({{float(v.c.x), float(v.c.y), float(v.c.z), float(1.0 / rectArea(v))}});
    packed.push_back({{float(v.e1.x), float(v.e1.y), float(v.e1.z), 0.0f}});
    packed.push_back({{float(v.e2.x), float(v.e2.y), float(v.e2.z), 0.0f}});
  }
  return packed;
}

/// A rectangle with corner c, first edge e1 and second edge of length
/// `width`, perpendicular to e1 and `up`, whose front faces `up`'s side.
RectView makeRect(glm::dvec3 p, glm::dvec3 c, glm::dvec3 e1, glm::dvec3 up, double width, bool twoSided = false) {
  const glm::dvec3 e2 = width * glm::normalize(glm::cross(glm::normalize(up), e1));
  return {p, c, e1, e2, twoSided};
}

/// The views the rectangle tests share (all but one from the front), by
/// solid angle where light_quad_spherical says so: near (3 sr; area over
/// squared distance to the centre 8.3), farther (0.6 sr, 0.72), almost a
/// hemisphere from the back of a two-sided light (6.13 sr), a turned
/// rectangle (0.93 sr, 1.24); by area: far (2.1e-3 sr, 2e-3), grazing (9e-3
/// sr, 0.12), and small and distant, seen at 15 degrees (6e-4 sr).
std::vector<RectView> rectViews() {
  const glm::dvec3 c{0.0, 0.0, 0.0}, e1{1.0, 0.0, 0.0}, up{0.0, 0.0, 1.0};
  return {
      makeRect({0.4, 0.3, 0.25}, c, e1, up, 0.6),
      makeRect({0.6, 0.2, 0.9}, c, e1, up, 0.6),
      makeRect({0.7, 0.1, 17.0}, c, e1, up, 0.6),
      makeRect({2.5, 1.2, 0.15}, c, e1, up, 0.6),
      makeRect({0.5, 0.3, -0.01}, c, e1, up, 0.6, true),
      makeRect({0.6, 0.1, 0.7}, {0.2, -0.1, 0.3}, {0.6, 0.3, -0.2}, {0.3, -0.1, 0.8}, 0.45),
      makeRect({8.0, 0.2, 30.0}, c, e1, up, 0.6),
  };
}

/// chi-square quantile with `dof` degrees of freedom exceeded with
/// probability about 1e-4 (Wilson-Hilferty).
double chiSquareLimit(int dof) {
  const double k = dof, z = 3.719;
  const double h = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return k * h * h * h;
}

// The rectangle sampler: every direction meets the rectangle where the
// sampler says it does; directions are uniform in its solid angle where
// light_quad_spherical chooses it (counts on a 6 x 6 grid of the rectangle
// against each cell's solid angle, chi-square at P(fail) = 1e-4 per view),
// uniform in area below it (against the cells' areas); the sampler's pdf is
// 1 / solid angle there, d^2 / (cos area) here, and the pdf an emitter hit
// computes for the same direction (light_quad_pdf) is the same.
TEST(LightSampling, QuadSamplingIsUniformInSolidAngleAndHitsTheRectangle) {
  const int m = 6;
  const cl_uint perView = test::testSize(1 << 17, 1 << 15);
  std::vector<RectView> shapes = rectViews();
  std::vector<cl_float4> packedShapes = packRects(shapes);
  std::vector<cl_float4> views;
  std::vector<cl_float2> u;
  for (std::size_t s = 0; s < shapes.size(); ++s)
    for (cl_uint i = 0; i < perView; ++i) {
      views.insert(views.end(), packedShapes.begin() + std::ptrdiff_t(4 * s), packedShapes.begin() + std::ptrdiff_t(4 * s + 4));
      u.push_back({{rng_uniform(i, 0u, 0u, 0u, 9u), rng_uniform(i, 0u, 0u, 1u, 9u)}});
    }
  Context& ctx = test::deviceContext();
  const cl_uint n = cl_uint(u.size());
  cl::Buffer vb(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, views.size() * 16, views.data());
  cl::Buffer ub(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 8, u.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 3 * std::size_t(n) * 16);
  cl::Kernel k(test::unitTestProgram(), "test_quad_sample");
  k.setArg(0, n), k.setArg(1, vb), k.setArg(2, ub), k.setArg(3, out);
  ctx.launch("test_quad_sample", k, n);
  std::vector<cl_float4> got(3 * std::size_t(n));
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, got.size() * 16, got.data());

  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const RectView& v = shapes[s];
    const double omega = rectSolidAngle(v), area = rectArea(v);
    // light_quad_spherical
    const glm::dvec3 toCentre = v.c + 0.5 * (v.e1 + v.e2) - v.p;
    const bool spherical = area >= 0.25 * glm::dot(toCentre, toCentre) && omega >= 1e-3 && omega <= 6.2;
    // the cells' expected shares
    std::vector<double> expected(std::size_t(m * m));
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) {
        RectView cell = v;
        cell.c = v.c + double(i) / m * v.e1 + double(j) / m * v.e2;
        cell.e1 = v.e1 / double(m), cell.e2 = v.e2 / double(m);
        expected[std::size_t(i * m + j)] = perView * (spherical ? rectSolidAngle(cell) / omega : 1.0 / (m * m));
      }
    std::vector<double> counts(expected.size(), 0.0);
    int outside = 0, missed = 0, pdfOff = 0;
    double worstPdf = 0.0;
    for (cl_uint k2 = 0; k2 < perView; ++k2) {
      const std::size_t at = 3 * (s * perView + k2);
      const cl_float4 wd = got[at], st = got[at + 1], info = got[at + 2];
      if (info.s[1] == 0.0f) {
        ++missed;
        continue;
      }
      const glm::dvec3 w = glm::normalize(glm::dvec3(wd.s[0], wd.s[1], wd.s[2]));
      const glm::dvec3 hit = rectPlaneHit(v, w);
      // where the direction meets the plane is the point the sampler reports, on the rectangle
      if (!(hit.x >= -1e-4 && hit.x <= 1.0 + 1e-4 && hit.y >= -1e-4 && hit.y <= 1.0 + 1e-4) ||
          !(std::fabs(hit.x - st.s[0]) <= 1e-3 && std::fabs(hit.y - st.s[1]) <= 1e-3) ||
          !(std::fabs(hit.z - wd.s[3]) <= 1e-4 * hit.z)) {
        if (++outside <= 3)
          ADD_FAILURE() << "view " << s << ": sampled (" << st.s[0] << ", " << st.s[1] << ") at " << wd.s[3]
                        << ", its direction meets the plane at (" << hit.x << ", " << hit.y << ") at " << hit.z;
        continue;
      }
      const double cosLight = std::fabs(glm::dot(glm::normalize(glm::cross(v.e1, v.e2)), w));
      const double want = spherical ? 1.0 / omega : hit.z * hit.z / (cosLight * area);
      const double err = std::max(std::fabs(st.s[2] - want), double(std::fabs(st.s[3] - st.s[2]))) / want;
      worstPdf = std::max(worstPdf, err);
      pdfOff += !(err <= 1e-3);
      const int i = std::clamp(int(hit.x * m), 0, m - 1), j = std::clamp(int(hit.y * m), 0, m - 1);
      counts[std::size_t(i * m + j)] += 1.0;
    }
    EXPECT_EQ(missed, 0) << "view " << s;
    EXPECT_EQ(outside, 0) << "view " << s;
    EXPECT_EQ(pdfOff, 0) << "view " << s << ": worst relative pdf error " << worstPdf;
    double chi2 = 0.0;
    for (std::size_t c = 0; c < counts.size(); ++c) chi2 += (counts[c] - expected[c]) * (counts[c] - expected[c]) / expected[c];
    EXPECT_LT(chi2, chiSquareLimit(m * m - 1))
        << "view " << s << " (solid angle " << omega << (spherical ? ", spherical" : ", by area") << "): counts "
        << ::testing::PrintToString(counts) << " expected " << ::testing::PrintToString(expected);
  }
}

// The pdf an emitter hit gets (light_quad_pdf, with selection 1 / area)
// integrates to 1 over the sphere of directions, for every view (spherical
// and by area): a Monte Carlo estimate over directions uniform in a cone
// holding the rectangle (the whole sphere where none is narrower), within 4.5
// standard errors of its own sample variance.
TEST(LightSampling, QuadPdfIntegratesToOneOverTheSphere) {
  const std::size_t perView = test::testSize(1 << 17, 1 << 15);
  std::vector<RectView> shapes = rectViews();
  const std::vector<cl_float4> packedShapes = packRects(shapes);
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<cl_float4> views, dirs;
  std::vector<std::size_t> viewOf;
  std::vector<double> coneSolidAngle(shapes.size());
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const RectView& v = shapes[s];
    // the cone about the centre's direction through the farthest corner, a little wider
    const glm::dvec3 axis = glm::normalize(v.c + 0.5 * (v.e1 + v.e2) - v.p);
    double cosMax = 1.0;
    for (glm::dvec3 corner : {v.c, v.c + v.e1, v.c + v.e2, v.c + v.e1 + v.e2})
      cosMax = std::min(cosMax, glm::dot(axis, glm::normalize(corner - v.p)));
    const double theta = std::min(1.05 * std::acos(cosMax) + 1e-3, std::numbers::pi);
    const double cosTheta = std::cos(theta);
    coneSolidAngle[s] = 2.0 * std::numbers::pi * (1.0 - cosTheta);
    glm::dvec3 t = glm::normalize(glm::cross(axis, std::fabs(axis.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0)));
    const glm::dvec3 b = glm::cross(axis, t);
    for (std::size_t k = 0; k < perView; ++k) {
      const double z = 1.0 - unit(rng) * (1.0 - cosTheta), phi = 2.0 * std::numbers::pi * unit(rng);
      const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
      const glm::dvec3 w = z * axis + r * std::cos(phi) * t + r * std::sin(phi) * b;
      const glm::dvec3 hit = rectPlaneHit(v, w);
      if (!(hit.z > 0.0 && hit.x >= 0.0 && hit.x <= 1.0 && hit.y >= 0.0 && hit.y <= 1.0)) {
        viewOf.push_back(~std::size_t{0});
        continue;
      }
      views.insert(views.end(), packedShapes.begin() + std::ptrdiff_t(4 * s), packedShapes.begin() + std::ptrdiff_t(4 * s + 4));
      dirs.push_back({{float(w.x), float(w.y), float(w.z), float(hit.z)}});
      viewOf.push_back(s);
    }
  }
  Context& ctx = test::deviceContext();
  const cl_uint n = cl_uint(dirs.size());
  cl::Buffer vb(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, views.size() * 16, views.data());
  cl::Buffer db(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, dirs.size() * 16, dirs.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, std::size_t(n) * 4);
  cl::Kernel k(test::unitTestProgram(), "test_quad_pdf");
  k.setArg(0, n), k.setArg(1, vb), k.setArg(2, db), k.setArg(3, out);
  ctx.launch("test_quad_pdf", k, n);
  std::vector<float> pdf(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, std::size_t(n) * 4, pdf.data());

  std::vector<double> sum(shapes.size(), 0.0), sum2(shapes.size(), 0.0);
  std::size_t next = 0;
  for (std::size_t k2 = 0; k2 < viewOf.size(); ++k2) {
    if (viewOf[k2] == ~std::size_t{0}) continue;
    const std::size_t s = viewOf[k2];
    const double f = double(pdf[next++]) * coneSolidAngle[s];
    sum[s] += f, sum2[s] += f * f;
  }
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const double mean = sum[s] / perView;
    const double se = std::sqrt(std::max(0.0, sum2[s] / perView - mean * mean) / perView);
    EXPECT_LT(std::fabs(mean - 1.0), 4.5 * se + 1e-4)
        << "view " << s << " (solid angle " << rectSolidAngle(shapes[s]) << "): integral " << mean << ", standard error " << se;
  }
}

}  // namespace
}  // namespace wt
