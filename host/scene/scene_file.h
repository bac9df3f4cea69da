// The wavetrace scene file (.json, docs/scene-format.md): glTF files placed
// by transforms, analytic spheres, named materials, a camera, the
// environment and render settings, in one strictly validated document. Every
// error names the file and the JSON path of the element, e.g.
// "spheres.json: objects[3].radius: must be > 0, got -1".
#pragma once

#include "scene/gltf_loader.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace wt {

/// The "environment" object: a constant colour or a map, lighting the scene.
struct SceneEnvironment {
  std::optional<glm::vec3> color;  ///< constant radiance (nits per channel); absent when a map is given
  std::string map;                 ///< .hdr/.exr path, resolved against the scene file's folder; empty: constant
  float intensity = 1.0f;          ///< scale on the map
  float rotationDegrees = 0.0f;    ///< the map about +Y, counter-clockwise seen from above
  bool hidden = false;             ///< camera rays see black where they escape; the environment still lights
};

/// What the scene file asks of the renderer; the command line overrides
/// each field it names. Absent fields keep the renderer's defaults.
struct SceneFileSettings {
  std::optional<int> width, height;  ///< pixels, [1, 16384]
  std::optional<int> samplesPerPixel;  ///< [1, 2^24]
  std::optional<int> maxBounces;       ///< [0, 1024]
  std::optional<std::uint32_t> seed;
  std::optional<float> exposureStops;     ///< fixed stops, or with autoExposure the offset from auto
  bool autoExposure = false;              ///< "auto", "auto+STOPS", "auto-STOPS"
  std::optional<std::string> integrator;  ///< "path" or "minimal"
  std::optional<std::string> tonemap;     ///< a --tonemap operator name (render/tonemap_names.h)
  std::optional<SceneEnvironment> environment;
};

struct SceneFile {
  Scene scene;
  SceneFileSettings settings;
};

/// Load a scene file. Included glTF files are resolved against the file's
/// folder; with options.recenter the scene is stored relative to its camera
/// (else the centre of its bounds), every transform composed in double.
/// options.maxVertices / maxTriangles bound the whole flattened scene.
/// Throws SceneError.
SceneFile loadSceneFile(const std::string& path, const GltfLoadOptions& options = {});

/// The same from the document's text: `name` starts every message, and
/// relative file names (glTF includes, the environment map) are resolved
/// against `baseDir`.
SceneFile loadSceneFileFromMemory(std::string_view json, const std::string& name, const std::string& baseDir,
                                  const GltfLoadOptions& options = {});

}  // namespace wt
