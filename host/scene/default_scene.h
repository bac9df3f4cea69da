// The scenes compiled into the binary (scenes/*.gltf) and the entry point
// that picks a loader by file extension.
#pragma once

#include "scene/gltf_loader.h"
#include "scene/scene_file.h"

#include <string>
#include <vector>

namespace wt {

/// The embedded Cornell box (scenes/cornell.gltf).
Scene loadDefaultScene(const GltfLoadOptions& options = {});

/// Names of the built-in scenes (scenes/*.gltf), e.g. "cornell".
std::vector<std::string> builtInSceneNames();

/// Load a scene file by its extension (.gltf, .glb, .json), or a built-in
/// scene by its bare name ("cornell_small_light"). A scene file's render
/// settings are dropped (loadSceneAny keeps them). Throws SceneError.
Scene loadScene(const std::string& path, const GltfLoadOptions& options = {});

/// As loadScene, with the scene file's settings; glTF files and built-in
/// scenes give empty settings.
SceneFile loadSceneAny(const std::string& path, const GltfLoadOptions& options = {});

}  // namespace wt
