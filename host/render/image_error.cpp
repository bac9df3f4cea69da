#include "render/image_error.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace wt {

ImageError imageError(const Image& image, const Image& reference) {
  if (image.width != reference.width || image.height != reference.height)
    throw std::invalid_argument("reference is " + std::to_string(reference.width) + "x" +
                                std::to_string(reference.height) + ", the render " +
                                std::to_string(image.width) + "x" + std::to_string(image.height));
  const std::size_t pixels = std::size_t(image.width) * image.height;
  ImageError e;
  if (pixels == 0) return e;
  // the 0.01 keeps dark reference pixels from dominating the relative error
  const double kEpsilon = 0.01;
  std::vector<double> perPixel(pixels);
  double sumSq = 0.0, sumRel = 0.0, sumImage = 0.0, sumRef = 0.0, sumRefNoise = 0.0;
  const bool refVariance = reference.rgbVariance.size() == reference.rgb.size() && reference.samples.size() == pixels;
  for (std::size_t p = 0; p < pixels; ++p) {
    double rel = 0.0;
    for (int c = 0; c < 3; ++c) {
      double x = image.rgb[3 * p + c], r = reference.rgb[3 * p + c];
      double d2 = (x - r) * (x - r);
      sumSq += d2;
      rel += d2 / (r * r + kEpsilon);
      if (refVariance && reference.samples[p] > 0)
        sumRefNoise += reference.rgbVariance[3 * p + c] / reference.samples[p] / (r * r + kEpsilon);
      sumImage += x;
      sumRef += r;
    }
    sumRel += rel;
    perPixel[p] = std::sqrt(rel / 3.0);
  }
  e.rmse = std::sqrt(sumSq / (3.0 * pixels));
  e.relMseRaw = sumRel / (3.0 * pixels);
  e.relMse = (sumRel - sumRefNoise) / (3.0 * pixels);
  std::size_t k = std::min(pixels - 1, std::size_t(0.99 * double(pixels)));
  std::nth_element(perPixel.begin(), perPixel.begin() + k, perPixel.end());
  e.p99 = perPixel[k];
  e.meanRatio = sumRef > 0.0 ? sumImage / sumRef : 0.0;
  return e;
}

}  // namespace wt
