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
#include <span>
#include <string>
#include <string_view>
#include <vector>

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
/// (for any work-group size). There a miss in the default folder compiles
/// without asking for the binary, and leaves the entry to a background
/// process (storeDeferredProgramsInBackground); a chosen folder stores at once.
bool ownCacheMakesBinariesDear(const DeviceInfo& device);

/// What happened to one program.
enum class CacheOutcome {
  kOff,       ///< no cache: turned off, Oclgrind, or the device gives no binary
  kHit,       ///< loaded from a valid entry
  kMiss,      ///< no entry: compiled and stored (or its store deferred: CachedProgram::deferred)
  kRejected,  ///< an entry was there but corrupt, truncated or stale: compiled and replaced
};
const char* cacheOutcomeName(CacheOutcome outcome);

struct CachedProgram {
  cl::Program program;
  CacheOutcome outcome = CacheOutcome::kOff;
  double seconds = 0.0;          ///< compile or load time, build included
  std::size_t binaryBytes = 0;   ///< the device binary's size (0: none)
  std::filesystem::path entry;   ///< the entry file (empty: no cache)
  bool deferred = false;         ///< compiled without its binary: storeDeferredProgramsInBackground stores it
};

/// A PoCL 3.1 binary (format 9) without its program bitcode, under a build
/// hash of its own: loading it skips parsing the bitcode, and each kernel
/// runs the work-group functions it carries (specialised ones where the
/// render that preceded the fetch compiled them, else the generic one).
/// Nothing where `binary` is not such a binary or holds other program files.
std::optional<std::vector<unsigned char>> poclBinaryWithoutBitcode(std::span<const unsigned char> binary);

/// The cache key: SHA-256 over the expanded source, the build options, the
/// device's name and version, the driver version and the platform.
Digest programCacheKey(const DeviceInfo& device, std::string_view source, std::string_view options);

/// Build `source` with `options` for the context's device through the cache
/// (none under Oclgrind): load a valid entry, else compile and store one
/// (written to a temporary file in the same folder and renamed, so
/// concurrent processes never see a partial entry); on PoCL's CPU device
/// with the default folder, a miss records a DeferredStore instead.
/// `label` names the program in messages (the kernels/ root of its source).
/// Throws DeviceError carrying the build log when compiling fails.
CachedProgram buildCachedProgram(Context& context, const std::string& source, const std::string& options,
                                 const std::string& label);

/// A program compiled without fetching its binary, whose entry is still to
/// be written: by a process of its own after the render, off its critical path.
struct DeferredStore {
  std::filesystem::path dir;  ///< the cache folder
  std::string key;            ///< the entry's key (hex): its source, options and device
  std::string label;          ///< the kernels/ root its source expands from
  std::string options;
};
/// The stores recorded so far in this process (not yet handed on).
std::vector<DeferredStore> deferredProgramStores();

/// The executable that `storeDeferredProgramsInBackground` starts as
/// `EXE store-programs`; unset (the tests, the bench; "" unsets) nothing is started.
void setProgramStoreExecutable(const std::filesystem::path& exe);

/// Hand the deferred stores to a background process (`EXE store-programs
/// --device N`, the jobs on its standard input; its own process group,
/// lowest priority) and forget them; the caller does not wait. A job whose entry
/// another process is storing (a `KEY.pending` file under 10 minutes old)
/// is skipped. False when nothing was started.
bool storeDeferredProgramsInBackground(const DeviceInfo& device);

/// The jobs as `storeDeferredProgramsInBackground` writes them, one a line;
/// parseDeferredStores reads them back (malformed lines are dropped).
std::string formatDeferredStores(const std::vector<DeferredStore>& jobs);
std::vector<DeferredStore> parseDeferredStores(const std::string& text);

/// Compile `source` (a PoCL cache hit where the render just built it), fetch
/// its binary and write the entry for `job`, unless a valid one is there;
/// then remove the job's pending mark. False (with a debug message) where
/// the source, options and device do not give the job's key, or the device
/// gives no binary.
bool storeProgramEntry(Context& context, const std::string& source, const DeferredStore& job);

}  // namespace wt
