// Where a render's time goes: per stage and bounce, from OpenCL profiling
// events (RenderSettings::profile, `wavetrace render --profile`), with the
// queue sizes of every bounce. The path counts are recorded always (the host
// reads them back anyway); the times only when asked, since profiling events
// need a queue made with CL_QUEUE_PROFILING_ENABLE.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace wt {

/// One bounce, summed over the sample passes that reached it.
struct BounceProfile {
  std::uint64_t passes = 0;      ///< sample passes that reached this bounce (some path alive)
  std::uint64_t paths = 0;       ///< paths extended and shaded (the queue's size)
  std::uint64_t shadowRays = 0;  ///< shadow rays shade queued for connect (timed profiles only)
  double extendSeconds = 0.0;    ///< kernel time (profiling events)
  double shadeSeconds = 0.0;
  double connectSeconds = 0.0;
  double transferSeconds = 0.0;  ///< counter fills and the count read-back, on the device
  double idleSeconds = 0.0;      ///< the device idle between this bounce's commands (waiting on the host)
};

struct RenderProfile {
  bool timed = false;          ///< the times below were measured (else only the counts)
  std::size_t pixels = 0;      ///< paths per sample pass
  int samples = 0;             ///< sample passes profiled
  int maxBounces = 0;
  double wallSeconds = 0.0;    ///< host wall time of the sample passes, profiling's own reads taken out
  double generateSeconds = 0.0, accumulateSeconds = 0.0;  ///< kernel time
  double otherIdleSeconds = 0.0;  ///< device idle before generate and accumulate
  double hostWaitSeconds = 0.0;   ///< host blocked in the count read-backs (kernels still running included)
  double profileReadSeconds = 0.0;  ///< profiling's own reads (the shadow queue's count), not in wallSeconds
  std::uint64_t kernelLaunches = 0, fills = 0, blockingReads = 0;
  std::vector<BounceProfile> bounces;

  double kernelSeconds() const;    ///< every kernel, every bounce
  double transferSeconds() const;  ///< fills and reads on the device
  double idleSeconds() const;      ///< device idle between commands
  /// Wall time outside every kernel: transfers, idle gaps, the host's own work.
  double outsideKernelSeconds() const { return wallSeconds - kernelSeconds(); }
  std::uint64_t raysTraced() const;  ///< extend rays and shadow rays
};

/// The --profile table: per bounce and stage, times, counts, rates, and the
/// share of wall time outside kernels.
std::string profileTable(const RenderProfile& p);
/// A few lines for --verbose: the path counts per bounce (and, when timed,
/// the kernel share of the wall time).
std::string profileSummary(const RenderProfile& p);
/// The profile as a JSON object (--profile-json; docs/command-line.md).
std::string profileJson(const RenderProfile& p);

}  // namespace wt
