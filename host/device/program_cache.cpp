#include "device/program_cache.h"

#include "core/log.h"
#include "device/program.h"

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <random>
#include <span>
#include <sstream>
#include <system_error>

#include <fcntl.h>
#include <openssl/sha.h>
#include <spawn.h>
#include <sys/stat.h>
#include <unistd.h>

extern char** environ;

namespace wt {
namespace {

// entry layout: the header, then the payload (the device binary)
constexpr char kMagic[8] = {'W', 'T', 'K', 'C', 'A', 'C', 'H', 'E'};
constexpr std::uint32_t kFormatVersion = 2;  // 2: PoCL CPU binaries without their bitcode
struct EntryHeader {
  char magic[8];
  std::uint32_t formatVersion;
  std::uint32_t headerBytes;
  std::uint8_t key[32];
  std::uint64_t payloadBytes;
  std::uint8_t checksum[32];  ///< sha256 of the payload
};
static_assert(sizeof(EntryHeader) == 88, "the header is written as it is laid out");

std::optional<std::string> g_directoryOverride;  // set by --kernel-cache
std::mutex g_deferredMutex;
std::vector<DeferredStore> g_deferred;               // misses whose entries are still to be written
std::optional<std::filesystem::path> g_storeExecutable;  // set by the command line only

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string megabytes(std::size_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f MB", double(bytes) / 1e6);
  return buf;
}

std::string secondsText(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f s", seconds);
  return buf;
}

/// Why the entry's bytes cannot be used, or nothing when they can.
std::optional<std::string> checkEntry(const std::string& bytes, const Digest& key) {
  if (bytes.size() < sizeof(EntryHeader)) return "truncated (" + std::to_string(bytes.size()) + " bytes, no full header)";
  EntryHeader header;
  std::memcpy(&header, bytes.data(), sizeof header);
  if (std::memcmp(header.magic, kMagic, sizeof kMagic) != 0) return std::string("not a wavetrace kernel cache entry");
  if (header.formatVersion != kFormatVersion || header.headerBytes != sizeof(EntryHeader))
    return "stale (format version " + std::to_string(header.formatVersion) + ", expected " +
           std::to_string(kFormatVersion) + ")";
  if (std::memcmp(header.key, key.data(), key.size()) != 0) return std::string("stale (its key is not its name's)");
  const std::uint64_t payload = bytes.size() - sizeof header;
  if (payload < header.payloadBytes)
    return "truncated (" + std::to_string(payload) + " of " + std::to_string(header.payloadBytes) + " payload bytes)";
  if (payload > header.payloadBytes)
    return "corrupt (" + std::to_string(payload - header.payloadBytes) + " bytes past the payload)";
  const Digest sum = sha256(std::string_view(bytes).substr(sizeof header));
  if (std::memcmp(header.checksum, sum.data(), sum.size()) != 0) return std::string("corrupt (checksum mismatch)");
  return std::nullopt;
}

std::optional<std::string> readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Write the entry beside its final name and rename it there: a reader sees
/// the old entry or the whole new one, never a partial file. PoCL's CPU
/// binaries are stored without their program bitcode (poclBinaryWithoutBitcode).
/// Returns the payload's size.
std::size_t storeEntry(const std::filesystem::path& dir, const std::filesystem::path& entry, const Digest& key,
                       const std::vector<unsigned char>& fetched, bool poclCpu) {
  std::optional<std::vector<unsigned char>> lean;
  if (poclCpu) lean = poclBinaryWithoutBitcode(fetched);
  const std::vector<unsigned char>& binary = lean ? *lean : fetched;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    log::warnOnce("kernel cache: cannot create " + dir.string() + " (" + ec.message() + "); kernels are not cached");
    return binary.size();
  }
  EntryHeader header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.formatVersion = kFormatVersion;
  header.headerBytes = sizeof header;
  std::memcpy(header.key, key.data(), key.size());
  header.payloadBytes = binary.size();
  const Digest sum = sha256(std::string_view(reinterpret_cast<const char*>(binary.data()), binary.size()));
  std::memcpy(header.checksum, sum.data(), sum.size());

  std::random_device random;
  const std::filesystem::path temp =
      entry.string() + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(random());
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(&header), sizeof header);
    out.write(reinterpret_cast<const char*>(binary.data()), std::streamsize(binary.size()));
    out.close();
    if (!out) {
      std::filesystem::remove(temp, ec);
      log::warnOnce("kernel cache: cannot write in " + dir.string() + "; kernels are not cached");
      return binary.size();
    }
  }
  std::filesystem::rename(temp, entry, ec);
  if (ec) {
    std::filesystem::remove(temp, ec);
    log::warnOnce("kernel cache: cannot write " + entry.string() + " (" + ec.message() + "); kernels are not cached");
  }
  return binary.size();
}

cl::Program compile(Context& context, const std::string& source, const std::string& options,
                    const std::string& label) {
  cl::Program program(context.context(), source);
  try {
    program.build({context.info().device}, options.c_str());
  } catch (const cl::Error& e) {
    std::string buildLog;
    try {
      buildLog = program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(context.info().device);
    } catch (const cl::Error&) {
    }
    throw DeviceError("building kernels (" + label + ") for '" + context.info().name + "' failed (" +
                      clErrorName(e.err()) + "), options: " + options + "\n" + buildLog);
  }
  return program;
}

/// The program from an entry's payload, or nothing where the device refuses it.
std::optional<cl::Program> load(Context& context, std::string_view payload, const std::string& options) {
  cl_device_id device = context.info().device();
  const std::size_t length = payload.size();
  const auto* bytes = reinterpret_cast<const unsigned char*>(payload.data());
  cl_int status = CL_SUCCESS, err = CL_SUCCESS;
  cl_program raw = clCreateProgramWithBinary(context.context()(), 1, &device, &length, &bytes, &status, &err);
  if (err != CL_SUCCESS || status != CL_SUCCESS) {
    if (raw) clReleaseProgram(raw);
    return std::nullopt;
  }
  cl::Program program(raw);  // takes the reference
  if (clBuildProgram(raw, 1, &device, options.c_str(), nullptr, nullptr) != CL_SUCCESS) return std::nullopt;
  return program;
}

// PoCL 3.1's binary (lib/CL/pocl_binary.c, format 9): a header, the
// program folder's files (program.bc), then each kernel's record, whose
// files are its work-group functions (.so) under the program's build hash
constexpr char kPoclMagic[8] = {'p', 'o', 'c', 'l', 'b', 'i', 'n', '\0'};
constexpr std::uint32_t kPoclFormat = 9;
constexpr std::size_t kPoclHashOffset = 8 + 8 + 4 + 4 + 8 + 4;  // id, device, version, kernels, flags, root entries
constexpr std::size_t kPoclHashBytes = 41;                       // "XX/" + 37 letters + NUL
constexpr std::size_t kPoclHeaderBytes = kPoclHashOffset + kPoclHashBytes;

/// Little-endian reads that fail past the end instead of reading it.
struct PoclReader {
  std::span<const unsigned char> bytes;
  std::size_t at = 0;
  bool ok = true;
  std::uint64_t number(std::size_t width) {
    if (!ok || bytes.size() - at < width) return ok = false, 0;
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < width; ++i) v |= std::uint64_t(bytes[at + i]) << (8 * i);
    at += width;
    return v;
  }
  std::string_view text() {  // a u32 length, then that many bytes
    const std::uint64_t n = number(4);
    if (!ok || bytes.size() - at < n) return ok = false, std::string_view();
    std::string_view s(reinterpret_cast<const char*>(bytes.data() + at), n);
    at += n;
    return s;
  }
};

void appendLe(std::vector<unsigned char>& out, std::uint64_t v, std::size_t width) {
  for (std::size_t i = 0; i < width; ++i) out.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

void appendText(std::vector<unsigned char>& out, std::string_view s) {
  appendLe(out, s.size(), 4);
  out.insert(out.end(), s.begin(), s.end());
}

}  // namespace

std::optional<std::vector<unsigned char>> poclBinaryWithoutBitcode(std::span<const unsigned char> binary) {
  PoclReader r{binary};
  if (binary.size() < kPoclHeaderBytes || std::memcmp(binary.data(), kPoclMagic, sizeof kPoclMagic) != 0) return std::nullopt;
  r.at = sizeof kPoclMagic;
  r.number(8);  // the device's id
  const std::uint64_t version = r.number(4), kernels = r.number(4);
  r.number(8);  // flags
  const std::uint64_t roots = r.number(4);
  if (version != kPoclFormat || roots != 1 || kernels == 0) return std::nullopt;
  r.at = kPoclHeaderBytes;
  // the program folder: only program.bc goes, anything else keeps the binary whole
  const std::uint64_t rootBytes = r.number(8);
  if (!r.ok || binary.size() - r.at < rootBytes) return std::nullopt;
  const std::size_t rootEnd = r.at + std::size_t(rootBytes);
  bool bitcode = false;
  while (r.ok && r.at < rootEnd) {
    const std::string_view name = r.text();
    r.text();
    if (name != "/program.bc") return std::nullopt;
    bitcode = true;
  }
  if (!r.ok || r.at != rootEnd || !bitcode) return std::nullopt;
  // every kernel record whole, up to the last byte
  for (std::uint64_t k = 0; k < kernels; ++k) {
    const std::size_t start = r.at;
    const std::uint64_t recordBytes = r.number(8), fileBytes = r.number(8);
    if (!r.ok || recordBytes < fileBytes || binary.size() - start < recordBytes) return std::nullopt;
    PoclReader files{binary.subspan(start + std::size_t(recordBytes - fileBytes), std::size_t(fileBytes))};
    while (files.ok && files.at < files.bytes.size()) files.text(), files.text();
    if (!files.ok) return std::nullopt;
    r.at = start + std::size_t(recordBytes);
  }
  if (r.at != binary.size()) return std::nullopt;

  std::vector<unsigned char> lean(binary.begin(), binary.begin() + kPoclHashOffset);
  // A build hash of its own: under the original one PoCL would find program.bc
  // in its cache and parse it; this one names these files alone.
  const Digest digest = sha256(std::string_view(reinterpret_cast<const char*>(binary.data()), binary.size()));
  std::string hash;
  for (std::uint8_t b : digest) hash += char('A' + (b >> 4)), hash += char('A' + (b & 15));
  hash = hash.substr(0, 2) + "/" + hash.substr(2, kPoclHashBytes - 4);
  lean.insert(lean.end(), hash.begin(), hash.end());
  lean.push_back(0);
  // PoCL requires a non-empty program folder: one small marker file
  std::vector<unsigned char> root;
  appendText(root, "/wavetrace-without-bitcode");
  appendText(root, "1\n");
  appendLe(lean, root.size(), 8);
  lean.insert(lean.end(), root.begin(), root.end());
  lean.insert(lean.end(), binary.begin() + std::ptrdiff_t(rootEnd), binary.end());
  return lean;
}

Digest sha256(std::string_view data) {
  // libcrypto picks the CPU's SHA instructions where it has them
  Digest digest;
  SHA256(reinterpret_cast<const unsigned char*>(data.data()), data.size(), digest.data());
  return digest;
}

std::string toHex(const Digest& digest) {
  static const char* kHex = "0123456789abcdef";
  std::string s;
  for (std::uint8_t b : digest) s += kHex[b >> 4], s += kHex[b & 15];
  return s;
}

void setProgramCacheDirectory(const std::string& dir) {
  if (dir.empty())
    g_directoryOverride.reset();
  else
    g_directoryOverride = dir;
}

bool programCacheDirectoryChosen() {
  const char* env = std::getenv("WAVETRACE_CACHE_DIR");
  return g_directoryOverride || (env && *env);
}

bool ownCacheMakesBinariesDear(const DeviceInfo& device) {
  return device.isCpu && device.platformName.find("Portable Computing Language") != std::string::npos;
}

std::optional<std::filesystem::path> programCacheDirectory() {
  auto chosen = [](const std::string& dir) -> std::optional<std::filesystem::path> {
    if (dir == "off") return std::nullopt;
    return std::filesystem::path(dir);
  };
  if (g_directoryOverride) return chosen(*g_directoryOverride);
  if (const char* env = std::getenv("WAVETRACE_CACHE_DIR"); env && *env) return chosen(env);
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
    return std::filesystem::path(xdg) / "wavetrace" / "kernels";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".cache" / "wavetrace" / "kernels";
  return std::nullopt;
}

const char* cacheOutcomeName(CacheOutcome outcome) {
  switch (outcome) {
    case CacheOutcome::kOff: return "off";
    case CacheOutcome::kHit: return "hit";
    case CacheOutcome::kMiss: return "miss";
    case CacheOutcome::kRejected: return "rejected";
  }
  return "?";
}

Digest programCacheKey(const DeviceInfo& device, std::string_view source, std::string_view options) {
  std::string material;
  auto field = [&](std::string_view name, std::string_view value) {
    // length-prefixed, so no two field lists hash the same text
    material += std::string(name) + ":" + std::to_string(value.size()) + ":" + std::string(value) + "\n";
  };
  field("format", std::to_string(kFormatVersion));
  field("source", toHex(sha256(source)));
  field("options", options);
  field("device", device.name);
  field("device version", device.version);
  std::string driver, platformVersion;
  try {
    driver = device.device.getInfo<CL_DRIVER_VERSION>();
    platformVersion = device.platform.getInfo<CL_PLATFORM_VERSION>();
  } catch (const cl::Error&) {
    // a device that cannot say keeps an empty field: the rest still tell builds apart
  }
  field("driver version", driver);
  field("platform", device.platformName);
  field("platform version", platformVersion);
  return sha256(material);
}

CachedProgram buildCachedProgram(Context& context, const std::string& source, const std::string& options,
                                 const std::string& label) {
  const auto start = std::chrono::steady_clock::now();
  CachedProgram result;
  // Oclgrind checks the kernels as they are compiled: a binary would skip that.
  const std::optional<std::filesystem::path> dir =
      context.underOclgrind() ? std::nullopt : programCacheDirectory();
  if (!dir) {
    result.program = compile(context, source, options, label);
    result.seconds = secondsSince(start);
    log::debug("program " + label + ": cache off, compiled in " + secondsText(result.seconds));
    return result;
  }

  const Digest key = programCacheKey(context.info(), source, options);
  result.entry = *dir / (toHex(key) + ".bin");
  result.outcome = CacheOutcome::kMiss;
  if (std::optional<std::string> bytes = readFile(result.entry)) {
    std::optional<std::string> problem = checkEntry(*bytes, key);
    if (!problem) {
      std::string_view payload = std::string_view(*bytes).substr(sizeof(EntryHeader));
      if (std::optional<cl::Program> program = load(context, payload, options)) {
        result.program = std::move(*program);
        result.outcome = CacheOutcome::kHit;
        result.binaryBytes = payload.size();
        result.seconds = secondsSince(start);
        log::debug("program " + label + ": cache hit, loaded " + megabytes(result.binaryBytes) + " in " +
                   secondsText(result.seconds) + " (" + result.entry.string() + ")");
        return result;
      }
      problem = "refused by the device";
    }
    log::warnOnce("kernel cache: " + result.entry.string() + " is " + *problem + "; rebuilding it");
    result.outcome = CacheOutcome::kRejected;
  }

  result.program = compile(context, source, options, label);
  const double compileSeconds = secondsSince(start);
  if (ownCacheMakesBinariesDear(context.info()) && !programCacheDirectoryChosen()) {
    // the binary would compile every kernel once more here, on the render's critical path
    result.deferred = true;
    {
      std::lock_guard<std::mutex> lock(g_deferredMutex);
      const std::string hex = toHex(key);
      bool known = false;
      for (const DeferredStore& job : g_deferred) known = known || (job.key == hex && job.dir == *dir);
      if (!known) g_deferred.push_back({*dir, hex, label, options});
    }
    result.seconds = compileSeconds;
    log::debug("program " + label + ": cache " + cacheOutcomeName(result.outcome) + ", compiled in " +
               secondsText(compileSeconds) + "; its entry is stored after the render, in the background");
    return result;
  }
  std::vector<std::vector<unsigned char>> binaries;
  try {
    binaries = result.program.getInfo<CL_PROGRAM_BINARIES>();
  } catch (const cl::Error&) {
    // no binary to keep: compiled each time, as below
  }
  if (binaries.size() == 1 && !binaries[0].empty()) {
    result.binaryBytes = storeEntry(*dir, result.entry, key, binaries[0], ownCacheMakesBinariesDear(context.info()));
  } else {
    log::debug("program " + label + ": the device gives no binary; not cached");
    result.outcome = CacheOutcome::kOff;
    result.entry.clear();
  }
  result.seconds = secondsSince(start);
  log::debug("program " + label + ": cache " + cacheOutcomeName(result.outcome) + ", compiled in " +
             secondsText(compileSeconds) +
             (result.binaryBytes ? ", binary " + megabytes(result.binaryBytes) + " (fetched and stored in " +
                                       secondsText(result.seconds - compileSeconds) + ")"
                                 : std::string()));
  return result;
}

// ---------------------------------------------------------------- deferred stores

namespace {

std::filesystem::path pendingMark(const DeferredStore& job) { return job.dir / (job.key + ".pending"); }

/// Claim the job with its pending mark; false where another process holds a
/// mark younger than ten minutes (an older one is a store that died: taken over).
bool markPending(const DeferredStore& job) {
  std::error_code ec;
  std::filesystem::create_directories(job.dir, ec);
  const std::filesystem::path mark = pendingMark(job);
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int fd = ::open(mark.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return true;
    }
    if (errno != EEXIST) return false;
    struct stat st {};
    if (::stat(mark.c_str(), &st) != 0) continue;  // removed meanwhile: try again
    if (std::time(nullptr) - st.st_mtime < 600) return false;
    std::filesystem::remove(mark, ec);
  }
  return false;
}

}  // namespace

std::vector<DeferredStore> deferredProgramStores() {
  std::lock_guard<std::mutex> lock(g_deferredMutex);
  return g_deferred;
}

void setProgramStoreExecutable(const std::filesystem::path& exe) {
  if (exe.empty())
    g_storeExecutable.reset();
  else
    g_storeExecutable = exe;
}

std::string formatDeferredStores(const std::vector<DeferredStore>& jobs) {
  std::string text;
  for (const DeferredStore& job : jobs) text += job.dir.string() + "\t" + job.key + "\t" + job.label + "\t" + job.options + "\n";
  return text;
}

std::vector<DeferredStore> parseDeferredStores(const std::string& text) {
  std::vector<DeferredStore> jobs;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::size_t from = 0;
    for (std::size_t tab; fields.size() < 3 && (tab = line.find('\t', from)) != std::string::npos; from = tab + 1)
      fields.push_back(line.substr(from, tab - from));
    if (fields.size() != 3 || fields[0].empty() || fields[1].size() != 64 || fields[2].empty()) continue;
    fields.push_back(line.substr(from));
    jobs.push_back({fields[0], fields[1], fields[2], fields[3]});
  }
  return jobs;
}

bool storeDeferredProgramsInBackground(const DeviceInfo& device) {
  std::vector<DeferredStore> jobs;
  {
    std::lock_guard<std::mutex> lock(g_deferredMutex);
    jobs.swap(g_deferred);
  }
  if (jobs.empty() || !g_storeExecutable) return false;
  std::vector<DeferredStore> mine;
  for (const DeferredStore& job : jobs)
    if (markPending(job)) mine.push_back(job);
  auto unmark = [&mine]() {
    std::error_code ec;
    for (const DeferredStore& job : mine) std::filesystem::remove(pendingMark(job), ec);
  };
  if (mine.empty()) return false;

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    unmark();
    return false;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  // its own process group, so a terminal's Ctrl-C does not reach it; the same session, so that
  // at its lowest priority it yields to the user's next command (one scheduling group per session)
  posix_spawnattr_setpgroup(&attr, 0);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  const std::string exe = g_storeExecutable->string(), index = std::to_string(device.index);
  std::vector<std::string> args = {exe, "store-programs", "--device", index};
  if (std::optional<std::filesystem::path> kernels = kernelDirectory()) {
    args.push_back("--kernel-dir");
    args.push_back(kernels->string());
  }
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, exe.c_str(), &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(fds[0]);
  if (spawned != 0) {
    ::close(fds[1]);
    unmark();
    return false;
  }
  // a few hundred bytes: the pipe takes them whole; a child that died must not kill this process
  const std::string text = formatDeferredStores(mine);
  struct sigaction ignore {}, previous {};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &previous);
  const bool written = ::write(fds[1], text.data(), text.size()) == ssize_t(text.size());
  sigaction(SIGPIPE, &previous, nullptr);
  ::close(fds[1]);
  log::debug(std::to_string(mine.size()) + " program(s) handed to a background process (pid " + std::to_string(pid) +
             ") to store in the kernel cache" + (written ? "" : "; writing its jobs failed"));
  return true;
}

bool storeProgramEntry(Context& context, const std::string& source, const DeferredStore& job) {
  struct Unmark {
    std::filesystem::path mark;
    ~Unmark() {
      std::error_code ec;
      std::filesystem::remove(mark, ec);
    }
  } unmark{pendingMark(job)};
  const Digest key = programCacheKey(context.info(), source, job.options);
  if (toHex(key) != job.key) {
    log::debug("program " + job.label + ": not stored (this source, these options and this device give another key)");
    return false;
  }
  const std::filesystem::path entry = job.dir / (job.key + ".bin");
  if (std::optional<std::string> bytes = readFile(entry); bytes && !checkEntry(*bytes, key)) return true;
  cl::Program program = compile(context, source, job.options, job.label);
  std::vector<std::vector<unsigned char>> binaries;
  try {
    binaries = program.getInfo<CL_PROGRAM_BINARIES>();
  } catch (const cl::Error&) {
  }
  if (binaries.size() != 1 || binaries[0].empty()) {
    log::debug("program " + job.label + ": the device gives no binary; not cached");
    return false;
  }
  storeEntry(job.dir, entry, key, binaries[0], ownCacheMakesBinariesDear(context.info()));
  return true;
}

}  // namespace wt
