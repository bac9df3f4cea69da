#include "render/render_profile.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>

namespace wt {

double RenderProfile::kernelSeconds() const {
  double s = generateSeconds + accumulateSeconds;
  for (const BounceProfile& b : bounces) s += b.extendSeconds + b.shadeSeconds + b.connectSeconds;
  return s;
}

double RenderProfile::transferSeconds() const {
  double s = 0.0;
  for (const BounceProfile& b : bounces) s += b.transferSeconds;
  return s;
}

double RenderProfile::idleSeconds() const {
  double s = otherIdleSeconds;
  for (const BounceProfile& b : bounces) s += b.idleSeconds;
  return s;
}

std::uint64_t RenderProfile::raysTraced() const {
  std::uint64_t n = 0;
  for (const BounceProfile& b : bounces) n += b.paths + b.shadowRays;
  return n;
}

namespace {

/// Millions per second; 0 where nothing was timed.
double rate(std::uint64_t count, double seconds) { return seconds > 0.0 ? double(count) / seconds * 1e-6 : 0.0; }
double percent(double part, double whole) { return whole > 0.0 ? 100.0 * part / whole : 0.0; }

std::string format(const char* fmt, auto... args) {
  char line[512];
  std::snprintf(line, sizeof line, fmt, args...);
  return line;
}

}  // namespace

std::string profileTable(const RenderProfile& p) {
  std::string out;
  const double n = double(std::max(p.samples, 1));
  out += format("profile: %d sample passes of %zu paths, up to %d bounces; %.3f s wall in the passes (%.2f ms a pass)\n",
                p.samples, p.pixels, p.maxBounces, p.wallSeconds, p.wallSeconds / n * 1e3);
  if (!p.timed) {
    out += "  (no stage times: the device queue has no profiling)\n";
  } else {
    const double kernels = p.kernelSeconds(), outside = p.outsideKernelSeconds();
    out += format("  kernels %.3f s (%.1f %%); outside kernels %.3f s (%.1f %%): fills and reads on the device %.3f s, "
                  "device idle between commands %.3f s, the rest (host enqueue and wake-up) %.3f s\n",
                  kernels, percent(kernels, p.wallSeconds), outside, percent(outside, p.wallSeconds),
                  p.transferSeconds(), p.idleSeconds(), outside - p.transferSeconds() - p.idleSeconds());
  }
  out += format("  per pass: %.1f kernel launches, %.1f fills, %.1f blocking reads; host blocked in reads %.3f s in all\n",
                double(p.kernelLaunches) / n, double(p.fills) / n, double(p.blockingReads) / n, p.hostWaitSeconds);
  out += "  bounce      paths  shadow rays   extend ms Mray/s    shade ms Mpath/s  connect ms Mray/s   xfer ms   idle ms\n";
  for (std::size_t b = 0; b < p.bounces.size(); ++b) {
    const BounceProfile& s = p.bounces[b];
    out += format("  %6zu %10llu %12llu %11.2f %6.2f %11.2f %7.2f %11.2f %6.2f %9.2f %9.2f\n", b,
                  (unsigned long long)s.paths, (unsigned long long)s.shadowRays, s.extendSeconds * 1e3,
                  rate(s.paths, s.extendSeconds), s.shadeSeconds * 1e3, rate(s.paths, s.shadeSeconds),
                  s.connectSeconds * 1e3, rate(s.shadowRays, s.connectSeconds), s.transferSeconds * 1e3,
                  s.idleSeconds * 1e3);
  }
  BounceProfile all;
  for (const BounceProfile& s : p.bounces) {
    all.paths += s.paths, all.shadowRays += s.shadowRays;
    all.extendSeconds += s.extendSeconds, all.shadeSeconds += s.shadeSeconds, all.connectSeconds += s.connectSeconds;
    all.transferSeconds += s.transferSeconds, all.idleSeconds += s.idleSeconds;
  }
  out += format("  %6s %10llu %12llu %11.2f %6.2f %11.2f %7.2f %11.2f %6.2f %9.2f %9.2f\n", "all",
                (unsigned long long)all.paths, (unsigned long long)all.shadowRays, all.extendSeconds * 1e3,
                rate(all.paths, all.extendSeconds), all.shadeSeconds * 1e3, rate(all.paths, all.shadeSeconds),
                all.connectSeconds * 1e3, rate(all.shadowRays, all.connectSeconds), all.transferSeconds * 1e3,
                all.idleSeconds * 1e3);
  const std::uint64_t paths = std::uint64_t(p.pixels) * std::uint64_t(p.samples);
  out += format("  generate %.2f ms (%.2f Mpath/s), accumulate %.2f ms (%.2f Mpath/s), idle around them %.2f ms\n",
                p.generateSeconds * 1e3, rate(paths, p.generateSeconds), p.accumulateSeconds * 1e3,
                rate(paths, p.accumulateSeconds), p.otherIdleSeconds * 1e3);
  if (p.timed) {
    const double k = p.kernelSeconds();
    out += format("  share of kernel time: generate %.1f %%, extend %.1f %%, shade %.1f %%, connect %.1f %%, accumulate %.1f %%\n",
                  percent(p.generateSeconds, k), percent(all.extendSeconds, k), percent(all.shadeSeconds, k),
                  percent(all.connectSeconds, k), percent(p.accumulateSeconds, k));
    out += format("  whole path: %.2f Mray/s (extend and shadow rays over the wall time)\n",
                  rate(p.raysTraced(), p.wallSeconds));
  }
  return out;
}

std::string profileSummary(const RenderProfile& p) {
  std::string counts;
  for (const BounceProfile& b : p.bounces)
    counts += format(" %.0f", p.samples > 0 ? double(b.paths) / double(p.samples) : 0.0);
  std::string out = "paths alive per bounce (mean over " + std::to_string(p.samples) + " passes):" + counts;
  if (p.timed)
    out += format("; kernels %.1f %% of %.3f s wall, outside kernels %.1f %%", percent(p.kernelSeconds(), p.wallSeconds),
                  p.wallSeconds, percent(p.outsideKernelSeconds(), p.wallSeconds));
  return out;
}

std::string profileJson(const RenderProfile& p) {
  nlohmann::ordered_json j;
  j["timed"] = p.timed;
  j["pixels"] = p.pixels;
  j["samples"] = p.samples;
  j["max_bounces"] = p.maxBounces;
  j["wall_seconds"] = p.wallSeconds;
  j["kernel_seconds"] = p.kernelSeconds();
  j["outside_kernel_seconds"] = p.outsideKernelSeconds();
  j["transfer_seconds"] = p.transferSeconds();
  j["idle_seconds"] = p.idleSeconds();
  j["host_wait_seconds"] = p.hostWaitSeconds;
  j["profile_read_seconds"] = p.profileReadSeconds;
  j["generate_seconds"] = p.generateSeconds;
  j["accumulate_seconds"] = p.accumulateSeconds;
  j["kernel_launches"] = p.kernelLaunches;
  j["fills"] = p.fills;
  j["blocking_reads"] = p.blockingReads;
  j["bounces"] = nlohmann::ordered_json::array();
  for (std::size_t b = 0; b < p.bounces.size(); ++b) {
    const BounceProfile& s = p.bounces[b];
    nlohmann::ordered_json e;
    e["bounce"] = b;
    e["passes"] = s.passes;
    e["paths"] = s.paths;
    e["shadow_rays"] = s.shadowRays;
    e["extend_seconds"] = s.extendSeconds;
    e["shade_seconds"] = s.shadeSeconds;
    e["connect_seconds"] = s.connectSeconds;
    e["transfer_seconds"] = s.transferSeconds;
    e["idle_seconds"] = s.idleSeconds;
    e["extend_mrays_per_second"] = rate(s.paths, s.extendSeconds);
    e["shade_mpaths_per_second"] = rate(s.paths, s.shadeSeconds);
    e["connect_mrays_per_second"] = rate(s.shadowRays, s.connectSeconds);
    j["bounces"].push_back(e);
  }
  return j.dump(2) + "\n";
}

}  // namespace wt
