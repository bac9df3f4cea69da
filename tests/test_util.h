// Helpers shared by the tests.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace wt::test {

/// ../shared/assets beside the clone.
inline std::filesystem::path assetsDir() { return WT_ASSETS_DIR; }

/// A file under ../shared/assets, or skip the test saying why.
#define WT_REQUIRE_ASSET(var, rel)                                                        \
  const std::filesystem::path var = ::wt::test::assetsDir() / (rel);                      \
  if (!std::filesystem::exists(var))                                                      \
  GTEST_SKIP() << "SKIPPED: asset " << var.string()                                       \
               << " is absent (../shared/assets is not beside this clone)"

/// A scratch folder under the build tree for files a test writes.
inline std::filesystem::path scratchDir(const std::string& name) {
  std::filesystem::path dir = std::filesystem::path(WT_TEST_BINARY_DIR) / "scratch" / name;
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace wt::test
