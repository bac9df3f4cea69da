// The scenes compiled into the binary (scenes/*.gltf) and the entry point
// that picks a loader by file extension.
#pragma once

#include "scene/gltf_loader.h"

#include <string>

namespace wt {

/// The embedded Cornell box (scenes/cornell.gltf).
Scene loadDefaultScene(const GltfLoadOptions& options = {});

/// Load a scene file by its extension (.gltf, .glb). Throws SceneError.
Scene loadScene(const std::string& path, const GltfLoadOptions& options = {});

}  // namespace wt
