#include "render/tonemap.h"

#include "device/program.h"
#include "render/renderer.h"

#include <array>
#include <cmath>

namespace wt {
namespace {

using Mat3 = std::array<double, 9>;  // row-major

Mat3 mul(const Mat3& a, const Mat3& b) {
  Mat3 r{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) r[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return r;
}

std::array<double, 3> apply(const Mat3& m, const std::array<double, 3>& v) {
  return {m[0] * v[0] + m[1] * v[1] + m[2] * v[2], m[3] * v[0] + m[4] * v[1] + m[5] * v[2],
          m[6] * v[0] + m[7] * v[1] + m[8] * v[2]};
}

// Rec.709 (D65) and CIE XYZ, and CAT02's LMS (CIECAM02)
constexpr Mat3 kRgbToXyz = {0.4123907992659595, 0.3575843393838780, 0.1804807884018343,
                            0.2126390058715104, 0.7151686787677559, 0.0721923153607337,
                            0.0193308187155918, 0.1191947797946259, 0.9505321522496608};
constexpr Mat3 kXyzToRgb = {3.2409699419045213,  -1.5373831775700935, -0.4986107602930033,
                            -0.9692436362808798, 1.8759675015077206,  0.0415550574071756,
                            0.0556300796969936,  -0.2039769588889765, 1.0569715142428784};
constexpr Mat3 kXyzToLms = {0.7328, 0.4296, -0.1624, -0.7036, 1.6975, 0.0061, 0.0030, 0.0136, 0.9834};
constexpr Mat3 kLmsToXyz = {1.096123820835514,  -0.278869000218287, 0.182745179382773,
                            0.454369041975359,  0.473533154307412,  0.072097803717229,
                            -0.009627608738429, -0.005698031216113, 1.015325639954543};

std::array<double, 3> blackbodyLms(double kelvin) {
  auto [x, y] = blackbodyChromaticity(kelvin);
  return apply(kXyzToLms, {x / y, 1.0, (1.0 - x - y) / y});
}

}  // namespace

float defaultTonemapWhite(std::uint32_t op) { return op == WT_TONEMAP_HABLE ? 11.2f : 4.0f; }

double physicalExposureScale(double fNumber, double shutterSeconds, double iso) {
  const double ev100 = std::log2(fNumber * fNumber / shutterSeconds * 100.0 / iso);
  return std::exp2(-ev100);
}

float exposureScale(const TonemapSettings& s, float exposureStops) {
  return float(std::exp2(double(exposureStops)) * physicalExposureScale(s.fNumber, s.shutterSeconds, s.iso));
}

std::pair<double, double> blackbodyChromaticity(double t) {
  // Kang et al. 2002: the Planckian locus as piecewise rational polynomials
  const double t2 = t * t, t3 = t2 * t;
  const double x = t < 4000.0 ? -0.2661239e9 / t3 - 0.2343580e6 / t2 + 0.8776956e3 / t + 0.179910
                              : -3.0258469e9 / t3 + 2.1070379e6 / t2 + 0.2226347e3 / t + 0.240390;
  const double x2 = x * x, x3 = x2 * x;
  const double y = t < 2222.0   ? -1.1063814 * x3 - 1.34811020 * x2 + 2.18555832 * x - 0.20219683
                   : t < 4000.0 ? -0.9549476 * x3 - 1.37418593 * x2 + 2.09137015 * x - 0.16748867
                                : 3.0817580 * x3 - 5.87338670 * x2 + 3.75112997 * x - 0.37001483;
  return {x, y};
}

std::vector<double> whiteBalanceMatrix(double kelvin) {
  // von Kries: scale LMS so that the source white becomes the 6500 K white
  const std::array<double, 3> target = blackbodyLms(6500.0), source = blackbodyLms(kelvin);
  const Mat3 d = {target[0] / source[0], 0, 0, 0, target[1] / source[1], 0, 0, 0, target[2] / source[2]};
  const Mat3 m = mul(mul(mul(kXyzToRgb, kLmsToXyz), d), mul(kXyzToLms, kRgbToXyz));
  return std::vector<double>(m.begin(), m.end());
}

WtTonemapParams tonemapParams(const TonemapSettings& s) {
  WtTonemapParams p{};
  p.op = s.op;
  p.flags = (s.autoExposure ? WT_TONEMAP_FLAG_AUTO_EXPOSURE : 0u) | (s.dither ? WT_TONEMAP_FLAG_DITHER : 0u);
  p.white = s.white > 0.0f ? s.white : defaultTonemapWhite(s.op);
  std::vector<double> m = s.whiteBalanceKelvin > 0.0f ? whiteBalanceMatrix(s.whiteBalanceKelvin)
                                                      : std::vector<double>{1, 0, 0, 0, 1, 0, 0, 0, 1};
  p.balance_r = {float(m[0]), float(m[1]), float(m[2]), 0.0f};
  p.balance_g = {float(m[3]), float(m[4]), float(m[5]), 0.0f};
  p.balance_b = {float(m[6]), float(m[7]), float(m[8]), 0.0f};
  return p;
}

Tonemapper::Tonemapper(Context& context, const cl::Program& program, ParamFeatures features, std::size_t pixels)
    : m_context(&context),
      m_logLuminance(program, features),
      m_exposure(program, features),
      m_tonemap(program, features) {
  const std::size_t chunks = std::max<std::size_t>(1, (pixels + WT_TONEMAP_CHUNK - 1) / WT_TONEMAP_CHUNK);
  m_partials = cl::Buffer(context.context(), CL_MEM_READ_WRITE, chunks * sizeof(float));
  m_scale = cl::Buffer(context.context(), CL_MEM_READ_WRITE, sizeof(float));
  context.fill(m_scale, 0x3f800000u, 0, sizeof(float));  // 1.0f until the first auto exposure
  m_logLuminance.set("partials", m_partials);
  m_exposure.set("partials", m_partials).set("exposure", m_scale);
  m_tonemap.set("exposure", m_scale);
}

void Tonemapper::run(const WtFrameParams& frame, const WtTonemapParams& params, const cl::Buffer& mean,
                     cl::Buffer& pixels) {
  const std::size_t count = std::size_t(frame.width) * frame.height;
  if (params.flags & WT_TONEMAP_FLAG_AUTO_EXPOSURE) {
    m_logLuminance.set("frame", frame).set("mean", mean);
    m_logLuminance.requireBound();
    m_context->launch("tonemap_log_luminance", m_logLuminance.kernel(),
                      (count + WT_TONEMAP_CHUNK - 1) / WT_TONEMAP_CHUNK);
    m_exposure.set("frame", frame);
    m_exposure.requireBound();
    m_context->launch("tonemap_exposure", m_exposure.kernel(), 1);
  }
  m_tonemap.set("frame", frame).set("tonemap", params).set("mean", mean).set("pixels", pixels);
  m_tonemap.requireBound();
  m_context->launch("tonemap", m_tonemap.kernel(), count);
}

float Tonemapper::autoExposure() {
  float scale = 0.0f;
  m_context->queue().enqueueReadBuffer(m_scale, CL_TRUE, 0, sizeof(float), &scale);
  return scale;
}

void tonemapImage(Context& context, Image& image, const TonemapSettings& s, float exposureStops,
                  float* autoExposure) {
  const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
  // the renderer's frame program: the same build a render loads
  static_assert(sizeof(cl_float4) == 16);
  cl::Program program = buildFrameProgram(context, false);
  std::vector<cl_float4> mean(pixels);
  for (std::size_t i = 0; i < pixels; ++i)
    mean[i] = {{image.rgb[3 * i], image.rgb[3 * i + 1], image.rgb[3 * i + 2], 1.0f}};
  cl::Buffer meanBuffer(context.context(), CL_MEM_READ_ONLY, std::max<std::size_t>(pixels, 1) * 16);
  cl::Buffer pixelBuffer(context.context(), CL_MEM_READ_WRITE, std::max<std::size_t>(pixels, 1) * 4);
  if (pixels > 0) context.queue().enqueueWriteBuffer(meanBuffer, CL_TRUE, 0, pixels * 16, mean.data());
  Tonemapper tonemapper(context, program, ParamFeatures{}, pixels);
  WtFrameParams frame{};
  frame.width = cl_uint(image.width);
  frame.height = cl_uint(image.height);
  frame.exposure = exposureScale(s, exposureStops);
  tonemapper.run(frame, tonemapParams(s), meanBuffer, pixelBuffer);
  image.srgba.resize(4 * pixels);
  if (pixels > 0) context.queue().enqueueReadBuffer(pixelBuffer, CL_TRUE, 0, pixels * 4, image.srgba.data());
  if (autoExposure) *autoExposure = s.autoExposure ? tonemapper.autoExposure() : 1.0f;
  context.finish();
}

}  // namespace wt
