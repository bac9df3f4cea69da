// When a render stops (a sample count, a time budget, an estimated error,
// whichever comes first), the error estimate the last needs, and the
// progress line. The render loop itself is the command line's (host/cli).
#pragma once

#include "render/renderer.h"

#include <string>

namespace wt {

/// The estimated relative mean squared error of an image's pixel means:
/// the mean over pixels and channels of Var(mean) / (mean^2 + 0.01), with
/// Var(mean) = sample variance / samples of the pixel. The same quantity as
/// ImageError::relMse against a converged reference (render/image_error.h),
/// estimated from the render's own per-pixel variance; sqrt of it is the
/// RMS relative error of a pixel (--target-error compares that). Pixels
/// with fewer than 2 samples have no variance: +infinity.
double estimatedRelMse(const Image& image);

/// Samples before --target-error may stop a render: with fewer, a pixel
/// that has not yet met a rare bright path reports a variance of 0, and
/// the estimate is too low.
constexpr int kMinSamplesForErrorEstimate = 16;

/// Largest share of render time the error read-backs may take.
constexpr double kErrorCheckShare = 0.02;

/// The sample count of a render only --time or --target-error bounds (the
/// --spp limit).
constexpr int kUnboundedSamples = 1 << 24;

struct HaltCriteria {
  int samplesPerPixel = 64;  ///< total, counting samples of a resumed checkpoint
  double seconds = 0.0;      ///< stop after the pass that crosses this many seconds of rendering; 0: no limit
  double targetError = 0.0;  ///< stop when sqrt(estimatedRelMse) < this; 0: no target
};

enum class HaltReason { None, Samples, Time, TargetError };

/// Decides after each pass whether to stop, and when to estimate the
/// error: read-backs spaced so that they cost at most kErrorCheckShare of
/// the render time (by the cheapest read-back seen, from the second on),
/// and earlier when the error's 1/sqrt(n) trend says the target will be
/// crossed before then.
class Halting {
 public:
  /// `samplesDone`: samples already accumulated (a resumed checkpoint's).
  Halting(const HaltCriteria& criteria, int samplesDone);

  /// Whether the error should be estimated now (target set, enough samples, due).
  bool wantsErrorEstimate(int samplesDone) const;
  /// An estimate made after `samplesDone` samples; `readSeconds`: what it
  /// cost; `secondsPerSample`: the mean pass time so far.
  void recordError(int samplesDone, double relError, double readSeconds, double secondsPerSample);

  /// Why to stop after a pass (None: go on). `seconds`: rendering time in
  /// this process so far.
  HaltReason check(int samplesDone, double seconds) const;

  /// Seconds left by the nearest criterion (-1: unknown).
  double eta(int samplesDone, double seconds, double secondsPerSample) const;

  /// The last estimate (-1: none yet) and the samples it was made at.
  double lastError() const { return m_lastError; }
  int lastErrorSamples() const { return m_lastErrorSamples; }
  int errorChecks() const { return m_checks; }
  double errorCheckSeconds() const { return m_checkSeconds; }
  const HaltCriteria& criteria() const { return m_criteria; }

 private:
  HaltCriteria m_criteria;
  int m_nextCheck = kMinSamplesForErrorEstimate;
  double m_lastError = -1.0;
  int m_lastErrorSamples = 0;
  int m_checks = 0;
  double m_checkSeconds = 0.0;
  double m_minReadSeconds = 0.0;
};

/// "12.5 s", "3 min 05 s", "1 h 02 min".
std::string formatDuration(double seconds);

/// The progress line: samples done (of the count when one bounds the
/// render), Mrays/s, elapsed time, the last error estimate, and the ETA
/// (not on the `final` line).
std::string progressLine(const Halting& halting, int samplesDone, double mraysPerSecond, double seconds,
                         double secondsPerSample, bool final = false);

}  // namespace wt
