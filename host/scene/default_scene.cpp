#include "scene/default_scene.h"

#include "core/embedded.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace wt {

Scene loadDefaultScene(const GltfLoadOptions& options) {
  auto contents = embedded::find("scenes/cornell.gltf");
  if (!contents) throw SceneError("the default scene is missing from this build (scenes/cornell.gltf)");
  return loadGltfFromMemory(*contents, "cornell.gltf (built in)", ".", options);
}

std::vector<std::string> builtInSceneNames() {
  std::vector<std::string> names;
  for (const embedded::File& f : embedded::files()) {
    std::filesystem::path p(f.path);
    if (p.parent_path() == "scenes" && p.extension() == ".gltf") names.push_back(p.stem().string());
  }
  return names;
}

Scene loadScene(const std::string& path, const GltfLoadOptions& options) {
  return loadSceneAny(path, options).scene;
}

SceneFile loadSceneAny(const std::string& path, const GltfLoadOptions& options) {
  // a bare name that is not a file: one of the built-in scenes
  if (std::filesystem::path(path).extension().empty() && !std::filesystem::exists(path)) {
    if (auto contents = embedded::find("scenes/" + path + ".gltf"))
      return {loadGltfFromMemory(*contents, path + ".gltf (built in)", ".", options), {}};
    std::string known;
    for (const std::string& n : builtInSceneNames()) known += (known.empty() ? "" : ", ") + n;
    throw SceneError(path + ": no such file, and no built-in scene of that name (built in: " + known + ")");
  }
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".gltf" || ext == ".glb") return {loadGltf(path, options), {}};
  if (ext == ".json") return loadSceneFile(path, options);
  throw SceneError(path + ": unsupported scene format '" + ext + "' (wavetrace reads .gltf, .glb and .json)");
}

}  // namespace wt
