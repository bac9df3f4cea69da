// The far-furnace group: one white convex object of each geometry type
// (triangles, a sphere, a curve; each also as an instance) alone in a
// uniform sky, placed 1 to 1e4 of its own size from the origin in world
// coordinates (a scene made in code is not recentred). Every ray leaving
// a convex surface outwards escapes, so a white object must vanish into
// the sky: a ray spawned off the surface that finds the surface again (or
// a shadow ray it blocks) darkens its pixel.
#include "stress/stress.h"
#include "stress/stress_rows.h"

#include "render/image_error.h"
#include "render/renderer.h"
#include "scene/generators.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace wt {
namespace {

enum class FarShape { kTriangles, kSphere, kCurve };

/// The object at the origin, about one unit across, white (albedo 1).
Scene farShape(FarShape shape) {
  const WtMaterial white = makeMaterial(glm::vec3(1.0f));
  if (shape == FarShape::kTriangles) {
    // flat-shaded: with interpolated normals a sample above the shading
    // normal can fall below the facet and be absorbed by design
    Scene s = makeIcosphere(2, glm::vec3(0.0f), 1.0f, white);
    std::fill(s.normals.begin(), s.normals.end(), WtVec4{0.0f, 0.0f, 0.0f, 0.0f});
    return s;
  }
  Scene s;
  s.materials.push_back(white);
  s.materialNames.push_back("white");
  if (shape == FarShape::kSphere) {
    s.spheres.push_back({glm::vec3(0.0f), 1.0f, 0u});
    return s;
  }
  // a straight strand of two segments whose radius shrinks linearly: one
  // round cone, so convex, with a joint between the segments
  Curve c;
  c.pointCount = 3;
  s.curvePoints = {{-1.2f, -0.3f, 0.1f, 0.6f}, {0.0f, 0.0f, 0.0f, 0.45f}, {1.2f, 0.3f, -0.1f, 0.3f}};
  s.curves.push_back(c);
  return s;
}

const char* farShapeName(FarShape shape) {
  return shape == FarShape::kTriangles ? "a flat icosphere (320 triangles)"
         : shape == FarShape::kSphere  ? "a sphere"
                                       : "a curve (two linear segments, one round cone)";
}

struct FarCase {
  std::uint64_t darkPixels = 0;   ///< pixels of the BSDF-only render off the sky beyond rounding
  double worstRatio = 1.0;        ///< the darkest (or brightest) such pixel over the sky
  double neeZ = 0.0;              ///< the NEE + MIS render's image mean against the sky, in standard errors
  std::uint64_t nonFinite = 0;
  std::size_t instances = 0;      ///< copies stored as instances
};

/// `shape` moved to `distance` from the origin (rotated, scaled by 0.8) and
/// rendered twice from 3 units away: by BSDF sampling alone (every sample is
/// exactly the sky unless a spawned ray meets the object: no noise) and by
/// the default estimator (NEE + MIS: its shadow rays checked in the mean).
FarCase farCase(Context& context, const StressOptions& options, FarShape shape, bool instanced, double distance) {
  const glm::vec3 sky(0.5f, 1.0f, 2.0f);
  const glm::vec3 place = float(distance) * glm::normalize(glm::vec3(1.0f, -0.6f, 0.8f));
  glm::mat4 m = glm::translate(glm::mat4(1.0f), place);
  m = glm::rotate(m, 0.7f, glm::normalize(glm::vec3(1.0f, 2.0f, 0.5f)));
  m = glm::scale(m, glm::vec3(0.8f));
  // A second copy makes the geometry one to store once: 1/100 of the size,
  // 50 units nearer the origin (out of view; a spawned ray meets it about
  // once in 1e8). The object is drawn as the copy whose floats are the
  // finest for its size moved, which is not this nearer one: its corners
  // are rounded by about 2 % of its size at 1e4.
  const glm::vec3 nearer = place - 50.0f * glm::normalize(glm::vec3(1.0f, -0.6f, 0.8f));
  const glm::mat4 copies[] = {m, glm::scale(glm::translate(glm::mat4(1.0f), nearer), glm::vec3(0.01f))};
  Scene scene = placeCopies(farShape(shape), copies);
  CameraDesc camera;
  camera.cameraToWorld = glm::translate(glm::mat4(1.0f), place + glm::vec3(0.0f, 0.0f, 3.0f));
  scene.camera = camera;

  RenderSettings settings;
  settings.width = settings.height = options.quick ? 16 : 32;
  settings.samplesPerPixel = options.quick ? 8 : 32;
  settings.maxBounces = 1;  // a spawned ray that meets the object again ends the path dark
  settings.background = sky;
  settings.seed = 5;
  settings.instancing = instanced ? Instancing::On : Instancing::Off;

  FarCase out;
  settings.useNee = false;
  {
    Renderer renderer(context, scene, settings);
    for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
    const Image image = renderer.readImage();
    out.nonFinite += renderer.stats().nonFiniteSamples;
    out.instances = renderer.sceneBuffers().instanceCount();
    for (std::size_t p = 0; p < image.samples.size(); ++p) {
      bool dark = false;
      for (int c = 0; c < 3; ++c) {
        // each sample is the sky times a Lambert weight within a few float roundings of 1
        const double ratio = image.rgb[3 * p + c] / sky[c];
        if (!(std::abs(ratio - 1.0) <= 1e-5)) {
          dark = true;
          if (!(std::abs(ratio - 1.0) <= std::abs(out.worstRatio - 1.0))) out.worstRatio = ratio;
        }
      }
      out.darkPixels += dark;
    }
  }
  settings.useNee = true;
  {
    Renderer renderer(context, scene, settings);
    for (int s = 0; s < settings.samplesPerPixel; ++s) renderer.renderSample();
    const Image image = renderer.readImage();
    out.nonFinite += renderer.stats().nonFiniteSamples;
    // the image mean's standard error from the pixels' own variances
    double sum = 0.0, variance = 0.0;
    const double pixels = double(image.samples.size());
    for (std::size_t p = 0; p < image.samples.size(); ++p) {
      sum += image.rgb[3 * p + 1];
      variance += image.rgbVariance[3 * p + 1] / std::max(1.0, double(image.samples[p]));
    }
    const double se = std::sqrt(variance) / pixels;
    const double diff = sum / pixels - double(sky.y);
    out.neeZ = se > 0.0 ? diff / se : (std::abs(diff) <= 1e-5 ? 0.0 : INFINITY);
  }
  return out;
}

}  // namespace

std::vector<StressRow> stressFarFurnace(Context& context, const StressOptions& options) {
  std::vector<StressRow> rows;
  const double distances[] = {1.0, 1e2, 1e3, 1e4};
  const FarShape shapes[] = {FarShape::kTriangles, FarShape::kSphere, FarShape::kCurve};
  // one false alarm in 1e3 runs over every case's NEE mean
  const double zLimit = bonferroniZ(int(std::size(distances) * std::size(shapes) * 2), 1e-3);
  for (FarShape shape : shapes)
    for (bool instanced : {false, true}) {
      const auto start = std::chrono::steady_clock::now();
      std::string figure;
      bool pass = true;
      for (double distance : distances) {
        const FarCase c = farCase(context, options, shape, instanced, distance);
        figure += (figure.empty() ? "" : "; ") + stressFormat("%.0e: ", distance) + std::to_string(c.darkPixels) +
                  " dark" + (c.darkPixels ? stressFormat(" (worst %.4f)", c.worstRatio) : std::string()) +
                  stressFormat(", NEE z %.2f", c.neeZ);
        if (c.nonFinite) figure += ", " + std::to_string(c.nonFinite) + " NaN/Inf samples";
        pass = pass && c.darkPixels == 0 && std::abs(c.neeZ) < zLimit && c.nonFinite == 0 &&
               (c.instances > 0) == instanced;
        if ((c.instances > 0) != instanced) figure += instanced ? ", not instanced" : ", instanced";
      }
      StressRow row;
      row.group = "far-furnace";
      row.name = std::string("white ") + farShapeName(shape) + (instanced ? " as an instance" : "") +
                 " in a uniform sky, 1 to 1e4 from the origin";
      row.figure = figure;
      row.criterion = "BSDF sampling only: every pixel the sky within 1e-5; NEE + MIS: image mean within |z| < " +
                      stressFormat("%.2f", zLimit) + " of the sky; no NaN";
      row.pass = pass;
      row.seconds = stress_rows::secondsSince(start);
      rows.push_back(row);
    }
  return rows;
}

}  // namespace wt
