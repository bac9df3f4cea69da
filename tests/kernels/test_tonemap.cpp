// The tonemap stage (kernels/tonemap.cl, kernels/shared/tonemap.h): every
// operator on the device against its closed form evaluated here in double,
// monotonic, 0 -> 0 and its documented values (docs/tonemapping.md); auto
// exposure of a constant image to middle grey; PNGs of values above 1 not
// clipped by the filmic operators; dithering; the EXR unchanged by tone mapping.
#include "device/program.h"
#include "device_fixture.h"
#include "output/image_io.h"
#include "render/renderer.h"
#include "render/tonemap.h"
#include "scene/default_scene.h"
#include "test_util.h"

#include <gtest/gtest.h>
#include <stb_image.h>

#include <array>
#include <bit>
#include <cmath>
#include <fstream>
#include <iterator>
#include <random>

namespace wt {
namespace {

using Rgb = std::array<double, 3>;
using Mat = std::array<double, 9>;  // row-major

Rgb mul(const Mat& m, const Rgb& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

Mat inverse(const Mat& m) {
  const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                     m[2] * (m[3] * m[7] - m[4] * m[6]);
  return {(m[4] * m[8] - m[5] * m[7]) / det, (m[2] * m[7] - m[1] * m[8]) / det, (m[1] * m[5] - m[2] * m[4]) / det,
          (m[5] * m[6] - m[3] * m[8]) / det, (m[0] * m[8] - m[2] * m[6]) / det, (m[2] * m[3] - m[0] * m[5]) / det,
          (m[3] * m[7] - m[4] * m[6]) / det, (m[1] * m[6] - m[0] * m[7]) / det, (m[0] * m[4] - m[1] * m[3]) / det};
}

double sat(double x) { return std::min(std::max(x, 0.0), 1.0); }
double luminance(const Rgb& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
Rgb scaled(const Rgb& c, double s) { return {c[0] * s, c[1] * s, c[2] * s}; }

// ---------------------------------------------------------------------------
// the closed forms, from their publications (docs/tonemapping.md)

double hableCurve(double x) {
  const double a = 0.22, b = 0.3, c = 0.1, d = 0.2, e = 0.01, f = 0.3;  // Falcor's ToneMapper
  return (x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f) - e / f;
}

double acesRrtOdt(double v) {
  return (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
}

// AgX: Jed Smith's tunable sigmoid as Sobotka's sigmoid.py writes it, with
// EaryChow's (Blender 4) parameters
constexpr double kAgxMin = -10.0, kAgxMax = 6.5, kAgxSlope = 2.4, kAgxPower = 1.5;
double agxXPivot() { return -kAgxMin / (kAgxMax - kAgxMin); }
double agxYPivot() { return std::pow(0.18, 1.0 / 2.4); }
double agxScale(double limitX, double limitY, double transitionX, double transitionY) {
  const double a = std::pow(kAgxSlope * (limitX - transitionX), -kAgxPower);
  const double b = std::pow(kAgxSlope * (limitX - transitionX) / (limitY - transitionY), kAgxPower) - 1.0;
  return std::pow(a * b, -1.0 / kAgxPower);
}
double agxToeScale() { return -agxScale(1.0, 1.0, 1.0 - agxXPivot(), 1.0 - agxYPivot()); }
double agxShoulderScale() { return agxScale(1.0, 1.0, agxXPivot(), agxYPivot()); }
double agxSigmoid(double x) {
  const double s = x < agxXPivot() ? agxToeScale() : agxShoulderScale();
  const double t = kAgxSlope * (x - agxXPivot()) / s;
  return s * t / std::pow(1.0 + std::pow(t, kAgxPower), 1.0 / kAgxPower) + agxYPivot();
}

Rgb agx(Rgb c) {
  // ITU-R BT.2087 (Rec.709 -> Rec.2020); the inset and outset matrices of EaryChow's AgXBaseRec2020.py
  const Mat to2020 = {0.627403895934699, 0.329283038377884, 0.043313065687417, 0.069097289358232, 0.919540395075459,
                      0.011362315566309, 0.016391438875150, 0.088013307877226, 0.895595253247624};
  const Mat inset = {0.856627153315983, 0.0951212405381588, 0.0482516061458583, 0.137318972929847, 0.761241990602591,
                     0.101439036467562, 0.11189821299995,  0.0767994186031903, 0.811302368396859};
  const Mat outsetForward = {0.899796955911611, 0.0871996192028351, 0.013003424885555,
                             0.11142098895748,  0.875575586156966,  0.0130034248855548,
                             0.11142098895748,  0.0871996192028349, 0.801379391839686};
  for (double& v : c) v = std::max(v, 1e-10);
  c = mul(inset, mul(to2020, c));
  for (double& v : c) {
    const double x = sat((std::log2(v / 0.18) - kAgxMin) / (kAgxMax - kAgxMin));
    v = std::pow(agxSigmoid(x), 2.4);
  }
  return mul(inverse(to2020), mul(inverse(outsetForward), c));
}

Rgb pbrNeutral(Rgb c) {
  const double start = 0.8 - 0.04, desaturation = 0.15;
  const double x = std::min({c[0], c[1], c[2]});
  const double offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
  for (double& v : c) v -= offset;
  const double peak = std::max({c[0], c[1], c[2]});
  if (peak < start) return c;
  const double d = 1.0 - start;
  const double newPeak = 1.0 - d * d / (peak + d - start);
  c = scaled(c, newPeak / peak);
  const double g = 1.0 - 1.0 / (desaturation * (peak - newPeak) + 1.0);
  for (double& v : c) v = v * (1.0 - g) + newPeak * g;
  return c;
}

/// Display-linear output of operator `op` for scene-linear `c`, in double.
Rgb closedForm(std::uint32_t op, Rgb c, double white) {
  for (double& v : c) v = std::max(v, 0.0);
  const double l = luminance(c);
  Rgb out = c;
  switch (op) {
    case WT_TONEMAP_LINEAR: break;
    case WT_TONEMAP_REINHARD: out = l > 0 ? scaled(c, (l / (1.0 + l)) / l) : Rgb{}; break;
    case WT_TONEMAP_REINHARD_MODIFIED:
      out = l > 0 ? scaled(c, (l * (1.0 + l / (white * white)) / (1.0 + l)) / l) : Rgb{};
      break;
    case WT_TONEMAP_HABLE:
      for (int i = 0; i < 3; ++i) out[i] = hableCurve(2.0 * c[i]) / hableCurve(white);
      break;
    case WT_TONEMAP_ACES: {
      const Mat in = {0.59719, 0.35458, 0.04823, 0.07600, 0.90834, 0.01566, 0.02840, 0.13383, 0.83777};
      const Mat back = {1.60475, -0.53108, -0.07367, -0.10208, 1.10813, -0.00605, -0.00327, -0.07276, 1.07602};
      Rgb v = mul(in, c);
      for (double& x : v) x = acesRrtOdt(x);
      out = mul(back, v);
      break;
    }
    case WT_TONEMAP_ACES_NARKOWICZ:
      for (int i = 0; i < 3; ++i) {
        const double x = 0.6 * c[i];
        out[i] = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
      }
      break;
    case WT_TONEMAP_AGX: out = agx(c); break;
    case WT_TONEMAP_PBR_NEUTRAL: out = pbrNeutral(c); break;
  }
  for (double& v : out) v = sat(v);
  return out;
}

// ---------------------------------------------------------------------------

/// The device's operator `op` on each colour (test_tonemap_apply).
std::vector<Rgb> onDevice(std::uint32_t op, const std::vector<Rgb>& colours, float white) {
  Context& ctx = test::deviceContext();
  const cl_uint n = cl_uint(colours.size());
  std::vector<cl_float4> in(n);
  for (cl_uint i = 0; i < n; ++i) in[i] = {{float(colours[i][0]), float(colours[i][1]), float(colours[i][2]), 0.0f}};
  cl::Buffer inBuffer(ctx.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, n * sizeof(cl_float4), in.data());
  cl::Buffer outBuffer(ctx.context(), CL_MEM_WRITE_ONLY, n * sizeof(cl_float4));
  cl::Kernel k(test::testProgram("tonemap_tests.cl"), "test_tonemap_apply");
  k.setArg(0, n), k.setArg(1, cl_uint(op)), k.setArg(2, white), k.setArg(3, inBuffer), k.setArg(4, outBuffer);
  ctx.launch("test_tonemap_apply", k, n);
  std::vector<cl_float4> out(n);
  ctx.queue().enqueueReadBuffer(outBuffer, CL_TRUE, 0, n * sizeof(cl_float4), out.data());
  std::vector<Rgb> result(n);
  for (cl_uint i = 0; i < n; ++i) result[i] = {out[i].s[0], out[i].s[1], out[i].s[2]};
  return result;
}

std::vector<std::uint32_t> allOperators() {
  std::vector<std::uint32_t> ops;
  for (std::uint32_t op = 0; op < WT_TONEMAP_COUNT; ++op) ops.push_back(op);
  return ops;
}

/// Greys from 0 over 2^-14 .. 2^14 (scene-linear), geometrically spaced.
std::vector<Rgb> greyRamp(int steps) {
  std::vector<Rgb> ramp = {{0.0, 0.0, 0.0}};
  for (int i = 0; i < steps; ++i) {
    const double v = std::exp2(-14.0 + 28.0 * i / (steps - 1));
    ramp.push_back({v, v, v});
  }
  return ramp;
}

// Float evaluation of at most ~60 operations, library functions within the
// OpenCL bounds (pow 16 ulp, log2/exp2 3 ulp), amplified at most 2.4x twice
// (AgX's slope and power): well under 1e-5 of the output range; 1e-4 is
// the margin, far below what a wrong constant or formula changes.
constexpr double kOperatorTolerance = 1e-4;

TEST(Tonemap, OperatorsMatchTheirClosedFormsInDouble) {
  std::vector<Rgb> colours = greyRamp(97);
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 400; ++i) {
    // colours over 2^-8 .. 2^6 per channel, some with a channel at 0
    Rgb c;
    for (double& v : c) v = u(rng) < 0.1 ? 0.0 : std::exp2(-8.0 + 14.0 * u(rng));
    colours.push_back(c);
  }
  for (std::uint32_t op : allOperators()) {
    const float white = defaultTonemapWhite(op);
    const std::vector<Rgb> got = onDevice(op, colours, white);
    double worst = 0.0;
    std::size_t at = 0;
    for (std::size_t i = 0; i < colours.size(); ++i) {
      const Rgb want = closedForm(op, colours[i], white);
      for (int c = 0; c < 3; ++c)
        if (std::fabs(got[i][c] - want[c]) > worst) worst = std::fabs(got[i][c] - want[c]), at = i;
    }
    EXPECT_LT(worst, kOperatorTolerance)
        << tonemapOperatorName(op) << ": worst at (" << colours[at][0] << ", " << colours[at][1] << ", "
        << colours[at][2] << ") -> device (" << got[at][0] << ", " << got[at][1] << ", " << got[at][2]
        << "), closed form (" << closedForm(op, colours[at], white)[0] << ", " << closedForm(op, colours[at], white)[1]
        << ", " << closedForm(op, colours[at], white)[2] << ")";
  }
}

// The curve's mantissa power is a degree-7 fit on [1, 2) whose float
// evaluation strays 1.8e-7 at most (the fit 8e-8 plus seven fma roundings),
// scaled by at most 1.055, then one more rounding of 1 at most (6e-8): 3e-7.
// A level of the 8-bit output is 3.9e-3.
constexpr double kSrgbCurveTolerance = 3e-7;

TEST(Tonemap, SrgbCurveIsWithinItsBoundAtEveryFloat) {
  // every float in [0, 1] above the linear segment's 2^-9 (75 M values), a
  // few on the segment and past its ends, on the device, against the
  // curve in double
  Context& ctx = test::deviceContext();
  cl::Kernel k(test::testProgram("tonemap_tests.cl"), "test_srgb_encode");
  constexpr cl_uint kChunk = 1u << 23;
  cl::Buffer outBuffer(ctx.context(), CL_MEM_WRITE_ONLY, kChunk * sizeof(float));
  std::vector<float> out(kChunk);
  const auto curve = [](double c) {
    c = std::isnan(c) ? 0.0 : sat(c);  // fmax and fmin drop a NaN
    return c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
  };
  double worst = 0.0;
  float worstAt = 0.0f;
  const auto check = [&](std::uint32_t first, cl_uint count) {
    k.setArg(0, cl_uint(first)), k.setArg(1, count), k.setArg(2, outBuffer);
    ctx.launch("test_srgb_encode", k, count);
    ctx.queue().enqueueReadBuffer(outBuffer, CL_TRUE, 0, count * sizeof(float), out.data());
    for (cl_uint i = 0; i < count; ++i) {
      const float c = std::bit_cast<float>(first + i);
      const double error = std::fabs(double(out[i]) - curve(double(c)));
      if (!(error <= worst)) worst = error, worstAt = c;  // a NaN output counts as worst
    }
  };
  const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
  for (std::uint32_t first = std::bit_cast<std::uint32_t>(0x1p-9f); first < one; first += kChunk)
    check(first, std::min<cl_uint>(kChunk, one - first + 1u));
  check(one, 4096);                                               // above 1: saturated
  check(std::bit_cast<std::uint32_t>(0.0f), 4096);                // 0 and denormals
  check(std::bit_cast<std::uint32_t>(0.0031308f) - 2048u, 4096);  // across the linear segment's end
  check(std::bit_cast<std::uint32_t>(-0.0f), 4096);               // negative: 0
  check(0x7f800000u, 4096);                                       // infinity: 1; NaNs: 0
  EXPECT_LE(worst, kSrgbCurveTolerance) << "at " << worstAt;
}

TEST(Tonemap, HostBuildOfTheHeaderMatchesTheDevice) {
  // the same shared/tonemap.h compiled by g++: float code, a few ulp apart
  // from the device's library functions, far inside kOperatorTolerance
  std::vector<Rgb> colours = greyRamp(65);
  colours.push_back({4.0, 0.5, 0.01});
  colours.push_back({0.0, 20.0, 0.3});
  for (std::uint32_t op : allOperators()) {
    const float white = defaultTonemapWhite(op);
    const std::vector<Rgb> got = onDevice(op, colours, white);
    for (std::size_t i = 0; i < colours.size(); ++i) {
      const TonemapRgb host =
          tonemap_apply(op, tonemap_rgb(float(colours[i][0]), float(colours[i][1]), float(colours[i][2])), white);
      EXPECT_NEAR(host.r, got[i][0], 1e-5) << tonemapOperatorName(op) << " colour " << i;
      EXPECT_NEAR(host.g, got[i][1], 1e-5) << tonemapOperatorName(op) << " colour " << i;
      EXPECT_NEAR(host.b, got[i][2], 1e-5) << tonemapOperatorName(op) << " colour " << i;
    }
  }
}

TEST(Tonemap, AgxSigmoidConstantsAreItsDefinitionsScales) {
  EXPECT_NEAR(WT_TONEMAP_AGX_X_PIVOT, agxXPivot(), 1e-7);
  EXPECT_NEAR(WT_TONEMAP_AGX_Y_PIVOT, agxYPivot(), 1e-7);
  EXPECT_NEAR(WT_TONEMAP_AGX_TOE, agxToeScale(), 1e-7);
  EXPECT_NEAR(WT_TONEMAP_AGX_SHOULDER, agxShoulderScale(), 1e-7);
  // the curve meets its limits (0, 0) and (1, 1)
  EXPECT_NEAR(agxSigmoid(0.0), 0.0, 1e-12);
  EXPECT_NEAR(agxSigmoid(1.0), 1.0, 1e-12);
}

TEST(Tonemap, OperatorsAreMonotonicAndMapZeroToZero) {
  const std::vector<Rgb> ramp = greyRamp(2049);
  for (std::uint32_t op : allOperators()) {
    const std::vector<Rgb> got = onDevice(op, ramp, defaultTonemapWhite(op));
    for (int c = 0; c < 3; ++c) EXPECT_LE(std::fabs(got[0][c]), 1e-6) << tonemapOperatorName(op) << " of 0";
    for (std::size_t i = 1; i < got.size(); ++i)
      for (int c = 0; c < 3; ++c)
        // float rounding may step back by an ulp or two of values near 1
        ASSERT_GE(got[i][c], got[i - 1][c] - 1e-6)
            << tonemapOperatorName(op) << " falls from grey " << ramp[i - 1][0] << " to " << ramp[i][0];
    EXPECT_GT(got.back()[1], got[1][1] + 0.5) << tonemapOperatorName(op) << " is flat";
  }
}

TEST(Tonemap, DocumentedValues) {
  // docs/tonemapping.md, "Operators": what each maps where
  struct Doc {
    std::uint32_t op;
    double in, out;
  };
  const double nark = 0.6 * (2.51 * 0.6 + 0.03) / (0.6 * (2.43 * 0.6 + 0.59) + 0.14);
  const std::vector<Doc> docs = {
      {WT_TONEMAP_LINEAR, 1.0, 1.0},           {WT_TONEMAP_LINEAR, 0.25, 0.25},
      {WT_TONEMAP_REINHARD, 1.0, 0.5},         {WT_TONEMAP_REINHARD, 3.0, 0.75},
      {WT_TONEMAP_REINHARD_MODIFIED, 4.0, 1.0},  // the white point
      {WT_TONEMAP_HABLE, 5.6, 1.0},            // linear white 11.2 after the bias of 2
      {WT_TONEMAP_ACES_NARKOWICZ, 1.0, nark},  // 0.9216 / 1.3688
      {WT_TONEMAP_AGX, 0.18, 0.18},            // middle grey is the sigmoid's pivot
      {WT_TONEMAP_PBR_NEUTRAL, 0.5, 0.46},     // below the compression: x - 0.04
      {WT_TONEMAP_PBR_NEUTRAL, 1.0, 1.0 - 0.24 * 0.24 / 0.44},
  };
  for (const Doc& d : docs) {
    const Rgb got = onDevice(d.op, {{d.in, d.in, d.in}}, defaultTonemapWhite(d.op))[0];
    EXPECT_NEAR(got[1], d.out, kOperatorTolerance) << tonemapOperatorName(d.op) << " of grey " << d.in;
  }
}

/// A linear image of `width` x `height` with every pixel `value`.
Image constantImage(int width, int height, float value) {
  Image image;
  image.width = width, image.height = height;
  image.rgb.assign(3 * std::size_t(width) * height, value);
  return image;
}

TEST(Tonemap, AutoExposureMapsAConstantImageToMiddleGrey) {
  Context& ctx = test::deviceContext();
  TonemapSettings s;
  s.op = WT_TONEMAP_LINEAR;
  s.autoExposure = true;
  s.dither = false;
  // 37 x 23 = 851 pixels: four partial sums, the last of 83 pixels
  for (float value : {0.003f, 0.5f, 7.0f, 2000.0f}) {
    Image image = constantImage(37, 23, value);
    float scale = 0.0f;
    tonemapImage(ctx, image, s, 0.0f, &scale);
    // float log2/exp2 of one value summed 851 times: a relative error of ~1e-6
    EXPECT_NEAR(scale * value, WT_TONEMAP_MIDDLE_GREY, 1e-5) << "constant " << value;
    // 0.18 through the sRGB curve is 117.64 / 255: every pixel 118
    for (std::size_t p = 0; p < image.srgba.size(); p += 4) ASSERT_EQ(image.srgba[p + 1], 118) << "pixel " << p / 4;
  }
  // compensation on top of auto: one stop brighter
  Image image = constantImage(37, 23, 3.0f);
  float scale = 0.0f;
  tonemapImage(ctx, image, s, 1.0f, &scale);
  EXPECT_NEAR(scale * 3.0f, WT_TONEMAP_MIDDLE_GREY, 1e-5);
  EXPECT_EQ(image.srgba[1], 162);  // sRGB of 0.36 is 0.6342, 161.73 / 255
}

TEST(Tonemap, AutoExposureUsesTheLogAverage) {
  // half the pixels a, half b: the log-average is sqrt(a b), not (a + b) / 2
  Image image = constantImage(40, 30, 0.0f);
  const float a = 0.02f, b = 50.0f;
  for (std::size_t p = 0; p < 1200; ++p)
    for (int c = 0; c < 3; ++c) image.rgb[3 * p + c] = p % 2 ? a : b;
  TonemapSettings s;
  s.autoExposure = true;
  float scale = 0.0f;
  tonemapImage(test::deviceContext(), image, s, 0.0f, &scale);
  EXPECT_NEAR(scale, WT_TONEMAP_MIDDLE_GREY / std::sqrt(a * b), 1e-5 * WT_TONEMAP_MIDDLE_GREY / std::sqrt(a * b));
}

/// 8-bit PNG channels of `image` as written to and read back from disk.
std::vector<unsigned char> throughPng(const Image& image, const std::string& name) {
  const std::filesystem::path path = test::scratchDir("tonemap") / (name + ".png");
  writeImage(path, image);
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 4);
  EXPECT_TRUE(data) << path;
  std::vector<unsigned char> out(data, data + 4 * w * h);
  stbi_image_free(data);
  return out;
}

TEST(Tonemap, FilmicPngOfValuesAboveOneIsNotClipped) {
  // greys from 1 to 3.5 (below the whites of reinhard-modified, 4, and
  // hable, 5.6): distinct shades under every operator but linear, which
  // clips them all to 255
  const int n = 32;
  Image image = constantImage(n, 1, 0.0f);
  for (int x = 0; x < n; ++x)
    for (int c = 0; c < 3; ++c) image.rgb[3 * x + c] = float(std::pow(3.5, double(x) / (n - 1)));
  for (std::uint32_t op : allOperators()) {
    TonemapSettings s;
    s.op = op;
    s.dither = false;
    tonemapImage(test::deviceContext(), image, s, 0.0f);
    const std::vector<unsigned char> png = throughPng(image, tonemapOperatorName(op));
    int clipped = 0;
    for (int x = 0; x < n; ++x) clipped += png[4 * x + 1] == 255;
    const int rise = png[4 * (n - 1) + 1] - png[1];
    if (op == WT_TONEMAP_LINEAR) {
      EXPECT_EQ(clipped, n) << "linear clips above 1";
    } else {
      EXPECT_EQ(clipped, 0) << tonemapOperatorName(op) << " clips values in [1, 3.5]";
      EXPECT_GE(rise, 4) << tonemapOperatorName(op) << ": 1 and 3.5 barely differ";
    }
  }
}

TEST(Tonemap, DitherIsReproducibleAndRemovesBanding) {
  // a flat field whose exact 8-bit value is 100.3: undithered every pixel is
  // 100; dithered, 100 or 101 with a mean of 100.3
  const double encoded = 100.3 / 255.0;
  const float linear = float(std::pow((encoded + 0.055) / 1.055, 2.4));
  Image image = constantImage(64, 64, linear);
  TonemapSettings s;
  s.op = WT_TONEMAP_LINEAR;
  s.dither = false;
  tonemapImage(test::deviceContext(), image, s, 0.0f);
  for (std::size_t p = 0; p < image.srgba.size(); p += 4) ASSERT_EQ(image.srgba[p], 100);
  s.dither = true;
  tonemapImage(test::deviceContext(), image, s, 0.0f);
  const std::vector<std::uint8_t> first = image.srgba;
  double sum = 0.0;
  const std::size_t pixels = 64 * 64;
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) ASSERT_TRUE(image.srgba[4 * p + c] == 100 || image.srgba[4 * p + c] == 101);
    sum += image.srgba[4 * p];
  }
  // a uniform dither: each pixel 101 with probability 0.3, sd of the mean
  // sqrt(0.21 / 4096) = 0.0072; five of them
  EXPECT_NEAR(sum / pixels, 100.3, 0.036);
  tonemapImage(test::deviceContext(), image, s, 0.0f);
  EXPECT_EQ(image.srgba, first) << "the dither is a function of the pixel";
}

TEST(Tonemap, ExrIsUnchangedByTheTonemapSettings) {
  Context& ctx = test::deviceContext();
  Scene scene = loadDefaultScene();
  auto renderTo = [&](const RenderSettings& settings, const std::string& name) {
    Renderer renderer(ctx, scene, settings);
    renderer.renderSample();
    Image image = renderer.readImage();
    const std::filesystem::path dir = test::scratchDir("tonemap_exr");
    writeImage(dir / (name + ".exr"), image);
    std::ifstream in(dir / (name + ".exr"), std::ios::binary);
    return std::make_pair(std::vector<char>(std::istreambuf_iterator<char>(in), {}), image.srgba);
  };
  RenderSettings a;
  a.width = 24, a.height = 16, a.samplesPerPixel = 1;
  a.tonemap.op = WT_TONEMAP_LINEAR;
  RenderSettings b = a;
  b.tonemap.op = WT_TONEMAP_AGX;
  b.tonemap.autoExposure = true;
  b.tonemap.whiteBalanceKelvin = 3200.0f;
  b.exposureStops = 2.0f;
  const auto [exrA, pngA] = renderTo(a, "linear");
  const auto [exrB, pngB] = renderTo(b, "agx_auto");
  EXPECT_EQ(exrA, exrB) << "the EXR changed with the tone mapping";
  EXPECT_NE(pngA, pngB) << "the tone mapping settings changed nothing";
}

TEST(Tonemap, PhysicalExposureIsTwoToTheMinusEv100) {
  EXPECT_DOUBLE_EQ(physicalExposureScale(1.0, 1.0, 100.0), 1.0);
  // sunny 16: f/16, 1/100 s, ISO 100 is EV100 log2(25600) = 14.64
  EXPECT_NEAR(physicalExposureScale(16.0, 0.01, 100.0), std::exp2(-std::log2(25600.0)), 1e-15);
  // one stop each: double the ISO or the time, or f-number times sqrt(2) the other way
  EXPECT_NEAR(physicalExposureScale(8.0, 0.01, 200.0), 2.0 * physicalExposureScale(8.0, 0.01, 100.0), 1e-15);
  EXPECT_NEAR(physicalExposureScale(8.0 * std::sqrt(2.0), 0.02, 100.0), physicalExposureScale(8.0, 0.01, 100.0), 1e-15);
  TonemapSettings s;
  s.fNumber = 16.0f, s.shutterSeconds = 0.01f, s.iso = 100.0f;
  EXPECT_NEAR(exposureScale(s, 1.0f), 2.0 / 25600.0, 1e-9);
}

TEST(Tonemap, WhiteBalanceTurnsTheBlackbodyGrey) {
  // at 6500 K nothing changes; at another temperature the blackbody's own
  // colour (its chromaticity as Rec.709) comes out grey
  const std::vector<double> d65 = whiteBalanceMatrix(6500.0);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(d65[i], i % 4 == 0 ? 1.0 : 0.0, 1e-12) << i;
  for (double kelvin : {2000.0, 3200.0, 5000.0, 9000.0, 20000.0}) {
    auto [x, y] = blackbodyChromaticity(kelvin);
    const Rgb xyz = {x / y, 1.0, (1.0 - x - y) / y};
    const Mat toRgb = {3.2409699419045213,  -1.5373831775700935, -0.4986107602930033,
                       -0.9692436362808798, 1.8759675015077206,  0.0415550574071756,
                       0.0556300796969936,  -0.2039769588889765, 1.0569715142428784};
    const Rgb light = mul(toRgb, xyz);
    const std::vector<double> m = whiteBalanceMatrix(kelvin);
    const Rgb balanced = mul({m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8]}, light);
    // grey: the 6500 K locus point (not exactly D65) balances to (1, 1, 1) up to its own tint
    const Rgb d65Light = mul(toRgb, [] {
      auto [x6, y6] = blackbodyChromaticity(6500.0);
      return Rgb{x6 / y6, 1.0, (1.0 - x6 - y6) / y6};
    }());
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(balanced[c] / balanced[1], d65Light[c] / d65Light[1], 1e-9) << kelvin << " K, channel " << c;
  }
}

}  // namespace
}  // namespace wt
