// wt_render_ab: two render configurations of one scene, A and B, timed
// side by side in one process -- their sample passes interleaved (A B B A
// A B ...), so that a machine shared with other work slows both alike --
// and, given a reference, the error of each, for the efficiency
// 1 / (relMSE x time). The lever measurements of
// docs/lab/2026-12-05-render-profile.md.
//
//   wt_render_ab [SCENE] [--width W --height H --spp N --max-bounces B --seed S]
//                [--reference REF.exr] [--rounds R]
//                [--a-OPTION V | --b-OPTION V ...]
//
// Per-configuration options (prefix --a- or --b-): kernel-dir DIR (kernels
// from that folder), rr-depth D, sampler independent|sobol, rr 0|1,
// lambertian-forms 0|1 (RenderSettings::lambertianForms), quad-lights 0|1
// (RenderSettings::quadLights), shade-lanes 0|1 (RenderSettings::shadeLanes),
// shade-lanes-width 0|8|16 (RenderSettings::shadeLanesWidth), power-heuristic 0|1
// (RenderSettings::powerHeuristic), power-lambertian 0|1 (RenderSettings::powerAtLambertian),
// shadow-traversal auto|single|packet|stream (RenderSettings::shadowTraversal: every bounce's shadow rays).
// extend-traversal auto|single|packet (RenderSettings::extendTraversal: bounces after the first).
#include "device/context.h"
#include "device/program.h"
#include "output/image_io.h"
#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/default_scene.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

struct Config {
  std::string kernelDir;
  wt::RenderSettings settings;
  std::string describe;
};

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr, "wt_render_ab: %s\n(see host/tools/render_ab.cpp)\n", why.c_str());
  std::exit(2);
}

int toInt(const std::string& option, const std::string& v) {
  try {
    std::size_t used = 0;
    int n = std::stoi(v, &used);
    if (used == v.size()) return n;
  } catch (const std::exception&) {
  }
  usage(option + ": '" + v + "' is not an integer");
}

void setOption(Config& c, const std::string& name, const std::string& v) {
  if (name == "kernel-dir") c.kernelDir = v;
  else if (name == "rr-depth") c.settings.rrMinDepth = toInt(name, v);
  else if (name == "rr") c.settings.useRussianRoulette = toInt(name, v) != 0;
  else if (name == "lambertian-forms") c.settings.lambertianForms = toInt(name, v) != 0;
  else if (name == "quad-lights") c.settings.quadLights = toInt(name, v) != 0;
  else if (name == "shade-lanes") c.settings.shadeLanes = toInt(name, v) != 0;
  else if (name == "shade-lanes-width") c.settings.shadeLanesWidth = toInt(name, v);
  else if (name == "power-heuristic") c.settings.powerHeuristic = toInt(name, v) != 0;
  else if (name == "power-lambertian") c.settings.powerAtLambertian = toInt(name, v) != 0;
  else if (name == "shadow-traversal") {
    if (v == "single") c.settings.shadowTraversal = wt::Traversal::kSingle;
    else if (v == "packet") c.settings.shadowTraversal = wt::Traversal::kPacket;
    else if (v == "stream") c.settings.shadowTraversal = wt::Traversal::kStream;
    else if (v != "auto") usage("--shadow-traversal: auto, single, packet or stream");
  } else if (name == "extend-traversal") {
    if (v == "single") c.settings.extendTraversal = wt::Traversal::kSingle;
    else if (v == "packet") c.settings.extendTraversal = wt::Traversal::kPacket;
    else if (v != "auto") usage("--extend-traversal: auto, single or packet");
  } else if (name == "sampler") {
    if (v != "independent" && v != "sobol") usage("--sampler: independent or sobol");
    c.settings.sobol = v == "sobol";
  } else usage("unknown option --a-" + name);
  c.describe += " --" + name + " " + v;
}

}  // namespace

int main(int argc, char** argv) {
  std::string sceneName;
  std::string reference;
  int rounds = 16;
  wt::RenderSettings common;
  common.width = 256;
  common.height = 256;
  common.samplesPerPixel = 16;
  std::vector<std::pair<std::string, std::string>> perConfig[2];
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    if (a == "--width") common.width = toInt(a, value());
    else if (a == "--height") common.height = toInt(a, value());
    else if (a == "--spp") common.samplesPerPixel = toInt(a, value());
    else if (a == "--max-bounces") common.maxBounces = toInt(a, value());
    else if (a == "--seed") common.seed = std::uint32_t(toInt(a, value()));
    else if (a == "--rounds") rounds = toInt(a, value());
    else if (a == "--reference") reference = value();
    else if (a.rfind("--a-", 0) == 0) perConfig[0].emplace_back(a.substr(4), value());
    else if (a.rfind("--b-", 0) == 0) perConfig[1].emplace_back(a.substr(4), value());
    else if (a.rfind("--", 0) == 0) usage("unknown option " + a);
    else sceneName = a;
  }
  if (rounds < 1 || common.samplesPerPixel < 1) usage("--rounds and --spp must be positive");

  try {
    wt::SceneFile loaded = sceneName.empty() ? wt::SceneFile{wt::loadDefaultScene(), {}} : wt::loadSceneAny(sceneName);
    wt::Context context(wt::selectDevice(""));
    Config configs[2];
    std::unique_ptr<wt::Renderer> renderers[2];
    for (int c = 0; c < 2; ++c) {
      configs[c].settings = common;
      for (const auto& [name, v] : perConfig[c]) setOption(configs[c], name, v);
      const std::optional<std::filesystem::path> before = wt::kernelDirectory();
      if (!configs[c].kernelDir.empty()) wt::setKernelDirectory(std::filesystem::path(configs[c].kernelDir));
      renderers[c] = std::make_unique<wt::Renderer>(context, loaded.scene, configs[c].settings);
      wt::setKernelDirectory(before);
      // a pass each, untimed: PoCL compiles each kernel at its first launch
      renderers[c]->renderSample();
    }
    std::optional<wt::Image> ref;
    if (!reference.empty()) ref = wt::readExr(reference);

    // Each round renders spp passes of each, from a fresh accumulation
    // (sample indices of its own: independent rounds for the error), in
    // alternating order; the per-round ratio B/A of the pass times.
    const wt::Accumulation fresh = [&] {
      wt::Accumulation a = renderers[0]->saveAccumulation();
      std::fill(a.state.begin(), a.state.end(), std::uint8_t(0));
      std::fill(a.samples.begin(), a.samples.end(), 0u);
      a.nonFiniteSamples = 0;
      return a;
    }();
    std::vector<double> ratios;
    double total[2] = {0.0, 0.0};
    double relMse[2] = {0.0, 0.0};
    for (int r = 0; r < rounds; ++r) {
      double seconds[2] = {0.0, 0.0};
      wt::Accumulation start = fresh;
      start.samplesDone = 1 + r * common.samplesPerPixel;
      for (int c = 0; c < 2; ++c) renderers[c]->restoreAccumulation(start);
      for (int p = 0; p < common.samplesPerPixel; ++p) {
        const int first = (p + r) % 2;
        for (int k = 0; k < 2; ++k) {
          const int c = k == 0 ? first : 1 - first;
          const auto t0 = std::chrono::steady_clock::now();
          renderers[c]->renderSample();
          seconds[c] += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
      }
      for (int c = 0; c < 2; ++c) {
        total[c] += seconds[c];
        if (ref) relMse[c] += wt::imageError(renderers[c]->readRadiance(), *ref).relMse / rounds;
      }
      ratios.push_back(seconds[1] / seconds[0]);
      std::printf("round %d: A %.3f s, B %.3f s, B/A %.3f\n", r, seconds[0], seconds[1], ratios.back());
      std::fflush(stdout);
    }
    std::sort(ratios.begin(), ratios.end());
    const double median = ratios[ratios.size() / 2];
    std::printf("A:%s\nB:%s\n", configs[0].describe.empty() ? " (defaults)" : configs[0].describe.c_str(),
                configs[1].describe.empty() ? " (defaults)" : configs[1].describe.c_str());
    std::printf("time: A %.3f s, B %.3f s over %d rounds of %d passes; B/A %.3f (median round %.3f, %.3f-%.3f)\n",
                total[0], total[1], rounds, common.samplesPerPixel, total[1] / total[0], median, ratios.front(),
                ratios.back());
    {
      // the last round's images: the same samples of the same paths, so a
      // traversal change that finds the same hits leaves them equal bit for bit
      const wt::Image ia = renderers[0]->readRadiance(), ib = renderers[1]->readRadiance();
      std::size_t differ = 0;
      for (std::size_t i = 0; i < std::min(ia.rgb.size(), ib.rgb.size()); ++i)
        differ += std::memcmp(&ia.rgb[i], &ib.rgb[i], sizeof(float)) != 0;
      std::printf("last round's radiance: %zu of %zu values differ between A and B\n", differ, ia.rgb.size());
    }
    if (ref) {
      const double effA = 1.0 / (relMse[0] * total[0]), effB = 1.0 / (relMse[1] * total[1]);
      std::printf("relMSE (mean over rounds): A %.4g, B %.4g, B/A %.3f; efficiency 1/(relMSE t) B/A %.3f\n", relMse[0],
                  relMse[1], relMse[1] / relMse[0], effB / effA);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "wt_render_ab: %s\n", e.what());
    return 1;
  }
  return 0;
}
