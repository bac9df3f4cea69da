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

Scene loadScene(const std::string& path, const GltfLoadOptions& options) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".gltf" || ext == ".glb") return loadGltf(path, options);
  throw SceneError(path + ": unsupported scene format '" + ext + "' (wavetrace reads .gltf and .glb)");
}

}  // namespace wt
