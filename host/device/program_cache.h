// Compiled program binaries kept on disk, so that a second run loads its
// kernels instead of compiling them. An entry is a header (magic, format
// version, key, payload length, payload checksum) and the device's binary;
// anything that does not check out is rebuilt with a warning, never trusted.
#pragma once

#include "device/context.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace wt {

/// A SHA-256 digest: entries are named and checked by it.
using Digest = std::array<std::uint8_t, 32>;
Digest sha256(std::string_view data);
std::string toHex(const Digest& digest);

/// Where entries live: `--kernel-cache DIR` (setProgramCacheDirectory), else
/// $WAVETRACE_CACHE_DIR, else $XDG_CACHE_HOME/wavetrace/kernels, else
/// ~/.cache/wavetrace/kernels. "off" as the folder (flag or variable) turns
/// the cache off; so does a missing HOME. None: no cache.
std::optional<std::filesystem::path> programCacheDirectory();
/// Override the folder; "off" turns the cache off, "" restores the default.
void setProgramCacheDirectory(const std::string& dir);
/// Whether the folder was chosen (flag or variable) rather than the default.
bool programCacheDirectoryChosen();
/// PoCL's CPU device: handing out a binary compiles every kernel once more
/// (for any work-group size), and PoCL caches compiled kernels itself, so
/// the default folder is not used there; a chosen one is.
bool ownCacheMakesBinariesDear(const DeviceInfo& device);

/// What happened to one program.
enum class CacheOutcome {
  kOff,       ///< no cache: turned off, Oclgrind, or the device gives no binary
  kHit,       ///< loaded from a valid entry
  kMiss,      ///< no entry: compiled and stored
  kRejected,  ///< an entry was there but corrupt, truncated or stale: compiled and replaced
};
const char* cacheOutcomeName(CacheOutcome outcome);

struct CachedProgram {
  cl::Program program;
  CacheOutcome outcome = CacheOutcome::kOff;
  double seconds = 0.0;          ///< compile or load time, build included
  std::size_t binaryBytes = 0;   ///< the device binary's size (0: none)
  std::filesystem::path entry;   ///< the entry file (empty: no cache)
};

/// The cache key: SHA-256 over the expanded source, the build options, the
/// device's name and version, the driver version and the platform.
Digest programCacheKey(const DeviceInfo& device, std::string_view source, std::string_view options);

/// Build `source` with `options` for the context's device through the cache
/// (none under Oclgrind, nor on PoCL's CPU device unless the folder was chosen):
/// load a valid entry, else compile and store one (written to a temporary
/// file in the same folder and renamed, so concurrent processes never see a
/// partial entry). `label` names the program in messages. Throws DeviceError
/// carrying the build log when compiling fails.
CachedProgram buildCachedProgram(Context& context, const std::string& source, const std::string& options,
                                 const std::string& label);

}  // namespace wt
