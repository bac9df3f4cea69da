// The tonemap stage on the host side: settings (operator, exposure, white
// balance, dither), their device parameters, and Tonemapper, which runs the
// auto-exposure reduction and the tonemap kernel over a mean image on the
// device, for the renderer and for `wavetrace tonemap` (an EXR to a PNG).
// The operators themselves: kernels/shared/tonemap.h; docs/tonemapping.md.
#pragma once

#include "device/context.h"
#include "device/kernel_args.h"
#include "render/stage_params.h"
#include "render/tonemap_names.h"
#include "shared/tonemap.h"
#include "shared/types.h"

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace wt {

struct Image;

struct TonemapSettings {
  std::uint32_t op = WT_TONEMAP_PBR_NEUTRAL;  ///< WT_TONEMAP_*; PBR Neutral: made for glTF's base colours
  bool autoExposure = false;  ///< scale the image's log-average luminance to middle grey (0.18) on the device
  /// Physical camera (Falcor's ToneMapper): scale ISO t / (100 N^2) = 2^-EV100;
  /// the defaults (f/1, 1 s, ISO 100) give 1
  float fNumber = 1.0f;
  float shutterSeconds = 1.0f;
  float iso = 100.0f;
  float white = 0.0f;        ///< reinhard-modified / hable white; 0: the operator's default
  float whiteBalanceKelvin = 0.0f;  ///< colour temperature the image is balanced from; 0: none
  bool dither = true;        ///< dither before the 8-bit quantisation
};

/// The white an operator uses when TonemapSettings::white is 0: 4 for
/// reinhard-modified (luminance 4 maps to 1), 11.2 for hable (Falcor's linear white).
float defaultTonemapWhite(std::uint32_t op);

/// 2^-EV100 with EV100 = log2(N^2 / t * 100 / ISO): the physical camera's scale.
double physicalExposureScale(double fNumber, double shutterSeconds, double iso);

/// The frame's exposure scale: 2^stops times the physical camera's.
float exposureScale(const TonemapSettings& s, float exposureStops);

/// The 3x3 (row-major) Rec.709 matrix that white-balances light of colour
/// temperature `kelvin` to D65 white: von Kries in CAT02 LMS, with the
/// blackbody's chromaticity from Kang et al. 2002 (as Falcor); identity at 6500 K.
std::vector<double> whiteBalanceMatrix(double kelvin);

/// The chromaticity (x, y) of a blackbody at `kelvin` (1667-25000 K).
std::pair<double, double> blackbodyChromaticity(double kelvin);

/// The tonemap kernel's parameters for the settings.
WtTonemapParams tonemapParams(const TonemapSettings& s);

/// The stage's three kernels over one image size: the log-luminance
/// partial sums and the exposure they give (when auto), then tonemap.
class Tonemapper {
 public:
  Tonemapper() = default;
  Tonemapper(Context& context, const cl::Program& program, ParamFeatures features, std::size_t pixels);

  /// Tone-map `mean` (float4 per pixel) into `pixels` (uchar4), in queue order.
  void run(const WtFrameParams& frame, const WtTonemapParams& params, const cl::Buffer& mean, cl::Buffer& pixels);
  /// The auto exposure the last run computed (waits for the queue).
  float autoExposure();

 private:
  Context* m_context = nullptr;
  KernelArgs<stage::LogLuminance> m_logLuminance;
  KernelArgs<stage::TonemapExposure> m_exposure;
  KernelArgs<stage::Tonemap> m_tonemap;
  cl::Buffer m_partials;  ///< float per WT_TONEMAP_CHUNK pixels
  cl::Buffer m_scale;     ///< float: the auto exposure
};

/// Tone-map a linear image (rgb) on the device, building the tonemap
/// program; fills image.srgba. For `wavetrace tonemap` and the tests.
void tonemapImage(Context& context, Image& image, const TonemapSettings& s, float exposureStops,
                  float* autoExposure = nullptr);

}  // namespace wt
