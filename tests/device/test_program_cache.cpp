// The program cache (host/device/program_cache.cpp): a second build loads
// the entry; a truncated, bit-flipped or stale entry is detected, warned
// about and rebuilt; other options miss; an unwritable folder only warns;
// on PoCL's CPU device the default folder's stores are deferred.
// Two processes at once: tests/program_cache_check.cmake.
#include "device/program_cache.h"
#include "device_fixture.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <optional>
#include <vector>

namespace wt {
namespace {

namespace fs = std::filesystem;

// a tiny program, so each build takes a fraction of a second
const std::string kSource =
    "__kernel void twice(__global uint* out, uint count) {\n"
    "  uint i = get_global_id(0);\n"
    "  if (i >= count) return;\n"
    "  out[i] = 2u * i + OFFSET;\n"
    "}\n";

/// A fresh cache folder for one test, set as the cache; the default is
/// restored when it goes.
struct ScratchCache {
  fs::path dir;
  explicit ScratchCache(const std::string& name)
      : dir(fs::path(WT_TEST_BINARY_DIR) / "scratch" / "program_cache" / name) {
    fs::remove_all(dir);
    setProgramCacheDirectory(dir.string());
  }
  ~ScratchCache() { setProgramCacheDirectory(""); }
};

/// Run `twice` and check what it wrote: a loaded program must work, not just load.
void expectRuns(CachedProgram& built, cl_uint offset) {
  Context& ctx = test::deviceContext();
  const cl_uint count = 100;
  cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, count * sizeof(cl_uint));
  cl::Kernel k(built.program, "twice");
  k.setArg(0, out), k.setArg(1, count);
  ctx.launch("twice", k, count, 64);
  std::vector<cl_uint> got(count);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, count * sizeof(cl_uint), got.data());
  for (cl_uint i = 0; i < count; ++i) ASSERT_EQ(got[i], 2u * i + offset) << "item " << i;
}

CachedProgram build(cl_uint offset = 1) {
  return buildCachedProgram(test::deviceContext(), kSource, "-cl-std=CL1.2 -D OFFSET=" + std::to_string(offset),
                            "test");
}

/// Build while capturing stderr; returns what was printed.
std::string buildCapturing(CachedProgram& built) {
  testing::internal::CaptureStderr();
  built = build();
  return testing::internal::GetCapturedStderr();
}

/// Build once, damage the entry with `damage`, then require the next build
/// to reject it with a warning naming `reason`, to work, and to leave an
/// entry the build after loads.
void expectRebuilt(const std::string& name, const std::function<void(const fs::path&)>& damage,
                   const std::string& reason) {
  ScratchCache cache(name);
  CachedProgram first = build();
  ASSERT_EQ(first.outcome, CacheOutcome::kMiss);
  ASSERT_TRUE(fs::exists(first.entry));
  damage(first.entry);
  CachedProgram second;
  const std::string err = buildCapturing(second);
  EXPECT_EQ(second.outcome, CacheOutcome::kRejected) << cacheOutcomeName(second.outcome);
  EXPECT_NE(err.find("warning: kernel cache: " + first.entry.string() + " is " + reason), std::string::npos) << err;
  expectRuns(second, 1);
  CachedProgram third = build();
  EXPECT_EQ(third.outcome, CacheOutcome::kHit) << "the rebuilt entry is valid";
  expectRuns(third, 1);
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void writeAll(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

TEST(ProgramCache, Sha256MatchesTheStandardVectors) {
  EXPECT_EQ(toHex(sha256("")), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(toHex(sha256("abc")), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  // 56 bytes: the length no longer fits the first padding block
  EXPECT_EQ(toHex(sha256("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq")),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(ProgramCache, SecondBuildLoadsTheEntry) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  ScratchCache cache("second_build");
  CachedProgram first = build();
  EXPECT_EQ(first.outcome, CacheOutcome::kMiss);
  ASSERT_TRUE(fs::exists(first.entry)) << first.entry;
  EXPECT_EQ(first.entry.parent_path(), cache.dir);
  EXPECT_GT(first.binaryBytes, 0u);
  expectRuns(first, 1);
  CachedProgram second = build();
  EXPECT_EQ(second.outcome, CacheOutcome::kHit);
  EXPECT_EQ(second.entry, first.entry);
  EXPECT_EQ(second.binaryBytes, first.binaryBytes);
  expectRuns(second, 1);
}

TEST(ProgramCache, OtherOptionsMiss) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  ScratchCache cache("other_options");
  CachedProgram one = build(1);
  CachedProgram two = build(5);
  EXPECT_EQ(one.outcome, CacheOutcome::kMiss);
  EXPECT_EQ(two.outcome, CacheOutcome::kMiss) << "a build with other options must not load the first's binary";
  EXPECT_NE(one.entry, two.entry);
  expectRuns(two, 5);
  CachedProgram again = build(1);
  EXPECT_EQ(again.outcome, CacheOutcome::kHit);
  expectRuns(again, 1);
}

TEST(ProgramCache, KeyCoversSourceOptionsAndDevice) {
  const DeviceInfo& device = test::deviceContext().info();
  const Digest key = programCacheKey(device, kSource, "-D OFFSET=1");
  EXPECT_EQ(key, programCacheKey(device, kSource, "-D OFFSET=1"));
  EXPECT_NE(key, programCacheKey(device, kSource + " ", "-D OFFSET=1"));
  EXPECT_NE(key, programCacheKey(device, kSource, "-D OFFSET=2"));
  DeviceInfo other = device;
  other.name += "x";
  EXPECT_NE(key, programCacheKey(other, kSource, "-D OFFSET=1"));
  other = device;
  other.version += "x";
  EXPECT_NE(key, programCacheKey(other, kSource, "-D OFFSET=1"));
  other = device;
  other.platformName += "x";
  EXPECT_NE(key, programCacheKey(other, kSource, "-D OFFSET=1"));
}

TEST(ProgramCache, TruncatedEntryIsRebuilt) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  expectRebuilt("truncated", [](const fs::path& entry) { fs::resize_file(entry, fs::file_size(entry) / 2); },
                "truncated");
}

TEST(ProgramCache, EntryCutInsideItsHeaderIsRebuilt) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  expectRebuilt("header_cut", [](const fs::path& entry) { fs::resize_file(entry, 20); }, "truncated");
}

TEST(ProgramCache, BitFlippedEntryIsRebuilt) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  expectRebuilt(
      "bit_flip",
      [](const fs::path& entry) {
        std::string bytes = readAll(entry);
        bytes[bytes.size() * 3 / 4] ^= 0x10;  // in the payload: only the checksum can tell
        writeAll(entry, bytes);
      },
      "corrupt (checksum mismatch)");
}

TEST(ProgramCache, EntryWithAnotherKeyIsStale) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  expectRebuilt(
      "stale_key",
      [](const fs::path& entry) {
        std::string bytes = readAll(entry);
        bytes[16] ^= 0x01;  // the key's first byte (after magic, version, header size)
        writeAll(entry, bytes);
      },
      "stale");
}

TEST(ProgramCache, EntryOfAnotherFormatIsStale) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  expectRebuilt(
      "stale_format",
      [](const fs::path& entry) {
        std::string bytes = readAll(entry);
        bytes[8] = 99;  // the format version's low byte
        writeAll(entry, bytes);
      },
      "stale (format version 99");
}

TEST(ProgramCache, UnwritableFolderIsAWarning) {
  if (test::deviceContext().underOclgrind()) GTEST_SKIP() << "the cache is off under Oclgrind";
  ScratchCache cache("unwritable");
  fs::create_directories(cache.dir);
  writeAll(cache.dir / "file", "a file where the cache folder should be");
  setProgramCacheDirectory((cache.dir / "file" / "kernels").string());
  CachedProgram built;
  const std::string err = buildCapturing(built);
  EXPECT_NE(err.find("warning: kernel cache: cannot create"), std::string::npos) << err;
  expectRuns(built, 1);
}

/// Set or unset an environment variable for a scope.
struct ScopedEnv {
  std::string name;
  std::optional<std::string> before;
  ScopedEnv(std::string n, const char* value) : name(std::move(n)) {
    if (const char* old = std::getenv(name.c_str())) before = old;
    if (value) setenv(name.c_str(), value, 1);
    else unsetenv(name.c_str());
  }
  ~ScopedEnv() {
    if (before) setenv(name.c_str(), before->c_str(), 1);
    else unsetenv(name.c_str());
  }
};

TEST(ProgramCache, FolderFollowsFlagVariableAndXdg) {
  ScopedEnv home("HOME", "/home/someone");
  ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
  ScopedEnv var("WAVETRACE_CACHE_DIR", nullptr);
  setProgramCacheDirectory("");
  EXPECT_EQ(programCacheDirectory(), fs::path("/home/someone/.cache/wavetrace/kernels"));
  {
    ScopedEnv set("XDG_CACHE_HOME", "/xdg");
    EXPECT_EQ(programCacheDirectory(), fs::path("/xdg/wavetrace/kernels"));
    ScopedEnv chosen("WAVETRACE_CACHE_DIR", "/chosen");
    EXPECT_EQ(programCacheDirectory(), fs::path("/chosen"));
    setProgramCacheDirectory("/flag");
    EXPECT_EQ(programCacheDirectory(), fs::path("/flag")) << "the flag wins over the variable";
    setProgramCacheDirectory("off");
    EXPECT_FALSE(programCacheDirectory().has_value());
    setProgramCacheDirectory("");
    ScopedEnv off("WAVETRACE_CACHE_DIR", "off");
    EXPECT_FALSE(programCacheDirectory().has_value());
  }
  ScopedEnv noHome("HOME", nullptr);
  EXPECT_FALSE(programCacheDirectory().has_value()) << "no HOME and no XDG_CACHE_HOME: nowhere to cache";
}

// PoCL's CPU device compiles every kernel once more to hand out a binary:
// with the default folder a miss does not ask for it and leaves the entry
// to storeProgramEntry (run by a background process after the render); the
// next build loads it, and a damaged one is rebuilt, never trusted.
TEST(ProgramCache, PoclCpuDefaultFolderDefersTheStore) {
  Context& ctx = test::deviceContext();
  if (!ownCacheMakesBinariesDear(ctx.info())) GTEST_SKIP() << "not PoCL's CPU device: a miss stores at once";
  ScratchCache cache("pocl_default");
  ScopedEnv home("HOME", cache.dir.c_str());
  ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
  ScopedEnv var("WAVETRACE_CACHE_DIR", nullptr);
  setProgramCacheDirectory("");
  EXPECT_FALSE(programCacheDirectoryChosen());
  storeDeferredProgramsInBackground(ctx.info());  // forgets earlier tests' stores: no executable is set here
  const fs::path folder = cache.dir / ".cache" / "wavetrace" / "kernels";

  CachedProgram first = build();
  EXPECT_EQ(first.outcome, CacheOutcome::kMiss) << cacheOutcomeName(first.outcome);
  EXPECT_TRUE(first.deferred);
  EXPECT_EQ(first.binaryBytes, 0u) << "the binary was fetched on the render's path";
  EXPECT_FALSE(fs::exists(first.entry));
  expectRuns(first, 1);
  const std::vector<DeferredStore> jobs = deferredProgramStores();
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].dir, folder);
  EXPECT_EQ(jobs[0].dir / (jobs[0].key + ".bin"), first.entry);
  // the jobs cross a pipe as text
  const std::vector<DeferredStore> parsed = parseDeferredStores(formatDeferredStores(jobs) + "a malformed line\n");
  ASSERT_EQ(parsed.size(), 1u);
  EXPECT_EQ(parsed[0].dir, jobs[0].dir);
  EXPECT_EQ(parsed[0].key, jobs[0].key);
  EXPECT_EQ(parsed[0].label, "test");
  EXPECT_EQ(parsed[0].options, jobs[0].options);
  EXPECT_FALSE(storeDeferredProgramsInBackground(ctx.info())) << "no executable set: nothing starts";
  EXPECT_TRUE(deferredProgramStores().empty()) << "handed on (or dropped) once";

  // what the background process does
  EXPECT_TRUE(storeProgramEntry(ctx, kSource, parsed[0]));
  ASSERT_TRUE(fs::exists(first.entry));
  CachedProgram second = build();
  EXPECT_EQ(second.outcome, CacheOutcome::kHit) << cacheOutcomeName(second.outcome);
  EXPECT_FALSE(second.deferred);
  expectRuns(second, 1);

  // a bit flipped in the payload: rejected with a warning, compiled, the store deferred again
  std::string bytes = readAll(first.entry);
  bytes[bytes.size() - 1] ^= 0x10;
  writeAll(first.entry, bytes);
  CachedProgram third;
  const std::string err = buildCapturing(third);
  EXPECT_EQ(third.outcome, CacheOutcome::kRejected) << cacheOutcomeName(third.outcome);
  EXPECT_TRUE(third.deferred);
  EXPECT_NE(err.find("is corrupt (checksum mismatch)"), std::string::npos) << err;
  expectRuns(third, 1);
  // the store replaces the damaged entry
  EXPECT_TRUE(storeProgramEntry(ctx, kSource, parsed[0]));
  EXPECT_EQ(build().outcome, CacheOutcome::kHit);

  // a job whose key this source and these options do not give is not stored
  DeferredStore other = parsed[0];
  other.options += " -D UNUSED=1";
  fs::remove(first.entry);
  EXPECT_FALSE(storeProgramEntry(ctx, kSource, other));
  EXPECT_FALSE(fs::exists(first.entry));
  storeDeferredProgramsInBackground(ctx.info());
}

// A job another process is storing (its pending mark) is not handed on twice.
TEST(ProgramCache, PendingStoreIsNotStartedTwice) {
  Context& ctx = test::deviceContext();
  if (!ownCacheMakesBinariesDear(ctx.info())) GTEST_SKIP() << "not PoCL's CPU device: a miss stores at once";
  ScratchCache cache("pending");
  ScopedEnv home("HOME", cache.dir.c_str());
  ScopedEnv xdg("XDG_CACHE_HOME", nullptr);
  ScopedEnv var("WAVETRACE_CACHE_DIR", nullptr);
  setProgramCacheDirectory("");
  storeDeferredProgramsInBackground(ctx.info());
  // a stand-in for `wavetrace store-programs` that reads nothing and leaves the mark
  setProgramStoreExecutable("/bin/true");
  CachedProgram first = build();
  ASSERT_TRUE(first.deferred);
  const fs::path mark = first.entry.parent_path() / (first.entry.stem().string() + ".pending");
  EXPECT_TRUE(storeDeferredProgramsInBackground(ctx.info()));
  EXPECT_TRUE(fs::exists(mark));
  build();
  EXPECT_FALSE(storeDeferredProgramsInBackground(ctx.info())) << "started again while the first store is pending";
  // a mark ten minutes old is a store that died: taken over
  fs::last_write_time(mark, fs::file_time_type::clock::now() - std::chrono::minutes(11));
  build();
  EXPECT_TRUE(storeDeferredProgramsInBackground(ctx.info()));
  setProgramStoreExecutable("");
  storeDeferredProgramsInBackground(ctx.info());
}

/// A PoCL format-9 binary as pocl_binary_serialize lays it out: `rootFiles`
/// (name, content) in the program folder, one kernel "k" carrying one file.
std::vector<unsigned char> poclBinary(const std::vector<std::pair<std::string, std::string>>& rootFiles,
                                      std::uint32_t version = 9) {
  std::vector<unsigned char> b;
  auto le = [&b](std::uint64_t v, int width) {
    for (int i = 0; i < width; ++i) b.push_back(static_cast<unsigned char>(v >> (8 * i)));
  };
  auto text = [&](const std::string& s) { le(s.size(), 4), b.insert(b.end(), s.begin(), s.end()); };
  const std::string id("poclbin\0", 8);
  b.insert(b.end(), id.begin(), id.end());
  le(0x1234, 8), le(version, 4), le(1, 4), le(0, 8), le(1, 4);
  std::string hash = "AB/" + std::string(37, 'C') + '\0';
  b.insert(b.end(), hash.begin(), hash.end());
  std::vector<unsigned char> root;
  std::swap(b, root);
  for (const auto& [name, content] : rootFiles) text(name), text(content);
  std::swap(b, root);
  le(root.size(), 8);
  b.insert(b.end(), root.begin(), root.end());
  // the kernel record: sizes, name, counts, metadata, then its files
  std::vector<unsigned char> files;
  std::swap(b, files);
  text("/k/64-1-1-goffs0/k.so"), text("machine code");
  std::swap(b, files);
  const std::size_t start = b.size();
  le(0, 8), le(files.size(), 8), le(0, 4);
  text("k"), le(0, 4), le(0, 4), le(0, 8), le(0, 8), le(0, 8), text(""), le(0, 8);
  b.insert(b.end(), files.begin(), files.end());
  const std::uint64_t record = b.size() - start;
  for (int i = 0; i < 8; ++i) b[start + std::size_t(i)] = static_cast<unsigned char>(record >> (8 * i));
  return b;
}

bool holds(const std::vector<unsigned char>& bytes, const std::string& text) {
  return std::search(bytes.begin(), bytes.end(), text.begin(), text.end()) != bytes.end();
}

// The stored binary drops program.bc (PoCL would parse it on every load)
// and names a build hash of its own; the kernels' records stay byte for byte.
TEST(ProgramCache, PoclBinaryWithoutBitcodeKeepsTheKernels) {
  const std::vector<unsigned char> full = poclBinary({{"/program.bc", std::string(1000, 'x')}});
  std::optional<std::vector<unsigned char>> lean = poclBinaryWithoutBitcode(full);
  ASSERT_TRUE(lean);
  EXPECT_FALSE(holds(*lean, "/program.bc"));
  EXPECT_LT(lean->size() + 900, full.size()) << "the bitcode went, a small marker came";
  const std::size_t hashAt = 36, hashEnd = hashAt + 41;
  EXPECT_TRUE(std::equal(full.begin(), full.begin() + hashAt, lean->begin())) << "the header before the hash";
  const std::string hash(lean->begin() + hashAt, lean->begin() + hashEnd);
  EXPECT_NE(hash, std::string(full.begin() + hashAt, full.begin() + hashEnd));
  EXPECT_EQ(hash[2], '/');
  EXPECT_EQ(hash.back(), '\0');
  // the kernel's record is the tail of both
  const std::size_t tail = full.size() - (hashEnd + 8 + 4 + 11 + 4 + 1000);
  EXPECT_TRUE(std::equal(full.end() - std::ptrdiff_t(tail), full.end(), lean->end() - std::ptrdiff_t(tail)));
  EXPECT_EQ(poclBinaryWithoutBitcode(*lean), std::nullopt) << "nothing left to drop";
  // another binary gets another hash (its files must not meet these)
  const std::vector<unsigned char> other = poclBinaryWithoutBitcode(poclBinary({{"/program.bc", "y"}})).value();
  EXPECT_NE(std::string(other.begin() + hashAt, other.begin() + hashEnd), hash);

  // anything not exactly this layout is stored whole
  std::vector<unsigned char> cut = full;
  cut.pop_back();
  EXPECT_EQ(poclBinaryWithoutBitcode(cut), std::nullopt) << "truncated";
  std::vector<unsigned char> longer = full;
  longer.push_back(0);
  EXPECT_EQ(poclBinaryWithoutBitcode(longer), std::nullopt) << "a byte past the last kernel";
  EXPECT_EQ(poclBinaryWithoutBitcode(poclBinary({{"/program.bc", "x"}}, 8)), std::nullopt) << "another format";
  EXPECT_EQ(poclBinaryWithoutBitcode(poclBinary({{"/program.bc", "x"}, {"/other", "y"}})), std::nullopt)
      << "other program files";
  std::vector<unsigned char> notPocl = full;
  notPocl[0] = 'P';
  EXPECT_EQ(poclBinaryWithoutBitcode(notPocl), std::nullopt);
}

// On PoCL's CPU device the entry holds no bitcode, and the program it loads
// runs at the local size it was fetched for and at another (PoCL's generic
// work-group function).
TEST(ProgramCache, PoclCpuEntryLoadsWithoutBitcode) {
  Context& ctx = test::deviceContext();
  if (!ownCacheMakesBinariesDear(ctx.info())) GTEST_SKIP() << "not PoCL's CPU device";
  ScratchCache cache("pocl_lean");
  CachedProgram first = build(3);
  ASSERT_EQ(first.outcome, CacheOutcome::kMiss);
  expectRuns(first, 3);
  const std::string bytes = readAll(first.entry);
  EXPECT_EQ(bytes.find("/program.bc"), std::string::npos);
  EXPECT_NE(bytes.find("/wavetrace-without-bitcode"), std::string::npos);
  EXPECT_NE(bytes.find("twice.so"), std::string::npos) << "the work-group functions travel in the entry";
  for (std::size_t local : {64, 32}) {
    CachedProgram hit = build(3);
    ASSERT_EQ(hit.outcome, CacheOutcome::kHit) << cacheOutcomeName(hit.outcome);
    const cl_uint count = 100;
    cl::Buffer out(ctx.context(), CL_MEM_WRITE_ONLY, count * sizeof(cl_uint));
    cl::Kernel k(hit.program, "twice");
    k.setArg(0, out), k.setArg(1, count);
    ctx.launch("twice", k, count, local);
    std::vector<cl_uint> got(count);
    ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, count * sizeof(cl_uint), got.data());
    for (cl_uint i = 0; i < count; ++i) ASSERT_EQ(got[i], 2u * i + 3u) << "item " << i << ", local size " << local;
  }
}

TEST(ProgramCache, OffCompilesWithoutAnEntry) {
  ScratchCache cache("off");
  setProgramCacheDirectory("off");
  CachedProgram built = build();
  EXPECT_EQ(built.outcome, CacheOutcome::kOff);
  EXPECT_TRUE(built.entry.empty());
  EXPECT_FALSE(fs::exists(cache.dir));
  expectRuns(built, 1);
}

}  // namespace
}  // namespace wt
