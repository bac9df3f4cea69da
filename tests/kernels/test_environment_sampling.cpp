// Environment lighting on the device (kernels/lights/environment.cl, run
// through kernels/env_tests.cl): the sampler reproduces its pdf (chi-square),
// the pdf integrates to one and follows luminance x sin(theta), sample, eval
// and pdf agree, the lat-long orientation is OpenEXR's, and importance
// sampling estimates irradiance as a brute-force sum over texels does.
#include "device/program.h"
#include "device_fixture.h"
#include "render/light_list.h"
#include "scene/environment.h"
#include "test_util.h"

#include <ImfEnvmap.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>

namespace wt {
namespace {

constexpr double kPi = std::numbers::pi;

cl::Program envProgram() { return test::testProgram("env_tests.cl"); }

// ---------------------------------------------------------------------------
// the convention, written independently of the kernels (double precision)

/// Rotation about +Y by `angle` radians, counter-clockwise seen from above (+Z towards +X).
glm::dvec3 rotateY(glm::dvec3 d, double angle) {
  return {d.x * std::cos(angle) + d.z * std::sin(angle), d.y, -d.x * std::sin(angle) + d.z * std::cos(angle)};
}

/// Map (u, v) of a world direction: u = 0.5 - atan2(x, z) / 2pi, v = theta / pi, in the map's frame.
glm::dvec2 mapUv(glm::dvec3 world, double rotation) {
  glm::dvec3 m = rotateY(world, -rotation);
  double u = 0.5 - std::atan2(m.x, m.z) / (2.0 * kPi);
  return {u - std::floor(u), std::atan2(std::hypot(m.x, m.z), m.y) / kPi};
}

/// World direction of map coordinates (u, v).
glm::dvec3 worldDirection(double u, double v, double rotation) {
  double theta = kPi * v, longitude = kPi * (1.0 - 2.0 * u);
  glm::dvec3 m(std::sin(theta) * std::sin(longitude), std::cos(theta), std::sin(theta) * std::cos(longitude));
  return rotateY(m, rotation);
}

double luminance709(const WtVec4& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// ---------------------------------------------------------------------------
// device helpers

struct DeviceEnv {
  explicit DeviceEnv(const Environment& env) : header(env.header) {
    cl::Context& c = test::deviceContext().context();
    EnvironmentUpload up = environmentUpload(env);
    auto upload = [&](const void* data, std::size_t bytes) {
      return cl::Buffer(c, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes, const_cast<void*>(data));
    };
    texels = upload(up.texels.data(), up.texels.size_bytes());
    marginal = upload(up.marginalCdf.data(), up.marginalCdf.size_bytes());
    conditional = upload(up.conditionalCdf.data(), up.conditionalCdf.size_bytes());
  }
  WtEnvironment header;
  cl::Buffer texels, marginal, conditional;
};

cl_float4 toCl(glm::dvec3 d) { return {{float(d.x), float(d.y), float(d.z), 0.0f}}; }
glm::dvec3 xyz(const cl_float4& v) { return {v.s[0], v.s[1], v.s[2]}; }

/// (radiance, pdf) of each direction.
std::vector<cl_float4> evalPdf(const DeviceEnv& env, const std::vector<cl_float4>& dirs) {
  Context& ctx = test::deviceContext();
  const cl_uint n = cl_uint(dirs.size());
  cl::Buffer in(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float4),
                const_cast<cl_float4*>(dirs.data()));
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(envProgram(), "test_env_eval_pdf");
  k.setArg(0, n), k.setArg(1, env.header), k.setArg(2, env.texels), k.setArg(3, env.marginal);
  k.setArg(4, env.conditional), k.setArg(5, in), k.setArg(6, out);
  ctx.launch("test_env_eval_pdf", k, n);
  std::vector<cl_float4> got(n);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, n * sizeof(cl_float4), got.data());
  return got;
}

struct Samples {
  std::vector<cl_float4> directionPdf;  ///< xyz direction, w pdf
  std::vector<cl_float4> radiance;      ///< xyz
  std::vector<cl_float4> evalPdf;       ///< environment_eval, environment_pdf of the direction
};

Samples sampleDevice(const DeviceEnv& env, cl_uint n, cl_uint seed) {
  Context& ctx = test::deviceContext();
  cl::Buffer a(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Buffer b(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Buffer c(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(envProgram(), "test_env_sample");
  k.setArg(0, n), k.setArg(1, seed), k.setArg(2, env.header), k.setArg(3, env.texels);
  k.setArg(4, env.marginal), k.setArg(5, env.conditional), k.setArg(6, a), k.setArg(7, b), k.setArg(8, c);
  ctx.launch("test_env_sample", k, n);
  Samples s;
  s.directionPdf.resize(n), s.radiance.resize(n), s.evalPdf.resize(n);
  ctx.queue().enqueueReadBuffer(a, CL_TRUE, 0, n * sizeof(cl_float4), s.directionPdf.data());
  ctx.queue().enqueueReadBuffer(b, CL_TRUE, 0, n * sizeof(cl_float4), s.radiance.data());
  ctx.queue().enqueueReadBuffer(c, CL_TRUE, 0, n * sizeof(cl_float4), s.evalPdf.data());
  return s;
}

/// Every sample: unit direction, finite pdf > 0, environment_pdf of the
/// direction within 1e-4 of it, environment_eval equal to the radiance.
void expectSamplesConsistent(const Samples& s, const std::string& what) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < s.directionPdf.size(); ++i) {
    const cl_float4& d = s.directionPdf[i];
    float pdf = d.s[3], pdfAgain = s.evalPdf[i].s[3];
    bool ok = std::abs(glm::length(xyz(d)) - 1.0) < 1e-5 && std::isfinite(pdf) && pdf > 0.0f &&
              std::abs(pdfAgain - pdf) <= 1e-4f * pdf;
    for (int c = 0; c < 3; ++c) ok = ok && s.radiance[i].s[c] == s.evalPdf[i].s[c] && std::isfinite(s.radiance[i].s[c]);
    if (!ok && ++bad <= 5)
      ADD_FAILURE() << what << " sample " << i << ": direction (" << d.s[0] << ", " << d.s[1] << ", " << d.s[2]
                    << ") pdf " << pdf << ", environment_pdf " << pdfAgain << "; radiance (" << s.radiance[i].s[0]
                    << ", " << s.radiance[i].s[1] << ", " << s.radiance[i].s[2] << "), environment_eval ("
                    << s.evalPdf[i].s[0] << ", " << s.evalPdf[i].s[1] << ", " << s.evalPdf[i].s[2] << ")";
  }
  EXPECT_EQ(bad, 0u) << what << ": samples where sample, eval and pdf disagree";
}

// ---------------------------------------------------------------------------
// chi-square

/// Upper tail of the chi-square distribution (Wilson-Hilferty approximation).
double chiSquarePValue(double chi2, int dof) {
  double k = dof, s = 2.0 / (9.0 * k);
  double z = (std::cbrt(chi2 / k) - (1.0 - s)) / std::sqrt(s);
  return 0.5 * std::erfc(z / std::sqrt(2.0));
}

/// Observed against expected counts on a columns x rows grid of bins. Bins
/// with expected 0 must stay empty; bins expecting fewer than 5 are pooled.
/// On failure the histograms go to scratch/env/<name>.csv and a map of
/// residuals into the message.
void expectHistogramsMatch(const std::string& name, int columns, int rows, const std::vector<double>& observed,
                           const std::vector<double>& expected) {
  double chi2 = 0.0, pooledObserved = 0.0, pooledExpected = 0.0;
  int dof = -1;
  std::size_t impossible = 0;
  for (std::size_t b = 0; b < observed.size(); ++b) {
    if (expected[b] <= 0.0) {
      impossible += observed[b] > 0.0;
      continue;
    }
    if (expected[b] < 5.0) {
      pooledObserved += observed[b], pooledExpected += expected[b];
      continue;
    }
    chi2 += (observed[b] - expected[b]) * (observed[b] - expected[b]) / expected[b];
    ++dof;
  }
  if (pooledExpected >= 5.0) {
    chi2 += (pooledObserved - pooledExpected) * (pooledObserved - pooledExpected) / pooledExpected;
    ++dof;
  }
  ASSERT_GT(dof, 0);
  const double p = chiSquarePValue(chi2, dof);
  if (p > 1e-4 && impossible == 0) return;

  std::filesystem::path csv = test::scratchDir("env") / (name + ".csv");
  std::ofstream out(csv);
  out << "column,row,observed,expected\n";
  std::ostringstream residuals;
  residuals << "residuals (observed - expected) / sqrt(expected), row 0 = +Y; '.' |r|<3, '+'/'-' 3..6, '#'/'=' beyond, "
               "'!' sample in a zero-pdf bin:\n";
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      std::size_t b = std::size_t(r) * columns + c;
      out << c << "," << r << "," << observed[b] << "," << expected[b] << "\n";
      double z = expected[b] > 0.0 ? (observed[b] - expected[b]) / std::sqrt(expected[b]) : 0.0;
      char ch = expected[b] <= 0.0 ? (observed[b] > 0.0 ? '!' : ' ')
                : std::abs(z) < 3.0 ? '.' : z > 6.0 ? '#' : z > 0.0 ? '+' : z < -6.0 ? '=' : '-';
      if (columns <= 128) residuals << ch;
    }
    if (columns <= 128) residuals << "\n";
  }
  ADD_FAILURE() << name << ": chi2 = " << chi2 << " with " << dof << " degrees of freedom, p = " << p << "; "
                << impossible << " bins with zero expectation received samples. Histograms: " << csv.string()
                << "\n" << residuals.str();
}

/// Chi-square of the sampler against the device pdf integrated over bins of
/// the map's (u, v) square. Bin and quadrature cell edges nest with the
/// texel edges, where pdf_solid_angle x 2 pi^2 sin(theta) is constant, so the
/// integral is exact up to float rounding.
void chiSquareTest(const std::string& name, const Environment& env, int binsU, int binsV, int pointsPerBin,
                   cl_uint sampleCount, cl_uint seed) {
  const double rotation = env.header.rotation;
  DeviceEnv dev(env);
  std::vector<cl_float4> dirs;
  dirs.reserve(std::size_t(binsU) * binsV * pointsPerBin * pointsPerBin);
  const double du = 1.0 / (binsU * pointsPerBin), dv = 1.0 / (binsV * pointsPerBin);
  for (int bv = 0; bv < binsV; ++bv)
    for (int bu = 0; bu < binsU; ++bu)
      for (int pv = 0; pv < pointsPerBin; ++pv)
        for (int pu = 0; pu < pointsPerBin; ++pu)
          dirs.push_back(toCl(worldDirection((bu * pointsPerBin + pu + 0.5) * du, (bv * pointsPerBin + pv + 0.5) * dv, rotation)));
  std::vector<cl_float4> pdfs = evalPdf(dev, dirs);
  std::vector<double> expected(std::size_t(binsU) * binsV, 0.0);
  double total = 0.0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    std::size_t bin = k / (pointsPerBin * pointsPerBin);
    int pv = int(k / pointsPerBin) % pointsPerBin;
    double v = ((bin / binsU) * pointsPerBin + pv + 0.5) * dv;
    double mass = pdfs[k].s[3] * 2.0 * kPi * kPi * std::sin(kPi * v) * du * dv;
    expected[bin] += mass;
    total += mass;
  }
  EXPECT_NEAR(total, 1.0, 1e-4) << name << ": pdf integrated over the (u, v) square";
  for (double& e : expected) e *= sampleCount;

  Samples s = sampleDevice(dev, sampleCount, seed);
  expectSamplesConsistent(s, name);
  std::vector<double> observed(expected.size(), 0.0);
  for (const cl_float4& d : s.directionPdf) {
    glm::dvec2 uv = mapUv(xyz(d), rotation);
    int bu = std::min(binsU - 1, int(uv.x * binsU)), bv = std::min(binsV - 1, int(uv.y * binsV));
    observed[std::size_t(bv) * binsU + bu] += 1.0;
  }
  expectHistogramsMatch(name, binsU, binsV, observed, expected);
}

// ---------------------------------------------------------------------------
// maps

/// 16 x 8: a gradient, one very bright texel (~80% of the power), a black
/// row, two black texels and a blue-only texel.
Environment syntheticMap(float rotationDegrees, float intensity = 1.0f) {
  const int w = 16, h = 8;
  std::vector<glm::vec3> rgb(w * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) rgb[j * w + i] = {0.1f + 0.05f * i, 0.05f + 0.1f * j, 0.3f + 0.02f * (i + j)};
  for (int i = 0; i < w; ++i) rgb[5 * w + i] = glm::vec3(0.0f);
  rgb[2 * w + 3] = rgb[2 * w + 4] = glm::vec3(0.0f);
  rgb[1 * w + 11] = {400.0f, 300.0f, 200.0f};
  rgb[6 * w + 2] = {0.0f, 0.0f, 5.0f};
  return makeEnvironmentMap(w, h, rgb, intensity, rotationDegrees, "synthetic");
}

// ---------------------------------------------------------------------------
// sampling against the pdf

TEST(EnvironmentSampling, ChiSquareOnSyntheticMap) {
  // bins (24 x 12) straddle the 16 x 8 texels; quadrature cells (1/96, 1/48) nest in both
  chiSquareTest("synthetic", syntheticMap(0.0f), 24, 12, 4, 1 << 21, 1);
}

TEST(EnvironmentSampling, ChiSquareOnRotatedSyntheticMap) {
  // bins expecting fewer than 5 samples are pooled, so the small size keeps the test valid
  chiSquareTest("synthetic_rotated", syntheticMap(37.0f, 2.5f), 24, 12, 4, test::testSize(1 << 21, 1 << 14), 2);
}

TEST(EnvironmentSamplingAssets, ChiSquareOnRealMap) {
  WT_REQUIRE_ASSET(file, "envmaps/royal_esplanade_1k.hdr");
  Environment env = loadEnvironmentMap(file);
  ASSERT_EQ(env.header.width, 1024u);
  // 64 x 32 bins of 16 x 16 texels, one quadrature point per texel
  chiSquareTest("royal_esplanade", env, 64, 32, 16, 1 << 21, 3);
}

/// Per texel, the pdf integrated over it is luminance x sin(theta of the row
/// centre) over the sum of the same: the distribution the brief asks for.
void expectPdfFollowsLuminance(const Environment& env, double absTolerance) {
  const int w = int(env.header.width), h = int(env.header.height);
  const double rotation = env.header.rotation;
  std::vector<cl_float4> dirs;
  std::vector<double> weight;
  double sum = 0.0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      dirs.push_back(toCl(worldDirection((i + 0.5) / w, (j + 0.5) / h, rotation)));
      weight.push_back(luminance709(env.texels[std::size_t(j) * w + i]) * std::sin(kPi * (j + 0.5) / h));
      sum += weight.back();
    }
  DeviceEnv dev(env);
  std::vector<cl_float4> got = evalPdf(dev, dirs);
  int bad = 0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    double v = (double(k / w) + 0.5) / h;
    double probability = got[k].s[3] * 2.0 * kPi * kPi * std::sin(kPi * v) / (double(w) * h);
    double want = weight[k] / sum;
    if (std::abs(probability - want) > absTolerance + 1e-4 * want && ++bad <= 5)
      ADD_FAILURE() << env.sourceName << " texel (" << k % w << ", " << k / w << "): probability " << probability
                    << ", luminance x sin(theta) says " << want;
  }
  EXPECT_EQ(bad, 0);
}

TEST(EnvironmentSampling, PdfFollowsLuminanceTimesSinTheta) {
  expectPdfFollowsLuminance(syntheticMap(0.0f), 1e-7);
  expectPdfFollowsLuminance(syntheticMap(-123.0f, 0.5f), 1e-7);
}

TEST(EnvironmentSamplingAssets, PdfFollowsLuminanceOnRealMap) {
  WT_REQUIRE_ASSET(file, "envmaps/royal_esplanade_1k.hdr");
  // float cdf differences near 1 carry absolute errors of ~1e-7
  expectPdfFollowsLuminance(loadEnvironmentMap(file, 1.0f, 90.0f), 3e-7);
}

/// Integral of the pdf over the sphere by the midpoint rule on a grid whose
/// pole is +X, so no cell edge follows the map's rows or columns.
double pdfIntegralAroundX(const Environment& env, int n) {
  std::vector<cl_float4> dirs;
  dirs.reserve(std::size_t(2 * n) * n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < 2 * n; ++b) {
      double theta = kPi * (a + 0.5) / n, phi = kPi * (b + 0.5) / n;
      dirs.push_back(toCl({std::cos(theta), std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi)}));
    }
  std::vector<cl_float4> got = evalPdf(DeviceEnv(env), dirs);
  double sum = 0.0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    double theta = kPi * (double(k / (2 * n)) + 0.5) / n;
    sum += got[k].s[3] * std::sin(theta) * (kPi / n) * (kPi / n);
  }
  return sum;
}

TEST(EnvironmentSampling, PdfIntegratesToOne) {
  EXPECT_NEAR(pdfIntegralAroundX(syntheticMap(0.0f), 1024), 1.0, 2e-3);
  EXPECT_NEAR(pdfIntegralAroundX(syntheticMap(37.0f), 1024), 1.0, 2e-3);
  EXPECT_NEAR(pdfIntegralAroundX(constantEnvironment({1, 2, 3}), 64), 1.0, 1e-3);
  // all black: uniform sphere sampling, still a density
  Environment black = makeEnvironmentMap(8, 4, std::vector<glm::vec3>(32, glm::vec3(0.0f)), 1.0f, 0.0f, "black");
  EXPECT_NEAR(pdfIntegralAroundX(black, 64), 1.0, 1e-3);
}

TEST(EnvironmentSamplingAssets, PdfIntegratesToOneOnRealMap) {
  WT_REQUIRE_ASSET(file, "envmaps/royal_esplanade_1k.hdr");
  EXPECT_NEAR(pdfIntegralAroundX(loadEnvironmentMap(file), 1024), 1.0, 5e-3);
}

TEST(EnvironmentSampling, ConstantAndBlackSampleTheUniformSphere) {
  const cl_uint n = 1 << 16;
  Environment black = makeEnvironmentMap(8, 4, std::vector<glm::vec3>(32, glm::vec3(0.0f)), 1.0f, 0.0f, "black");
  ASSERT_EQ(black.header.mode, cl_uint(WT_ENV_MAP_UNIFORM));
  for (const Environment& env : {constantEnvironment({0.5f, 1.0f, 2.0f}), black}) {
    Samples s = sampleDevice(DeviceEnv(env), n, 4);
    expectSamplesConsistent(s, env.sourceName);
    // y of a uniform sphere direction is uniform in [-1, 1]: 16 bins
    std::vector<double> observed(16, 0.0), expected(16, double(n) / 16);
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_FLOAT_EQ(s.directionPdf[i].s[3], float(1.0 / (4.0 * kPi)));
      glm::dvec3 want = env.header.mode == WT_ENV_CONSTANT ? glm::dvec3(0.5, 1.0, 2.0) : glm::dvec3(0.0);
      ASSERT_EQ(xyz(s.radiance[i]), want) << env.sourceName << " sample " << i;
      observed[std::min(15, int((s.directionPdf[i].s[1] + 1.0) * 8.0))] += 1.0;
    }
    expectHistogramsMatch("uniform_" + env.sourceName, 16, 1, observed, expected);
  }
}

TEST(EnvironmentSamplingAssets, SpotMapSamplesLandInItsTexel) {
  WT_REQUIRE_ASSET(file, "envmaps/spot1Lux.hdr");
  Environment env = loadEnvironmentMap(file);
  const int w = int(env.header.width), h = int(env.header.height);
  int lit = -1, litCount = 0;
  for (int k = 0; k < w * h; ++k)
    if (luminance709(env.texels[k]) > 0.0) lit = k, ++litCount;
  ASSERT_EQ(litCount, 1) << "spot1Lux.hdr should have exactly one non-zero pixel";
  const int li = lit % w, lj = lit / w;
  const double theta0 = kPi * lj / h, theta1 = kPi * (lj + 1) / h;
  const double solidAngle = 2.0 * kPi / w * (std::cos(theta0) - std::cos(theta1));

  const cl_uint n = 1 << 18;
  Samples s = sampleDevice(DeviceEnv(env), n, 5);
  expectSamplesConsistent(s, "spot1Lux");
  // E[1 / pdf] = the solid angle the samples cover
  double sum = 0.0, sum2 = 0.0;
  std::size_t outside = 0;
  for (std::size_t i = 0; i < n; ++i) {
    glm::dvec2 uv = mapUv(xyz(s.directionPdf[i]), 0.0);
    if ((int(uv.x * w) != li || int(uv.y * h) != lj) && ++outside <= 5)
      ADD_FAILURE() << "sample " << i << " at texel (" << int(uv.x * w) << ", " << int(uv.y * h) << "), not ("
                    << li << ", " << lj << ")";
    double pdf = s.directionPdf[i].s[3];
    ASSERT_TRUE(std::isfinite(pdf) && pdf > 0.0) << "sample " << i;
    sum += 1.0 / pdf, sum2 += 1.0 / (pdf * pdf);
  }
  EXPECT_EQ(outside, 0u);
  double mean = sum / n, se = std::sqrt(std::max(0.0, sum2 / n - mean * mean) / n);
  EXPECT_NEAR(mean, solidAngle, 5.0 * se + 1e-6 * solidAngle) << "texel solid angle " << solidAngle;
  // and environment_pdf there is the same finite value
  std::vector<cl_float4> at = evalPdf(DeviceEnv(env), {toCl(worldDirection((li + 0.5) / w, (lj + 0.5) / h, 0.0))});
  EXPECT_TRUE(std::isfinite(at[0].s[3]) && at[0].s[3] > 0.0f);
  EXPECT_NEAR(1.0 / at[0].s[3], solidAngle, 1e-3 * solidAngle);
}

// ---------------------------------------------------------------------------
// orientation and rotation

bool darkRed(const cl_float4& c) {
  return c.s[0] > 0.08f && c.s[1] < 0.35f * c.s[0] && c.s[2] < 0.35f * c.s[0];
}

TEST(EnvironmentOrientationAssets, MatchesOpenExrLatLongMap) {
  WT_REQUIRE_ASSET(file, "envmaps/openexr-images/OrientationLatLong.exr");
  Environment env = loadEnvironmentMap(file);
  const int w = int(env.header.width), h = int(env.header.height);
  ASSERT_EQ(w, 1024);
  ASSERT_EQ(h, 512);
  // random directions: the texel OpenEXR's LatLongMap names, within the half
  // texel by which its pixel-centre placement differs
  std::mt19937 rng(21);
  std::normal_distribution<double> g;
  std::vector<cl_float4> dirs;
  for (int k = 0; k < 20000; ++k) dirs.push_back(toCl(glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)))));
  std::vector<cl_float4> got = evalPdf(DeviceEnv(env), dirs);
  const Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1));
  int bad = 0;
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    Imath::V2f p = Imf::LatLongMap::pixelPosition(window, Imath::V3f(dirs[k].s[0], dirs[k].s[1], dirs[k].s[2]));
    bool found = false;
    for (int y = int(std::lround(p.y)) - 1; y <= int(std::lround(p.y)) + 1 && !found; ++y)
      for (int x = int(std::lround(p.x)) - 1; x <= int(std::lround(p.x)) + 1 && !found; ++x) {
        if (y < 0 || y >= h) continue;
        const WtVec4& t = env.texels[std::size_t(y) * w + std::size_t((x + w) % w)];
        found = t.x == got[k].s[0] && t.y == got[k].s[1] && t.z == got[k].s[2];
      }
    if (!found && ++bad <= 5)
      ADD_FAILURE() << "direction (" << dirs[k].s[0] << ", " << dirs[k].s[1] << ", " << dirs[k].s[2]
                    << "): OpenEXR pixel (" << p.x << ", " << p.y << ") differs from environment_eval";
  }
  EXPECT_EQ(bad, 0);
}

// OrientationLatLong.exr marks each horizontal axis with the dark red corner
// of a frame whose lines run towards +Y and towards the positive other
// horizontal axis (+X beside +-Z, +Z beside +-X); the poles are dark red caps.
TEST(EnvironmentOrientationAssets, AxesShowTheirMarks) {
  WT_REQUIRE_ASSET(file, "envmaps/openexr-images/OrientationLatLong.exr");
  Environment env = loadEnvironmentMap(file);
  DeviceEnv dev(env);
  const double texelU = 2.0 * kPi / env.header.width, texelV = kPi / env.header.height;
  const glm::dvec3 X(1, 0, 0), Y(0, 1, 0), Z(0, 0, 1);
  struct Axis {
    const char* name;
    glm::dvec3 a, side;
  };
  for (const Axis& axis : {Axis{"+X", X, Z}, Axis{"-X", -X, Z}, Axis{"+Z", Z, X}, Axis{"-Z", -Z, X}}) {
    // along direction `towards`, 4.5..24.5 texels out, with lateral slack of
    // +-2.5 texels (the axes lie on texel edges: half-texel steps hit centres)
    auto redAlong = [&](glm::dvec3 towards, glm::dvec3 lateral, double step, double lateralStep) {
      std::vector<cl_float4> dirs;
      for (int k = 4; k <= 24; ++k)
        for (int l = 0; l < 6; ++l) {
          glm::dvec3 d = axis.a * std::cos((k + 0.5) * step) + towards * std::sin((k + 0.5) * step);
          dirs.push_back(toCl(glm::normalize(d + lateral * ((l - 2.5) * lateralStep))));
        }
      std::vector<cl_float4> got = evalPdf(dev, dirs);
      int redSteps = 0;
      for (int k = 0; k <= 20; ++k) {
        bool red = false;
        for (int l = 0; l < 6; ++l) red = red || darkRed(got[std::size_t(k) * 6 + l]);
        redSteps += red;
      }
      return redSteps;  // of 21
    };
    EXPECT_EQ(redAlong(Y, axis.side, texelV, texelU), 21) << axis.name << ": the frame line towards +Y";
    EXPECT_EQ(redAlong(-Y, axis.side, texelV, texelU), 0) << axis.name << ": nothing red towards -Y";
    EXPECT_EQ(redAlong(axis.side, Y, texelU, texelV), 21) << axis.name << ": the frame line towards the positive side axis";
    EXPECT_EQ(redAlong(-axis.side, Y, texelU, texelV), 0) << axis.name << ": nothing red away from it";
  }
  std::vector<cl_float4> poles = evalPdf(dev, {toCl(Y), toCl(-Y)});
  EXPECT_TRUE(darkRed(poles[0])) << "+Y cap";
  EXPECT_TRUE(darkRed(poles[1])) << "-Y cap";
}

TEST(EnvironmentOrientationAssets, RotationTurnsCounterClockwiseSeenFromAbove) {
  // every texel a different colour; directions at texel centres of the unrotated map
  const int w = 16, h = 8;
  std::vector<glm::vec3> rgb(w * h);
  for (int k = 0; k < w * h; ++k) rgb[k] = {float(k + 1), float(k % 7), 1.0f};
  Environment plain = makeEnvironmentMap(w, h, rgb, 1.0f, 0.0f, "plain");
  for (float degrees : {90.0f, 37.0f, -200.0f}) {
    Environment turned = makeEnvironmentMap(w, h, rgb, 1.0f, degrees, "turned");
    const double a = degrees * kPi / 180.0;
    std::vector<cl_float4> dirs, turnedDirs;
    for (int j = 0; j < h; ++j)
      for (int i = 0; i < w; ++i) {
        glm::dvec3 d = worldDirection((i + 0.5) / w, (j + 0.5) / h, 0.0);
        dirs.push_back(toCl(d));
        turnedDirs.push_back(toCl(rotateY(d, a)));
      }
    std::vector<cl_float4> want = evalPdf(DeviceEnv(plain), dirs), got = evalPdf(DeviceEnv(turned), turnedDirs);
    for (std::size_t k = 0; k < dirs.size(); ++k)
      ASSERT_EQ(xyz(got[k]), xyz(want[k])) << degrees << " degrees, texel " << k;
  }
  // 90 degrees: what the map shows at +Z appears at +X, +X moves to -Z
  Environment turned = makeEnvironmentMap(w, h, rgb, 1.0f, 90.0f, "turned");
  std::vector<cl_float4> want = evalPdf(DeviceEnv(plain), {toCl({0.01, 0.2, 1}), toCl({1, 0.2, 0.01})});
  std::vector<cl_float4> got = evalPdf(DeviceEnv(turned), {toCl({1, 0.2, -0.01}), toCl({0.01, 0.2, -1})});
  EXPECT_EQ(xyz(got[0]), xyz(want[0]));
  EXPECT_EQ(xyz(got[1]), xyz(want[1]));
}

// ---------------------------------------------------------------------------
// estimation

/// Irradiance for `normal` by importance sampling against the sum over
/// texels of radiance x the cosine integrated over the texel (subdivided
/// `sub` x `sub`), per channel, within 5 standard errors.
void expectIrradianceMatches(const Environment& env, glm::dvec3 normal, cl_uint n, int sub, cl_uint seed) {
  const int w = int(env.header.width), h = int(env.header.height);
  const double rotation = env.header.rotation;
  glm::dvec3 brute(0.0);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const WtVec4& t = env.texels[std::size_t(j) * w + i];
      if (t.x == 0.0f && t.y == 0.0f && t.z == 0.0f) continue;
      double cosine = 0.0;
      for (int b = 0; b < sub; ++b)
        for (int a = 0; a < sub; ++a) {
          double u = (i + (a + 0.5) / sub) / w, v = (j + (b + 0.5) / sub) / h;
          double jacobian = 2.0 * kPi * kPi * std::sin(kPi * v) / (double(w) * h * sub * sub);
          cosine += std::max(0.0, glm::dot(normal, worldDirection(u, v, rotation))) * jacobian;
        }
      brute += glm::dvec3(t.x, t.y, t.z) * double(env.header.intensity) * cosine;
    }
  Samples s = sampleDevice(DeviceEnv(env), n, seed);
  glm::dvec3 sum(0.0), sum2(0.0);
  for (std::size_t i = 0; i < n; ++i) {
    glm::dvec3 f = xyz(s.radiance[i]) * std::max(0.0, glm::dot(normal, xyz(s.directionPdf[i]))) /
                   double(s.directionPdf[i].s[3]);
    sum += f, sum2 += f * f;
  }
  for (int c = 0; c < 3; ++c) {
    double mean = sum[c] / n, se = std::sqrt(std::max(0.0, sum2[c] / n - mean * mean) / n);
    EXPECT_NEAR(mean, brute[c], 5.0 * se + 1e-6 * brute[c])
        << env.sourceName << ", normal (" << normal.x << ", " << normal.y << ", " << normal.z << "), channel " << c
        << ": importance sampling vs brute force (standard error " << se << ")";
  }
}

TEST(EnvironmentEstimation, IrradianceMatchesBruteForce) {
  Environment env = syntheticMap(30.0f, 2.5f);
  for (glm::dvec3 n : {glm::dvec3(0, 1, 0), glm::normalize(glm::dvec3(1, 0.3, -0.5)), glm::dvec3(0, -1, 0),
                       glm::normalize(glm::dvec3(-0.2, 0.1, 1))})
    expectIrradianceMatches(env, n, 1 << 20, 64, 6);
}

TEST(EnvironmentEstimationAssets, IrradianceMatchesBruteForceOnRealMap) {
  WT_REQUIRE_ASSET(file, "envmaps/royal_esplanade_1k.hdr");
  Environment env = loadEnvironmentMap(file, 0.7f, -45.0f);
  for (glm::dvec3 n : {glm::dvec3(0, 1, 0), glm::normalize(glm::dvec3(0.6, 0.2, -0.7))})
    expectIrradianceMatches(env, n, 1 << 20, 4, 7);
}

}  // namespace
}  // namespace wt
