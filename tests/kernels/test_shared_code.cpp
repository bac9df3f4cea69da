// Shared device code run as tiny kernels and checked against the host build
// of the same header, or against what it must satisfy.
#include "device/program.h"
#include "device_fixture.h"
#include "core/spawn.h"
#include "shared/rng.h"
#include "shared/trig.h"
#include "test_util.h"

#include <glm/glm.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <tuple>

namespace wt {
namespace {

TEST(SharedCode, RngMatchesTheHostBuildBitForBit) {
  Context& ctx = test::deviceContext();
  const cl_uint n = 4096;
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
  cl::Kernel k(test::unitTestProgram(), "test_rng");
  for (auto [sample, bounce, dim, seed] : {std::array<cl_uint, 4>{0, 0, 0, 0}, {17, 3, 2, 99}, {1u << 20, 7, 3, 12345}}) {
    k.setArg(0, n), k.setArg(1, sample), k.setArg(2, bounce), k.setArg(3, dim), k.setArg(4, seed), k.setArg(5, out);
    ctx.launch("test_rng", k, n);
    std::vector<float> got(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float), got.data());
    double sum = 0.0;
    for (cl_uint i = 0; i < n; ++i) {
      ASSERT_EQ(got[i], rng_uniform(i, sample, bounce, dim, seed)) << "pixel " << i;
      ASSERT_GE(got[i], 0.0f);
      ASSERT_LT(got[i], 1.0f);
      sum += got[i];
    }
    // mean of n uniforms: standard error 1/sqrt(12 n); allow 5 of them
    EXPECT_NEAR(sum / n, 0.5, 5.0 / std::sqrt(12.0 * n));
  }
}

// Both forms: about a world normal, and about the local frame's +z (the
// BSDF's, which builds no frame).
TEST(SharedCode, LambertSamplesAreCosineDistributed) {
  Context& ctx = test::deviceContext();
  const cl_uint n = test::testSize(1 << 16, 1 << 12);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<cl_float2> us(n);
  for (auto& v : us) v = {{u(rng), u(rng)}};
  for (bool local : {false, true}) {
    SCOPED_TRACE(local ? "lambert_sample_local" : "lambert_sample");
    glm::vec3 normal = local ? glm::vec3(0.0f, 0.0f, 1.0f) : glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
    cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float2), us.data());
    cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
    cl::Kernel k(test::unitTestProgram(), "test_lambert");
    k.setArg(0, n), k.setArg(1, cl_float4{{normal.x, normal.y, normal.z, local ? 1.0f : 0.0f}}), k.setArg(2, in);
    k.setArg(3, out);
    ctx.launch("test_lambert", k, n);
    std::vector<cl_float4> dirs(n);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float4), dirs.data());
    // Chi-square over 8 x 8 bins of (cos(theta)^2, azimuth), both uniform
    // under a cosine distribution (pdf of c = cos(theta) is 2c, so c^2 ~
    // U(0,1)), the azimuth about any frame of the normal.
    const int kBins = 8;
    const glm::vec3 t = glm::normalize(glm::cross(normal, glm::vec3(1.0f, 0.0f, 0.0f))), b = glm::cross(normal, t);
    std::vector<double> counts(kBins * kBins, 0.0);
    for (const cl_float4& d : dirs) {
      glm::vec3 v(d.s[0], d.s[1], d.s[2]);
      ASSERT_NEAR(glm::length(v), 1.0f, 1e-5f);
      float c = glm::dot(v, normal);
      ASSERT_GE(c, 0.0f);
      const double phi = std::atan2(double(glm::dot(v, b)), double(glm::dot(v, t))) + M_PI;
      const int azimuth = std::min(kBins - 1, int(phi / (2.0 * M_PI) * kBins));
      counts[std::min(kBins - 1, int(c * c * kBins)) * kBins + azimuth] += 1.0;
    }
    double chi2 = 0.0, expected = double(n) / (kBins * kBins);
    for (double c : counts) chi2 += (c - expected) * (c - expected) / expected;
    // 63 degrees of freedom: P(chi2 > 103.4) = 0.001
    EXPECT_LT(chi2, 103.4) << "histogram of (cos^2, azimuth): " << ::testing::PrintToString(counts);
  }
}

// The one-ulp steps that push a spawned origin off a surface are
// std::nextafter towards +-infinity, bit for bit, zeros and denormals
// included (a coordinate that lands exactly on 0 must step to the smallest
// denormal, never to a NaN).
TEST(SharedCode, NextFloatStepsAreNextafterAtZerosDenormalsAndLimits) {
  std::vector<float> values = {0.0f, -0.0f, std::numeric_limits<float>::denorm_min(),
                               -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min(),
                               -std::numeric_limits<float>::min(), 1.0f, -1.0f, 3.0e-39f, -3.0e-39f,
                               std::numeric_limits<float>::max(), -std::numeric_limits<float>::max()};
  std::mt19937 rng(4);
  for (int i = 0; i < 2000; ++i) {
    std::uint32_t bits = rng();
    float v;
    std::memcpy(&v, &bits, sizeof v);
    if (std::isfinite(v)) values.push_back(v);
  }
  auto same = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const float inf = std::numeric_limits<float>::infinity();
  for (float v : values) {
    EXPECT_TRUE(same(spawn_next_up(v), std::nextafter(v, inf))) << v << " -> " << spawn_next_up(v);
    EXPECT_TRUE(same(spawn_next_down(v), std::nextafter(v, -inf))) << v << " -> " << spawn_next_down(v);
  }
  EXPECT_EQ(spawn_next_up(inf), inf);
  EXPECT_EQ(spawn_next_down(-inf), -inf);
}

// Random triangles of every size from 1e-6 to 1e4, up to 1e7 from the world
// origin, with points anywhere on them (edges and corners included): the
// spawned origin must lie strictly on the intended side of the triangle's
// exact plane (decided in double), within a few error bounds of the point,
// and the device must compute exactly what the host build does.
TEST(SharedCode, RayOffsetLeavesTheSurfaceOnTheNormalSideAtEveryScale) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), u01(0.0f, 1.0f);
  std::vector<cl_float4> verts;
  std::vector<cl_float2> bary;
  for (float size : {1e-6f, 1e-3f, 1.0f, 1e4f})
    for (float distance : {0.0f, 1.0f, 1e3f, 1e5f, 1e7f})
      for (int i = 0; i < 400; ++i) {
        glm::vec3 center = distance * glm::vec3(u(rng), u(rng), u(rng));
        for (int k = 0; k < 3; ++k) {
          glm::vec3 v = center + size * glm::vec3(u(rng), u(rng), u(rng));
          verts.push_back({{v.x, v.y, v.z, 0}});
        }
        float b1 = u01(rng), b2 = u01(rng);
        if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
        if (i % 8 == 1) b1 = 0.0f;          // on an edge
        if (i % 8 == 2) b1 = 0.0f, b2 = 0;  // on a corner
        if (i % 8 == 3) b2 = 1.0f - b1;     // on the third edge (up to rounding)
        bary.push_back({{b1, b2}});
      }
  const cl_uint n = cl_uint(bary.size());
  cl::Buffer bv(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, verts.size() * 16, verts.data());
  cl::Buffer bb(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 8, bary.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 2 * n * 16);
  cl::Kernel k(test::unitTestProgram(), "test_offset");
  k.setArg(0, n), k.setArg(1, bv), k.setArg(2, bb), k.setArg(3, out);
  ctx.launch("test_offset", k, n);
  std::vector<cl_float4> got(2 * n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, 2 * n * 16, got.data());
  auto vec = [](const cl_float4& v) { return glm::vec3(v.s[0], v.s[1], v.s[2]); };
  int failures = 0;
  for (cl_uint i = 0; i < n && failures < 10; ++i) {
    glm::vec3 p0 = vec(verts[3 * i]), p1 = vec(verts[3 * i + 1]), p2 = vec(verts[3 * i + 2]);
    glm::dvec3 normal = glm::cross(glm::dvec3(p1) - glm::dvec3(p0), glm::dvec3(p2) - glm::dvec3(p0));
    if (!(glm::length(normal) > 0.0)) continue;
    normal = glm::normalize(normal);
    glm::vec3 error;
    glm::vec3 p = trianglePoint(p0, p1, p2, bary[i].s[0], bary[i].s[1], &error);
    glm::vec3 nf = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    for (int side = 0; side < 2; ++side) {
      glm::vec3 device = vec(got[2 * i + side]);
      glm::vec3 host = offsetRayOrigin(p, error, side == 0 ? nf : -nf);
      double signedDistance = glm::dot(glm::dvec3(device) - glm::dvec3(p0), normal) * (side == 0 ? 1.0 : -1.0);
      double bound = spawn_offset_distance(nf.x, nf.y, nf.z, error.x, error.y, error.z);
      double ulp = std::ldexp(1.0, -23) * std::max({std::fabs(p.x), std::fabs(p.y), std::fabs(p.z)});
      bool ok = device == host && signedDistance > 0.0 &&
                glm::length(glm::dvec3(device) - glm::dvec3(p)) <= 2.0 * bound + 4.0 * ulp;
      if (!ok && ++failures <= 10)
        ADD_FAILURE() << "triangle " << i << " side " << side << ": signed distance " << signedDistance
                      << ", moved " << glm::length(glm::dvec3(device) - glm::dvec3(p)) << " (bound " << bound
                      << "), device " << device.x << "," << device.y << "," << device.z << " host " << host.x
                      << "," << host.y << "," << host.z;
    }
  }
  EXPECT_EQ(failures, 0);
}

// wt_atan2 (kernels/common.h), the kernels' atan2 for finite arguments:
// against the double-precision angle, within 2 ulp of the result plus
// 2e-7 rad, over every octant, magnitudes from 1e-30 to 1e30, the axes and
// the signed zeros (where it must give the library's exact values).
TEST(SharedCode, Atan2IsAccurateOnEveryOctantAndAtTheAxes) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), logScale(-30.0, 30.0);
  std::vector<cl_float2> yx;
  for (int i = 0; i < 50000; ++i) {
    const double a = angle(rng), r = std::pow(10.0, logScale(rng) * (i % 4 == 0 ? 1.0 : 0.1));
    yx.push_back({{float(r * std::sin(a)), float(r * std::cos(a))}});
  }
  // the octant boundaries and the reduction's thresholds, approached from both sides
  for (double a : {0.0, M_PI / 8, M_PI / 4, 3 * M_PI / 8, M_PI / 2, 5 * M_PI / 8, 3 * M_PI / 4, 7 * M_PI / 8, M_PI})
    for (double sign : {1.0, -1.0})
      for (int k = -50; k <= 50; ++k) {
        const double b = sign * (a + k * 1e-7);
        yx.push_back({{float(std::sin(b)), float(std::cos(b))}});
      }
  const float zeros[] = {0.0f, -0.0f};
  for (float y : zeros)
    for (float x : {0.0f, -0.0f, 1.0f, -1.0f, 1e-30f, -1e-30f}) yx.push_back({{y, x}});
  for (float y : {1.0f, -1.0f, 3e38f, -1e-38f})
    for (float x : zeros) yx.push_back({{y, x}});
  const cl_uint n = cl_uint(yx.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float2), yx.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(float));
  cl::Kernel k(test::unitTestProgram(), "test_atan2");
  k.setArg(0, n), k.setArg(1, in), k.setArg(2, out);
  ctx.launch("test_atan2", k, n);
  std::vector<float> got(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(float), got.data());
  int failures = 0;
  double worst = 0.0;
  for (cl_uint i = 0; i < n; ++i) {
    const float y = yx[i].s[0], x = yx[i].s[1];
    const double want = std::atan2(double(y), double(x));
    const double err = std::fabs(double(got[i]) - want);
    const double ulp = std::ldexp(1.0, std::ilogb(std::max(std::fabs(want), 1e-30)) - 23);
    worst = std::max(worst, err / (ulp + 2e-7));
    bool ok = err <= 2.0 * ulp + 2e-7;
    if (y == 0.0f) ok = got[i] == std::atan2(y, x) && std::signbit(got[i]) == std::signbit(std::atan2(y, x));
    if (!ok && ++failures <= 10)
      ADD_FAILURE() << "atan2(" << y << ", " << x << ") = " << got[i] << ", want " << want;
  }
  EXPECT_EQ(failures, 0) << "worst error " << worst << " x (2 ulp + 2e-7)";
}

// wt_sincospi (kernels/shared/trig.h), the samplers' sin and cos of pi x, on
// the device and in the host build: within 2 ulp of 1 (2.4e-7) of the
// double-precision values over the range the samplers use ([0, 2]) and
// beyond it, both signs; exact at the quarter turns, where a rounded
// reduction would leave a residue.
TEST(SharedCode, SinCosPiIsAccurateAndExactAtQuarterTurns) {
  Context& ctx = test::deviceContext();
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> near(-2.0f, 2.0f), far(-3000.0f, 3000.0f);
  std::vector<float> xs;
  for (int i = 0; i < 50000; ++i) xs.push_back(i % 8 == 0 ? far(rng) : near(rng));
  // the reduction's rounding points (k / 4, where the quarter turn changes) from both sides
  for (int k = -16; k <= 16; ++k) {
    float up = 0.25f * float(k), down = up;
    xs.push_back(up);
    for (int step = 0; step < 3; ++step) {
      xs.push_back(up = std::nextafter(up, 1e9f));
      xs.push_back(down = std::nextafter(down, -1e9f));
    }
  }
  for (float x : {1e-30f, -1e-30f, 0.0f, -0.0f, 4194303.5f, -4194303.25f}) xs.push_back(x);
  const cl_uint n = cl_uint(xs.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(float), xs.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float2));
  cl::Kernel k(test::unitTestProgram(), "test_sincospi");
  k.setArg(0, n), k.setArg(1, in), k.setArg(2, out);
  ctx.launch("test_sincospi", k, n);
  std::vector<cl_float2> device(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float2), device.data());
  const double tolerance = 2.0 * std::ldexp(1.0, -23);
  int failures = 0;
  double worst = 0.0;
  for (cl_uint i = 0; i < n; ++i) {
    const float x = xs[i];
    // pi x reduced in double: x is exact, so x mod 2 is too
    const double turns = std::fmod(double(x), 2.0);
    const double want_s = std::sin(M_PI * turns), want_c = std::cos(M_PI * turns);
    float host_c;
    const float host_s = wt_sincospi(x, &host_c);
    for (auto [s, c, where] : {std::tuple{device[i].s[0], device[i].s[1], "device"}, std::tuple{host_s, host_c, "host"}}) {
      const double err = std::max(std::fabs(s - want_s), std::fabs(c - want_c));
      worst = std::max(worst, err);
      bool ok = err <= tolerance;
      // quarter turns: sin(pi k) = +-0 and cos = +-1 exactly, and the other way round
      if (std::rint(2.0 * x) == 2.0 * x) ok = ok && (std::fabs(s) == 0.0f || std::fabs(s) == 1.0f) && std::fabs(s) + std::fabs(c) == 1.0f;
      if (!ok && ++failures <= 10)
        ADD_FAILURE() << where << " sincospi(" << x << ") = (" << s << ", " << c << "), want (" << want_s << ", " << want_c << ")";
    }
  }
  EXPECT_EQ(failures, 0) << "worst error " << worst;
}

// The four-lane leaf test gives what testing the triangles one by one gives,
// bit for bit: every range of lanes of a block (a leaf may start and end
// inside one), with and without a skipped triangle, on rays aimed at shared
// edges and vertices (exactly-zero edge functions) and at random points,
// some stopping short. The block is the second of two (WT_TRIANGLE_BLOCK
// layout); its four triangles: two neighbours of a fan in z = 1, the second
// of them again nearer (z = 0.6, so the nearer must win), and an exact copy
// of the first (a tie, which the lower index must win).
TEST(SharedCode, FourLaneTriangleTestMatchesOneByOne) {
  Context& ctx = test::deviceContext();
  // a fan of four triangles around (0, 0, 0) in the plane z = 1, and a fifth off to the side
  const glm::vec3 c(0.0f, 0.0f, 1.0f), r[5] = {{1, 0, 1}, {0, 1, 1}, {-1, 0, 1}, {0, -1, 1}, {1, 0, 1}};
  const glm::vec3 nearer(0.0f, 0.0f, -0.4f);
  const glm::vec3 tris[4][3] = {{c, r[0], r[1]}, {c, r[1], r[2]}, {c + nearer, r[1] + nearer, r[2] + nearer}, {c, r[0], r[1]}};
  // block 0 far off (never tested), block 1 the four triangles: row 3k + a of
  // a block holds axis a of corner k for its four lanes
  constexpr int kBlockFloats = 4 * WT_TRIANGLE_BLOCK_ROWS;
  std::vector<float> verts(2 * kBlockFloats, 1e6f);
  for (int lane = 0; lane < 4; ++lane)
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) verts[kBlockFloats + 12 * k + 4 * a + lane] = tris[lane][k][a];
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.2f, 1.2f);
  std::vector<cl_float4> o, d;
  auto aim = [&](glm::vec3 from, glm::vec3 at, float tmax = 1e30f) {
    glm::vec3 dir = glm::normalize(at - from);
    o.push_back({{from.x, from.y, from.z, 0.0f}});
    d.push_back({{dir.x, dir.y, dir.z, tmax}});
  };
  for (glm::vec3 target : {c, r[0], r[1], r[2], r[3], 0.5f * (c + r[0]), 0.5f * (c + r[1]), 0.5f * (r[0] + r[1])})
    for (glm::vec3 from : {glm::vec3(0.0f, 0.0f, -2.0f), glm::vec3(0.3f, -0.7f, 3.0f), glm::vec3(-2.0f, 1.0f, 0.5f)})
      aim(from, target);
  for (int i = 0; i < 2000; ++i) aim(glm::vec3(u(rng), u(rng), -1.5f), glm::vec3(u(rng), u(rng), 1.0f), i % 7 == 0 ? 1.0f : 1e30f);
  const cl_uint n = cl_uint(o.size());
  cl::Buffer bo(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 16, o.data());
  cl::Buffer bd(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * 16, d.data());
  cl::Buffer bv(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, verts.size() * sizeof(float), verts.data());
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, 2 * n * 16);
  cl::Kernel k(test::unitTestProgram(), "test_intersect4");
  int hits = 0;
  for (cl_uint lo = 0; lo < 4; ++lo)
    for (cl_uint hi = lo + 1; hi <= 4; ++hi)
    for (cl_uint skip : {0xffffffffu, 4u, 6u}) {
      k.setArg(0, n), k.setArg(1, bo), k.setArg(2, bd), k.setArg(3, bv), k.setArg(4, cl_uint(1)), k.setArg(5, lo);
      k.setArg(6, hi), k.setArg(7, skip), k.setArg(8, out);
      ctx.launch("test_intersect4", k, n);
      std::vector<cl_float4> got(2 * n);
      ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, 2 * n * 16, got.data());
      for (cl_uint i = 0; i < n; ++i) {
        const cl_float4 &four = got[2 * i], &one = got[2 * i + 1];
        for (int c4 = 0; c4 < 4; ++c4)
          ASSERT_EQ(std::memcmp(&four.s[c4], &one.s[c4], 4), 0)
              << "ray " << i << ", lanes " << lo << "-" << hi << ", skip " << skip << ", component " << c4 << ": " << four.s[c4] << " vs " << one.s[c4] << " (" << four.s[0] << " " << four.s[1] << " " << four.s[2] << " | " << one.s[0] << " " << one.s[1] << " " << one.s[2] << ")";
        std::uint32_t prim;
        std::memcpy(&prim, &four.s[3], 4);
        hits += prim != 0xffffffffu;
      }
    }
  EXPECT_GT(hits, 1000);  // the comparison covered hits, not only misses
}

}  // namespace
}  // namespace wt
