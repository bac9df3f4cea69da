// Checkpoints of a running render (--checkpoint, --resume): the
// accumulation as the device holds it, with what it depends on (scene
// content, image settings, kernels), written atomically and checked on
// reading. The format is documented in docs/halting.md, "File format".
#pragma once

#include "render/renderer.h"

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace wt {

/// A checkpoint that cannot be read, is truncated or corrupt, or belongs to
/// another render. what() names the file and what is wrong or differs.
struct CheckpointError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

constexpr std::uint32_t kCheckpointVersion = 2;  ///< 2 added the AOVs (aov_bytes)

/// One thing the accumulation depends on, as key and printable value.
struct CheckpointField {
  std::string key, value;
  bool operator==(const CheckpointField&) const = default;
};

/// Everything a resumed render must share with the checkpoint: the scene's
/// content, each image-affecting setting, the kernels' source and build
/// options. Halting options (--spp, --time, --target-error) and --exposure
/// (applied when the PNG is made) are not part of it.
std::vector<CheckpointField> checkpointIdentity(const Scene& scene, const Renderer& renderer);

struct Checkpoint {
  std::vector<CheckpointField> identity;
  std::string device;          ///< the device it was rendered on (another one only warns)
  std::uint64_t pixels = 0;
  Accumulation accumulation;
};

/// OUTPUT.wtckpt: beside the first output image.
std::filesystem::path checkpointPathFor(const std::filesystem::path& output);

/// Write under a temporary name in the same folder, flush to disk, rename
/// over `path`: a crash leaves the previous checkpoint whole. Throws
/// CheckpointError.
void writeCheckpoint(const std::filesystem::path& path, const Checkpoint& checkpoint);

/// Read and verify (magic, version, sizes, checksum, header). Throws
/// CheckpointError naming the file and the fault; never returns a partial one.
Checkpoint readCheckpoint(const std::filesystem::path& path);

/// Throw CheckpointError naming every field of `expected` that `found`
/// lacks or holds with another value.
void requireSameRender(const std::filesystem::path& path, const Checkpoint& found,
                       const std::vector<CheckpointField>& expected);

/// FNV-1a (64-bit) over the Scene's arrays: positions, attributes,
/// triangles, instances, spheres, curves, materials, textures, camera,
/// lights and origin. Names and the source path are left out.
std::uint64_t sceneContentHash(const Scene& scene);

/// FNV-1a over the byte stream taken as 8-byte little-endian words (a last
/// partial word byte by byte), however it is split into bytes() calls: a
/// change of any one byte always changes it.
class Fnv64 {
 public:
  void bytes(const void* data, std::size_t size);
  template <class T>
  void pod(const T& value) { bytes(&value, sizeof value); }
  template <class T>
  void array(const std::vector<T>& values) {
    pod(std::uint64_t(values.size()));
    bytes(values.data(), values.size() * sizeof(T));
  }
  std::uint64_t value() const;

 private:
  void word(std::uint64_t w);
  std::uint64_t m_hash = 0xcbf29ce484222325ull;
  unsigned char m_tail[8] = {};
  std::size_t m_tailSize = 0;
};

}  // namespace wt
