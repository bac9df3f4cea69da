// What the rows of the primitives group (stress_primitives.cpp,
// stress_displaced.cpp) share: timing, rendering a scene to an image,
// scene-file coordinates under a transform, and the row that holds a
// transformed scene's image against the untransformed one.
#pragma once

#include "render/image_error.h"
#include "render/renderer.h"
#include "stress/stress.h"

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace wt::stress_rows {

double secondsSince(std::chrono::steady_clock::time_point start);

struct Rendered {
  Image image;
  std::uint64_t nonFinite = 0;
};

/// `settings.samplesPerPixel` samples of `scene`.
Rendered render(Context& context, const Scene& scene, const RenderSettings& settings);

/// Pixels whose mean is NaN or infinite.
std::size_t nonFinitePixels(const Image& image);

/// Scene-file text for coordinates scaled by `scale` and moved by
/// `translate` on every axis, to 17 digits (doubles round-trip).
struct ScaledJson {
  double translate = 0.0, scale = 1.0;
  std::string point(double x, double y, double z) const;  ///< "[x, y, z]"
  std::string length(double v) const;                     ///< a radius or a scale
  /// A scene file on the rows' common stage: the camera, a ground sphere and
  /// a sphere light (materials "ground" and "light"); `materials` and
  /// `objects` are the scene's own entries, each line ending in ",\n".
  std::string stage(const std::string& materials, const std::string& objects) const;
};

/// The image comparison of the transform rows: the z limit that one false
/// alarm in 1e-3 rows allows over `blocks`^2 blocks of 3 channels, and the
/// settings (square images, seed 1, a dim background) they render with.
struct TransformStudy {
  int blocks = 0;
  double zLimit = 0.0;
  RenderSettings settings;
};
TransformStudy transformStudy(const StressOptions& options, int maxBounces);

/// A row of the primitives group: `r` against `reference` in the study's
/// blocks, passing within its z limit, no exact mismatch and no NaN;
/// `against` names the reference in the criterion (may be empty).
StressRow agreementRow(const std::string& name, const Rendered& r, const Rendered& reference,
                       const TransformStudy& study, const std::string& against,
                       std::chrono::steady_clock::time_point start);

/// The rows of a scene file `what` translated by 1e6 (recentred), scaled by
/// 1e-4 and by 1e4 (the first two with --quick), each against the
/// untransformed image; `renderCase` renders it under (translate, scale).
std::vector<StressRow> transformRows(const std::string& what, const StressOptions& options,
                                     const TransformStudy& study,
                                     const std::function<Rendered(double translate, double scale)>& renderCase);

/// transformRows for a scene file whose copies (`copies` of them) must be
/// stored as instances (Instancing::On): each row fails, saying so, where
/// the uploaded scene has another number of instances.
std::vector<StressRow> instancedTransformRows(
    Context& context, const std::string& what, const StressOptions& options, const TransformStudy& study,
    std::size_t copies, const std::function<Scene(double translate, double scale)>& loadCase);

}  // namespace wt::stress_rows
