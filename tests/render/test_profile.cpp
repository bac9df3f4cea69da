// The render profile (RenderSettings::profile, `render --profile`): its
// structure and the identities its counts and times must satisfy.
#include "device_fixture.h"
#include "render/render_profile.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

namespace wt {
namespace {

constexpr int kSpp = 4;

RenderSettings profileSettings(bool profile, bool packets = true) {
  RenderSettings s;
  s.width = 24;
  s.height = 16;
  s.maxBounces = 4;
  s.seed = 3;
  s.packets = packets;
  s.profile = profile;
  return s;
}

struct Rendered {
  RenderProfile profile;
  RenderStats stats;
  Image image;
};

Rendered renderProfiled(const RenderSettings& settings) {
  Renderer renderer(test::deviceContext(), loadDefaultScene(), settings);
  for (int s = 0; s < kSpp; ++s) renderer.renderSample();
  return {renderer.profile(), renderer.stats(), renderer.readImage()};
}

/// The identities of any profile of kSpp passes of `settings`.
void expectConsistent(const RenderProfile& p, const RenderSettings& settings, const RenderStats& stats) {
  const std::uint64_t pixels = std::uint64_t(settings.width) * std::uint64_t(settings.height);
  EXPECT_EQ(p.pixels, pixels);
  EXPECT_EQ(p.samples, kSpp);
  ASSERT_GE(p.bounces.size(), 1u);
  ASSERT_LE(p.bounces.size(), std::size_t(settings.maxBounces) + 1);
  // every pass starts one path per pixel
  EXPECT_EQ(p.bounces[0].paths, pixels * kSpp);
  EXPECT_EQ(p.bounces[0].passes, std::uint64_t(kSpp));
  std::uint64_t paths = 0, passes = 0, launches = 2 * std::uint64_t(kSpp);  // generate and accumulate
  for (std::size_t b = 0; b < p.bounces.size(); ++b) {
    const BounceProfile& s = p.bounces[b];
    SCOPED_TRACE("bounce " + std::to_string(b));
    // a path enters the next queue at most once: counts never grow
    if (b > 0) {
      EXPECT_LE(s.paths, p.bounces[b - 1].paths);
      EXPECT_LE(s.passes, p.bounces[b - 1].passes);
    }
    EXPECT_GT(s.passes, 0u);
    EXPECT_GE(s.paths, s.passes);  // a pass reaches a bounce only with some path alive
    // at most one shadow ray per shaded path, none at the last bounce (emission only)
    EXPECT_LE(s.shadowRays, s.paths);
    if (int(b) == settings.maxBounces) {
      EXPECT_EQ(s.shadowRays, 0u);
    }
    paths += s.paths;
    passes += s.passes;
    const bool connect = int(b) < settings.maxBounces;  // the box has a light: NEE at every bounce but the last
    launches += s.passes * (connect ? 3 : 2);
  }
  EXPECT_EQ(paths, stats.raysTraced);
  EXPECT_EQ(p.kernelLaunches, launches);
  EXPECT_EQ(p.blockingReads, passes);  // one count read-back per bounce of a pass
}

TEST(RenderProfile, TimedProfileIsConsistent) {
  for (bool packets : {true, false}) {
    SCOPED_TRACE(packets ? "packets" : "single rays");
    const RenderSettings settings = profileSettings(true, packets);
    Rendered r = renderProfiled(settings);
    const RenderProfile& p = r.profile;
    ASSERT_TRUE(p.timed);
    expectConsistent(p, settings, r.stats);
    // the box's light is in view of most camera hits: NEE makes shadow rays
    EXPECT_GT(p.bounces[0].shadowRays, 0u);
    // every stage that ran took time; the device's commands fit in the wall time
    EXPECT_GT(p.generateSeconds, 0.0);
    EXPECT_GT(p.accumulateSeconds, 0.0);
    for (const BounceProfile& s : p.bounces) {
      EXPECT_GT(s.extendSeconds, 0.0);
      EXPECT_GT(s.shadeSeconds, 0.0);
      EXPECT_GE(s.transferSeconds, 0.0);
      EXPECT_GE(s.idleSeconds, 0.0);
    }
    EXPECT_GT(p.wallSeconds, 0.0);
    EXPECT_LE(p.kernelSeconds() + p.transferSeconds() + p.idleSeconds(), p.wallSeconds);
    EXPECT_GE(p.outsideKernelSeconds(), 0.0);
    EXPECT_EQ(p.raysTraced(), r.stats.raysTraced + [&] {
      std::uint64_t n = 0;
      for (const BounceProfile& s : p.bounces) n += s.shadowRays;
      return n;
    }());
  }
}

TEST(RenderProfile, CountsWithoutTimesAndTheSameImage) {
  // off, the profile holds the counts only, and profiling changes no pixel
  const RenderSettings off = profileSettings(false), on = profileSettings(true);
  Rendered plain = renderProfiled(off), timed = renderProfiled(on);
  EXPECT_FALSE(plain.profile.timed);
  expectConsistent(plain.profile, off, plain.stats);
  ASSERT_EQ(plain.profile.bounces.size(), timed.profile.bounces.size());
  for (std::size_t b = 0; b < plain.profile.bounces.size(); ++b) {
    EXPECT_EQ(plain.profile.bounces[b].paths, timed.profile.bounces[b].paths) << "bounce " << b;
    EXPECT_EQ(plain.profile.bounces[b].shadowRays, 0u);  // counted only when profiling
    EXPECT_EQ(plain.profile.bounces[b].extendSeconds, 0.0);
  }
  EXPECT_EQ(plain.image.rgb, timed.image.rgb);
}

TEST(RenderProfile, NeedsAProfilingQueue) {
  Context plain(selectDevice(""), /*profiling=*/false);
  EXPECT_FALSE(plain.profiling());
  EXPECT_THROW(Renderer(plain, loadDefaultScene(), profileSettings(true)), DeviceError);
}

TEST(RenderProfile, JsonHoldsTheTable) {
  const RenderSettings settings = profileSettings(true);
  Rendered r = renderProfiled(settings);
  const nlohmann::json j = nlohmann::json::parse(profileJson(r.profile));
  EXPECT_EQ(j.at("timed").get<bool>(), true);
  EXPECT_EQ(j.at("samples").get<int>(), kSpp);
  EXPECT_EQ(j.at("pixels").get<std::uint64_t>(), r.profile.pixels);
  EXPECT_DOUBLE_EQ(j.at("wall_seconds").get<double>(), r.profile.wallSeconds);
  EXPECT_DOUBLE_EQ(j.at("kernel_seconds").get<double>(), r.profile.kernelSeconds());
  const auto& bounces = j.at("bounces");
  ASSERT_EQ(bounces.size(), r.profile.bounces.size());
  for (std::size_t b = 0; b < bounces.size(); ++b) {
    EXPECT_EQ(bounces[b].at("bounce").get<std::size_t>(), b);
    EXPECT_EQ(bounces[b].at("paths").get<std::uint64_t>(), r.profile.bounces[b].paths);
    EXPECT_EQ(bounces[b].at("shadow_rays").get<std::uint64_t>(), r.profile.bounces[b].shadowRays);
    EXPECT_DOUBLE_EQ(bounces[b].at("shade_seconds").get<double>(), r.profile.bounces[b].shadeSeconds);
  }
  // the table names every bounce and the share outside kernels
  const std::string table = profileTable(r.profile);
  EXPECT_NE(table.find("outside kernels"), std::string::npos);
  EXPECT_NE(table.find("share of kernel time"), std::string::npos);
}

}  // namespace
}  // namespace wt
