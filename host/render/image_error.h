// Error of a render against a reference image, for the error-versus-time
// instrument (scripts/error-vs-time) and tests.
#pragma once

#include "render/renderer.h"

#include <stdexcept>

namespace wt {

struct ImageError {
  double rmse = 0.0;         ///< root mean squared error over all pixels and channels
  double relMse = 0.0;       ///< mean of (x - r)^2 / (r^2 + 0.01) over pixels and channels, less the reference's own noise when known
  double relMseRaw = 0.0;    ///< the same without subtracting the reference's noise
  double p99 = 0.0;          ///< 99th percentile of the per-pixel relative error sqrt(relMSE of the pixel)
  double meanRatio = 0.0;    ///< mean(image) / mean(reference): a bias check
};

/// Compare `image` with `reference` (same size, else std::invalid_argument).
/// When the reference carries the variance of its pixel means (rgbVariance /
/// samples), its expected contribution to the squared error is subtracted:
/// E[(x - r)^2] = E[(x - mu)^2] + Var(r) for independent x and r.
ImageError imageError(const Image& image, const Image& reference);

/// Two independent renders of what should be the same image, compared block
/// by block: the difference of each block's channel means in standard errors
/// of that difference, from the per-pixel sample variances.
struct ImageAgreement {
  double maxAbsZ = 0.0;     ///< largest |z| over blocks and channels
  int tests = 0;            ///< block-channel pairs with variance, compared by z
  int exactMismatches = 0;  ///< pairs without variance in either image whose means differ (1e-6 relative)
  int worstBlockX = 0, worstBlockY = 0, worstChannel = 0;
};

/// Compare a and b (same size, else std::invalid_argument) over blocks x blocks regions.
ImageAgreement compareImages(const Image& a, const Image& b, int blocks);

/// Two-sided |z| that `tests` independent standard normal comparisons exceed
/// with total probability `alpha` (Bonferroni): the limit for
/// ImageAgreement::maxAbsZ that makes a false alarm that rare.
double bonferroniZ(int tests, double alpha);

}  // namespace wt
