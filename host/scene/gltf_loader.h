// glTF 2.0 (.gltf, .glb) to Scene, with validation that names the file and
// the element on every error.
#pragma once

#include "scene/scene.h"

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

namespace wt {

struct GltfLoadOptions {
  int sceneIndex = -1;   ///< -1: the file's default scene (or scene 0)
  int cameraIndex = 0;   ///< which camera node (in traversal order) to use, if any
  bool recenter = true;  ///< store the scene relative to the camera (else the geometry's centre), in double precision; false keeps world coordinates as they are
  /// Refuse scenes that flatten (every mesh instance placed) to more; counted
  /// from the accessors before anything is decoded. 2^28 vertices take
  /// 10 GiB of host arrays.
  std::size_t maxVertices = std::size_t(1) << 28;
  std::size_t maxTriangles = std::size_t(1) << 28;
  /// Threads that decode the images and build their mips; 0: the hardware's.
  /// Any count gives the same scene, bit for bit.
  unsigned textureThreads = 0;
};

/// Load a .gltf or .glb file. Throws SceneError.
Scene loadGltf(const std::string& path, const GltfLoadOptions& options = {});

/// Load a .gltf held in memory (the embedded default scene). `name` is used
/// in messages; external buffers are resolved against `baseDir`. Bytes that
/// start with the binary magic are read as .glb.
Scene loadGltfFromMemory(std::string_view contents, const std::string& name,
                         const std::string& baseDir, const GltfLoadOptions& options = {});

/// Load a .glb held in memory, as loadGltf reads a .glb file: the bytes must
/// start with the 'glTF' magic. `name` and `baseDir` as above.
Scene loadGlbFromMemory(std::span<const unsigned char> bytes, const std::string& name,
                        const std::string& baseDir, const GltfLoadOptions& options = {});

}  // namespace wt
