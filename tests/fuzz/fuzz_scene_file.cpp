// libFuzzer harness: scene file (.json) text through loadSceneFileFromMemory.
// Every input must load into a consistent scene with usable settings or
// throw a SceneError naming the file. Includes resolve against a folder of
// our own holding a small glTF file and an environment map's name, so that
// placement, recentring and the settings are reached, not only the parser.
#include "fuzz_checks.h"
#include "scene/gltf_doc.h"
#include "scene/scene_file.h"

#include <fstream>

namespace {

/// triangle.gltf (two placed copies of a triangle, a camera, a spot light)
/// and sky.hdr (its name only: the loader checks that it exists).
const std::string& baseDir() {
  static const std::string dir = [] {
    namespace fs = std::filesystem;
    const fs::path path = fs::temp_directory_path() / "wt_fuzz_scene_file_base";
    fs::create_directories(path);
    wt::gltf_doc::GltfDoc doc;
    const int pos = doc.addVec3({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
    const int nrm = doc.addVec3({{0, 0, 1}, {0, 0, 1}, {0, 0, 1}});
    doc.addMesh("{\"attributes\":{\"POSITION\":" + std::to_string(pos) + ",\"NORMAL\":" + std::to_string(nrm) +
                "},\"material\":0}");
    doc.materials.push_back("{\"name\":\"tri\"}");
    doc.cameras.push_back("{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.7,\"znear\":0.01}}");
    doc.addNode("{\"mesh\":0}");
    doc.addNode("{\"mesh\":0,\"translation\":[2,0,0]}");
    doc.addNode("{\"camera\":0,\"translation\":[0,0,3]}");
    doc.addNode("{\"translation\":[0,2,0],\"extensions\":{\"KHR_lights_punctual\":{\"light\":0}}}");
    doc.scenes.push_back("{\"nodes\":[0,1,2,3]}");
    doc.extensionsUsed = "[\"KHR_lights_punctual\"]";
    doc.extensions = "{\"KHR_lights_punctual\":{\"lights\":[{\"type\":\"spot\",\"spot\":{}}]}}";
    std::ofstream(path / "triangle.gltf") << doc.embedded();
    std::ofstream(path / "sky.hdr") << "not read";
    return path.string();
  }();
  return dir;
}

void checkSceneFile(const wt::SceneFile& f) {
  const wt::Scene& s = f.scene;
  wt::fuzz::checkScene(s);
  for (const wt::Sphere& sphere : s.spheres) {
    WT_FUZZ_CHECK(wt::fuzz::finite3(sphere.center), "");
    WT_FUZZ_CHECK(sphere.radius > 0.0f && std::isfinite(sphere.radius), "");
    WT_FUZZ_CHECK(sphere.material < s.materials.size(), "");
  }
  for (const wt::GeometryInstance& copy : s.instances)
    WT_FUZZ_CHECK(std::size_t(copy.firstTriangle) + copy.triangleCount <= s.triangles.size(), "");
  WT_FUZZ_CHECK(std::isfinite(s.origin.x) && std::isfinite(s.origin.y) && std::isfinite(s.origin.z), "");
  const wt::SceneFileSettings& settings = f.settings;
  WT_FUZZ_CHECK(!settings.width || (*settings.width >= 1 && *settings.width <= 16384), "");
  WT_FUZZ_CHECK(!settings.height || (*settings.height >= 1 && *settings.height <= 16384), "");
  WT_FUZZ_CHECK(!settings.samplesPerPixel || *settings.samplesPerPixel >= 1, "");
  WT_FUZZ_CHECK(!settings.maxBounces || *settings.maxBounces >= 0, "");
  WT_FUZZ_CHECK(!settings.exposureStops || std::isfinite(*settings.exposureStops), "");
  if (const auto& env = settings.environment) {
    WT_FUZZ_CHECK(env->color.has_value() != !env->map.empty(), "");
    if (env->color) WT_FUZZ_CHECK(wt::fuzz::finite3(*env->color) && glm::all(glm::greaterThanEqual(*env->color, glm::vec3(0.0f))), "");
    WT_FUZZ_CHECK(env->intensity >= 0.0f && std::isfinite(env->intensity), "");
    WT_FUZZ_CHECK(std::isfinite(env->rotationDegrees), "");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  const std::string name = "fuzz.json";
  try {
    checkSceneFile(wt::loadSceneFileFromMemory(std::string_view(reinterpret_cast<const char*>(data), size), name,
                                               baseDir()));
  } catch (const wt::SceneError& e) {
    wt::fuzz::checkMessage(e.what(), name);
  }
  return 0;
}
