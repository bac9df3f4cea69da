// Helpers shared by the tests.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

namespace wt::test {

/// ../shared/assets beside the clone.
inline std::filesystem::path assetsDir() { return WT_ASSETS_DIR; }

/// A file under ../shared/assets, or skip the test saying why.
#define WT_REQUIRE_ASSET(var, rel)                                                        \
  const std::filesystem::path var = ::wt::test::assetsDir() / (rel);                      \
  if (!std::filesystem::exists(var))                                                      \
  GTEST_SKIP() << "SKIPPED: asset " << var.string()                                       \
               << " is absent (../shared/assets is not beside this clone)"

/// A device test's problem size (work-items, samples): `full`, or `small` when
/// WT_TEST_SMALL is set and not 0. scripts/oclgrind sets it: under the
/// simulator a work-item costs about 1e4 times what it costs on PoCL, and a
/// checker needs every code path run, not statistical power. Every assertion
/// of a test must hold at both sizes.
inline unsigned testSize(unsigned full, unsigned small) {
  const char* value = std::getenv("WT_TEST_SMALL");
  return value && *value && std::string_view(value) != "0" ? small : full;
}

/// The same bit pattern (so +0 and -0 differ and a NaN matches itself).
inline bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// A file's bytes (none if it cannot be read).
inline std::vector<char> readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// A scratch folder under the build tree for files a test writes.
inline std::filesystem::path scratchDir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(WT_TEST_BINARY_DIR) / "scratch" / name;
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace wt::test
