// What every harness checks of a load that returned: the invariants the
// renderer relies on downstream, so a loader that accepts bad input without
// crashing still fails the fuzzer. A violated check aborts (libFuzzer saves
// the input as a crash).
#pragma once

#include "scene/environment.h"
#include "scene/scene.h"

#include <sanitizer/common_interface_defs.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace wt::fuzz {

/// Report through the sanitizer (which still prints under -close_fd_mask=2) and abort.
[[noreturn]] inline void violated(const char* what, const std::string& detail = "") {
  const std::string text = std::string("fuzz invariant violated: ") + what + (detail.empty() ? "" : ": " + detail);
  __sanitizer_report_error_summary(text.c_str());
  std::abort();
}

#define WT_FUZZ_CHECK(condition, detail) \
  do {                                   \
    if (!(condition)) ::wt::fuzz::violated(#condition, detail); \
  } while (0)

inline bool finite3(const WtVec4& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
inline bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

/// An empty folder of our own, for external buffer URIs to resolve against.
inline const std::string& emptyBaseDir() {
  static const std::string dir = [] {
    auto path = std::filesystem::temp_directory_path() / "wt_fuzz_gltf_base";
    std::filesystem::create_directories(path);
    return path.string();
  }();
  return dir;
}

/// An error names the file first: "<name>: ...". WT_FUZZ_PRINT=1 prints it
/// (to see what a saved input does: fuzz_exr -runs=1 FILE).
inline void checkMessage(const std::string& what, const std::string& name) {
  static const bool print = std::getenv("WT_FUZZ_PRINT") != nullptr;
  if (print) std::fprintf(stderr, "error: %s\n", what.c_str());
  WT_FUZZ_CHECK(what.rfind(name + ": ", 0) == 0, what);
  WT_FUZZ_CHECK(what.size() > name.size() + 2, what);
}

inline void checkScene(const Scene& s) {
  const std::size_t vertices = s.positions.size();
  WT_FUZZ_CHECK(s.normals.size() == vertices, "");
  WT_FUZZ_CHECK(s.texcoords.size() == vertices, "");
  WT_FUZZ_CHECK(!s.materials.empty(), "");
  WT_FUZZ_CHECK(s.materialNames.size() == s.materials.size(), "");
  for (std::size_t v = 0; v < vertices; ++v) {
    WT_FUZZ_CHECK(finite3(s.positions[v]), "vertex " + std::to_string(v));
    const WtVec4& n = s.normals[v];
    WT_FUZZ_CHECK(finite3(n), "normal " + std::to_string(v));
    const double length = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
    WT_FUZZ_CHECK(length == 0.0 || std::fabs(length - 1.0) < 1e-3, "normal " + std::to_string(v));
    WT_FUZZ_CHECK(std::isfinite(s.texcoords[v].x) && std::isfinite(s.texcoords[v].y), "");
  }
  for (const WtTriangle& t : s.triangles) {
    WT_FUZZ_CHECK(t.v0 < vertices && t.v1 < vertices && t.v2 < vertices, "");
    WT_FUZZ_CHECK(t.material < s.materials.size(), "");
  }
  for (const WtMaterial& m : s.materials) {
    WT_FUZZ_CHECK(finite3(m.base_color) && finite3(m.emission), "");
    WT_FUZZ_CHECK(m.base_color.x >= 0 && m.base_color.y >= 0 && m.base_color.z >= 0, "");
    WT_FUZZ_CHECK(m.emission.x >= 0 && m.emission.y >= 0 && m.emission.z >= 0, "");
  }
  for (const PunctualLight& l : s.lights) {
    WT_FUZZ_CHECK(finite3(l.position) && finite3(l.direction) && finite3(l.intensity), "");
    WT_FUZZ_CHECK(l.intensity.x >= 0 && l.intensity.y >= 0 && l.intensity.z >= 0, "");
  }
  if (s.camera) {
    const CameraDesc& c = *s.camera;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) WT_FUZZ_CHECK(std::isfinite(c.cameraToWorld[i][j]), "");
    WT_FUZZ_CHECK(c.orthographic ? c.xmag > 0 && c.ymag > 0 : c.yfov > 0 && std::isfinite(c.yfov), "");
    WT_FUZZ_CHECK(c.znear >= 0 && std::isfinite(c.znear), "");
  }
}

/// A cdf of n + 1 entries: 0 first, 1 last, non-decreasing, finite.
inline void checkCdf(const float* cdf, std::size_t n) {
  WT_FUZZ_CHECK(cdf[0] == 0.0f && cdf[n] == 1.0f, "");
  for (std::size_t i = 0; i < n; ++i) WT_FUZZ_CHECK(std::isfinite(cdf[i]) && cdf[i] <= cdf[i + 1], "");
}

inline void checkEnvironment(const Environment& env) {
  const std::size_t w = env.header.width, h = env.header.height;
  WT_FUZZ_CHECK(w > 0 && h > 0, "");
  WT_FUZZ_CHECK(env.texels.size() == w * h, "");
  WT_FUZZ_CHECK(env.marginalCdf.size() == h + 1, "");
  WT_FUZZ_CHECK(env.conditionalCdf.size() == h * (w + 1), "");
  for (const WtVec4& t : env.texels) WT_FUZZ_CHECK(finite3(t) && t.x >= 0 && t.y >= 0 && t.z >= 0, "");
  checkCdf(env.marginalCdf.data(), h);
  for (std::size_t j = 0; j < h; ++j) checkCdf(&env.conditionalCdf[j * (w + 1)], w);
  WT_FUZZ_CHECK(std::isfinite(env.meanLuminance) && env.meanLuminance >= 0.0, "");
}

}  // namespace wt::fuzz
