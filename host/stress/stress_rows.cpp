#include "stress/stress_rows.h"
#include "device/scene_buffers.h"

#include <cmath>
#include <sstream>

namespace wt::stress_rows {

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

Rendered render(Context& context, const Scene& scene, const RenderSettings& settings) {
  Renderer renderer(context, scene, settings);
  for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
  return {renderer.readImage(), renderer.stats().nonFiniteSamples};
}

std::size_t nonFinitePixels(const Image& image) {
  std::size_t n = 0;
  for (float v : image.rgb) n += !std::isfinite(v);
  return n;
}

std::string ScaledJson::point(double x, double y, double z) const {
  std::ostringstream out;
  out.precision(17);
  out << "[" << translate + scale * x << ", " << translate + scale * y << ", " << translate + scale * z << "]";
  return out.str();
}

std::string ScaledJson::length(double v) const {
  std::ostringstream out;
  out.precision(17);
  out << scale * v;
  return out.str();
}

std::string ScaledJson::stage(const std::string& materials, const std::string& objects) const {
  return R"({"version": 1,
  "camera": {"from": )" + point(0, 1.2, 4) + R"(, "to": )" + point(0, 0.4, 0) + R"(, "fov": 40},
  "materials": {
    "ground": {"type": "lambert", "base_color": [0.6, 0.6, 0.6]},
)" + materials + R"(    "light": {"type": "lambert", "base_color": [0, 0, 0], "emission": [20, 18, 15]}},
  "objects": [
    {"type": "sphere", "center": )" + point(0, -1000, 0) + R"(, "radius": )" + length(1000) + R"(, "material": "ground"},
)" + objects + R"(    {"type": "sphere", "center": )" + point(-1.5, 2.5, 1.5) + R"(, "radius": )" + length(0.3) +
         R"(, "material": "light"}]})";
}

TransformStudy transformStudy(const StressOptions& options, int maxBounces) {
  TransformStudy study;
  const int size = options.quick ? 32 : 48, spp = options.quick ? 64 : 256;
  study.blocks = options.quick ? 4 : 6;
  study.zLimit = bonferroniZ(study.blocks * study.blocks * 3, 1e-3);
  study.settings.width = study.settings.height = size;
  study.settings.samplesPerPixel = spp;
  study.settings.maxBounces = maxBounces;
  study.settings.seed = 1;
  study.settings.background = glm::vec3(0.1f, 0.12f, 0.15f);
  return study;
}

StressRow agreementRow(const std::string& name, const Rendered& r, const Rendered& reference,
                       const TransformStudy& study, const std::string& against,
                       std::chrono::steady_clock::time_point start) {
  const ImageAgreement a = compareImages(r.image, reference.image, study.blocks);
  StressRow row;
  row.group = "primitives";
  row.name = name;
  row.figure = "max |z| " + stressFormat("%.2f", a.maxAbsZ) + " over " + std::to_string(a.tests) + " blocks";
  if (r.nonFinite) row.figure += ", " + std::to_string(r.nonFinite) + " NaN/Inf samples";
  row.criterion = "max |z| < " + stressFormat("%.2f", study.zLimit) + (against.empty() ? "" : " " + against) + ", no NaN";
  row.pass = a.maxAbsZ < study.zLimit && a.exactMismatches == 0 && r.nonFinite == 0;
  row.seconds = secondsSince(start);
  return row;
}

std::vector<StressRow> transformRows(const std::string& what, const StressOptions& options,
                                     const TransformStudy& study,
                                     const std::function<Rendered(double translate, double scale)>& renderCase) {
  std::vector<StressRow> rows;
  const Rendered reference = renderCase(0.0, 1.0);
  struct Case {
    std::string name;
    double translate, scale;
  };
  std::vector<Case> cases = {{"translated by 1e+06 (recentred)", 1e6, 1.0},
                             {"scaled by 1e-04", 0.0, 1e-4},
                             {"scaled by 1e+04", 0.0, 1e4}};
  if (options.quick) cases.resize(2);
  for (const Case& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const Rendered r = renderCase(c.translate, c.scale);
    rows.push_back(agreementRow(what + ": " + c.name, r, reference, study, "against the untransformed scene", start));
  }
  return rows;
}

std::vector<StressRow> instancedTransformRows(
    Context& context, const std::string& what, const StressOptions& options, const TransformStudy& study,
    std::size_t copies, const std::function<Scene(double translate, double scale)>& loadCase) {
  TransformStudy instanced = study;
  instanced.settings.instancing = Instancing::On;
  std::vector<std::size_t> counts;
  std::vector<StressRow> rows = transformRows(what, options, instanced, [&](double translate, double scale) {
    const Scene scene = loadCase(translate, scale);
    BvhBuildOptions bvh;
    bvh.instancing = Instancing::On;
    counts.push_back(SceneBuffers(context, scene, bvh).instanceCount());
    return render(context, scene, instanced.settings);
  });
  // counts[0] is the reference's, then one per row
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t n : {counts[0], counts[i + 1]})
      if (n != copies) {
        rows[i].pass = false;
        rows[i].figure += ", " + std::to_string(n) + " instances (expected " + std::to_string(copies) + ")";
      }
  return rows;
}

}  // namespace wt::stress_rows
