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

ImageAgreement compareImages(const Image& a, const Image& b, int blocks) {
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("images differ in size: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                " and " + std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageAgreement result;
  auto block = [](const Image& img, int x0, int y0, int x1, int y1, int c, double* mean, double* varianceOfMean) {
    double sum = 0.0, var = 0.0;
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x, ++n) {
        std::size_t p = std::size_t(y) * img.width + x;
        sum += img.rgb[3 * p + c];
        var += img.rgbVariance[3 * p + c] / std::max<std::uint32_t>(img.samples[p], 1);
      }
    *mean = n ? sum / n : 0.0;
    *varianceOfMean = n ? var / (double(n) * n) : 0.0;
  };
  for (int by = 0; by < blocks; ++by)
    for (int bx = 0; bx < blocks; ++bx)
      for (int c = 0; c < 3; ++c) {
        int x0 = bx * a.width / blocks, x1 = (bx + 1) * a.width / blocks;
        int y0 = by * a.height / blocks, y1 = (by + 1) * a.height / blocks;
        double ma, va, mb, vb;
        block(a, x0, y0, x1, y1, c, &ma, &va);
        block(b, x0, y0, x1, y1, c, &mb, &vb);
        double se = std::sqrt(va + vb);
        if (se == 0.0) {
          result.exactMismatches += std::abs(ma - mb) > 1e-6 * std::max(1.0, std::abs(mb));
          continue;
        }
        ++result.tests;
        double z = std::abs(ma - mb) / se;
        if (!(z <= result.maxAbsZ)) {  // NaN z counts as the worst
          result.maxAbsZ = std::isnan(z) ? INFINITY : z;
          result.worstBlockX = bx, result.worstBlockY = by, result.worstChannel = c;
        }
      }
  return result;
}

double bonferroniZ(int tests, double alpha) {
  // P(|Z| > z) = erfc(z / sqrt 2) = alpha / tests, by bisection
  double target = alpha / std::max(tests, 1), lo = 0.0, hi = 40.0;
  for (int i = 0; i < 100; ++i) {
    double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace wt
