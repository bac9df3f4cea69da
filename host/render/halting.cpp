#include "render/halting.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace wt {

double estimatedRelMse(const Image& image) {
  const std::size_t pixels = std::size_t(image.width) * std::size_t(image.height);
  if (pixels == 0 || image.samples.size() != pixels || image.rgbVariance.size() != 3 * pixels)
    return std::numeric_limits<double>::infinity();
  // the 0.01 as ImageError::relMse has it: dark pixels do not dominate
  const double kEpsilon = 0.01;
  double sum = 0.0;
  for (std::size_t p = 0; p < pixels; ++p) {
    const std::uint32_t n = image.samples[p];
    if (n < 2) return std::numeric_limits<double>::infinity();
    for (int c = 0; c < 3; ++c) {
      const double x = image.rgb[3 * p + c];
      sum += double(image.rgbVariance[3 * p + c]) / n / (x * x + kEpsilon);
    }
  }
  return sum / (3.0 * double(pixels));
}

Halting::Halting(const HaltCriteria& criteria, int samplesDone) : m_criteria(criteria) {
  m_nextCheck = std::max(kMinSamplesForErrorEstimate, samplesDone + 1);
}

bool Halting::wantsErrorEstimate(int samplesDone) const {
  return m_criteria.targetError > 0.0 && samplesDone >= m_nextCheck;
}

void Halting::recordError(int samplesDone, double relError, double readSeconds, double secondsPerSample) {
  m_lastError = relError;
  m_lastErrorSamples = samplesDone;
  ++m_checks;
  m_checkSeconds += readSeconds;
  // Space read-backs so that they cost at most kErrorCheckShare of the
  // passes between them, by the cheapest one seen: the first includes
  // building the resolve kernel, so the second follows at once.
  m_minReadSeconds = m_checks == 1 ? readSeconds : std::min(m_minReadSeconds, readSeconds);
  int spacing = 1;
  if (secondsPerSample > 0.0 && m_checks > 1)
    spacing = int(std::clamp(std::ceil(m_minReadSeconds / (kErrorCheckShare * secondsPerSample)), 1.0, 1e6));
  int next = samplesDone + spacing;
  // the error falls as 1/sqrt(n): look again where that trend crosses the target, if sooner
  if (m_criteria.targetError > 0.0 && std::isfinite(relError) && relError > m_criteria.targetError) {
    const double ratio = relError / m_criteria.targetError;
    const double crossing = std::ceil(double(samplesDone) * ratio * ratio);
    if (crossing < double(next)) next = std::max(samplesDone + 1, int(crossing));
  }
  m_nextCheck = next;
}

HaltReason Halting::check(int samplesDone, double seconds) const {
  if (samplesDone >= m_criteria.samplesPerPixel) return HaltReason::Samples;
  if (m_criteria.targetError > 0.0 && m_lastErrorSamples == samplesDone && m_lastError >= 0.0 &&
      m_lastError < m_criteria.targetError)
    return HaltReason::TargetError;
  if (m_criteria.seconds > 0.0 && seconds >= m_criteria.seconds) return HaltReason::Time;
  return HaltReason::None;
}

double Halting::eta(int samplesDone, double seconds, double secondsPerSample) const {
  double best = -1.0;
  auto offer = [&](double t) {
    if (t >= 0.0 && std::isfinite(t) && (best < 0.0 || t < best)) best = t;
  };
  if (secondsPerSample > 0.0 && m_criteria.samplesPerPixel < kUnboundedSamples)
    offer((m_criteria.samplesPerPixel - samplesDone) * secondsPerSample);
  if (m_criteria.seconds > 0.0) offer(std::max(0.0, m_criteria.seconds - seconds));
  if (m_criteria.targetError > 0.0 && m_lastError > 0.0 && secondsPerSample > 0.0) {
    const double ratio = m_lastError / m_criteria.targetError;
    offer(std::max(0.0, m_lastErrorSamples * ratio * ratio - samplesDone) * secondsPerSample);
  }
  return best;
}

std::string formatDuration(double seconds) {
  char text[64];
  if (seconds < 60.0)
    std::snprintf(text, sizeof text, "%.1f s", seconds);
  else if (seconds < 3600.0)
    std::snprintf(text, sizeof text, "%d min %02d s", int(seconds / 60.0), int(std::fmod(seconds, 60.0)));
  else
    std::snprintf(text, sizeof text, "%d h %02d min", int(seconds / 3600.0), int(std::fmod(seconds, 3600.0) / 60.0));
  return text;
}

std::string progressLine(const Halting& halting, int samplesDone, double mraysPerSecond, double seconds,
                         double secondsPerSample, bool final) {
  const HaltCriteria& c = halting.criteria();
  char text[256];
  std::string line = "sample " + std::to_string(samplesDone);
  if (c.samplesPerPixel < kUnboundedSamples) {
    line += '/';  // appended apart: GCC 12 warns (-Wrestrict, falsely) on "/" + std::string at -O3
    line += std::to_string(c.samplesPerPixel);
  }
  std::snprintf(text, sizeof text, "  %.2f Mrays/s  %s", mraysPerSecond, formatDuration(seconds).c_str());
  line += text;
  if (halting.lastError() >= 0.0) {
    std::snprintf(text, sizeof text, "  error %.4f", halting.lastError());
    line += text;
    if (c.targetError > 0.0) {
      std::snprintf(text, sizeof text, " (target %g)", c.targetError);
      line += text;
    }
  }
  const double eta = halting.eta(samplesDone, seconds, secondsPerSample);
  if (eta >= 0.0 && !final) line += "  ETA " + formatDuration(eta);
  return line;
}

}  // namespace wt
