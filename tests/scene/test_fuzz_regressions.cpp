// Inputs the fuzzers found (tests/fuzz, scripts/fuzz), kept in
// tests/data/fuzz/ with what each must give now: a clean error that names
// the file and the problem, or a load. Every file there is listed here.
#include "scene/environment.h"
#include "core/embedded.h"
#include "scene/gltf_loader.h"

#include <gtest/gtest.h>

#include <cctype>
#include <chrono>
#include <filesystem>
#include <ostream>
#include <set>
#include <string>

namespace wt {
namespace {

struct Finding {
  const char* file;   ///< under tests/data/fuzz/
  const char* error;  ///< part of the error message; nullptr: it must load
  const char* was;    ///< what the input did before the fix
};

const Finding kFindings[] = {
    {"incomplete_huge_window.exr", "a 2621448 x 769 data window cannot fit in 334 bytes",
     "a 334-byte file with a huge data window (and chunks missing): 24 GiB of texels allocated before any "
     "pixel was read (the Release build was killed for memory)"},
    {"window_larger_than_the_data.exr", "a 16777216 x 4 data window cannot fit in 410 bytes",
     "a complete 1-chunk file whose window claims 16777216 x 4 texels: OpenEXR allocated 1.6 GB of line "
     "buffers, we 805 MB of texels, and the map loaded (OpenEXR filled it from its uninitialised buffers)"},
    {"attribute_size_mismatch.exr", "header attribute 'screenWindowCen\\x9eter' of type 'v2f' has 6 bytes, expected 8",
     "OpenEXR read 8 bytes anyway, lost step and allocated 1.8 GB for the next 'attribute'"},
    {"attribute_past_the_end.exr", "claims 1886152803 bytes, 19 follow",
     "OpenEXR allocated 1.8 GB for an attribute of a 51-byte file"},
    {"nul_line_ends_the_header.hdr", "unsupported resolution line '-Y 6 +X  \\x80",
     "stb ended the header at a line starting with NUL, the structure check did not: stb decoded a 0 x 6 "
     "image the check had never seen (and a 0-byte memcpy from a null pointer followed, UBSan)"},
    {"tiled_without_data_window.exr", "the header has no dataWindow",
     "a tiled file with 14 x 16777220 tiles and no dataWindow (OpenEXR then assumes 64 x 64): OpenEXR "
     "allocated 4 GiB for a row of tiles in InputFile::setFrameBuffer"},
    {"short_uncompressed_chunk.exr", nullptr,
     "a segfault in OpenEXR's copyIntoFrameBuffer while the EXR stream was memory-mapped (chunks shorter "
     "than their lines are read past their end); it loads now (OpenEXR fills the gap from its line buffer)"},
};

void PrintTo(const Finding& finding, std::ostream* out) { *out << finding.file; }

std::filesystem::path dataDir() { return wt::embedded::sourceDirectory() / "tests" / "data" / "fuzz"; }

/// Load by extension as the command line would; the error message, or "" when it loads.
std::string load(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  try {
    if (ext == ".gltf" || ext == ".glb") {
      loadGltf(path.string());
    } else if (ext == ".hdr" || ext == ".exr") {
      loadEnvironmentMap(path);
    } else {
      ADD_FAILURE() << path << ": no loader for '" << ext << "'";
    }
  } catch (const SceneError& e) {
    return e.what();
  } catch (const EnvironmentError& e) {
    return e.what();
  }
  return "";
}

class FuzzRegression : public ::testing::TestWithParam<Finding> {};

TEST_P(FuzzRegression, FailsCleanlyOrLoads) {
  const Finding& finding = GetParam();
  const std::filesystem::path path = dataDir() / finding.file;
  ASSERT_TRUE(std::filesystem::exists(path)) << path;
  const auto start = std::chrono::steady_clock::now();
  const std::string message = load(path);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (finding.error == nullptr) {
    EXPECT_EQ(message, "") << finding.file << " must load (before the fix: " << finding.was << ")";
  } else {
    // loadGltf names the file by its name, loadEnvironmentMap by its path
    const bool map = path.extension() == ".exr" || path.extension() == ".hdr";
    const std::string name = map ? path.string() : path.filename().string();
    EXPECT_EQ(message.rfind(name + ": ", 0), 0u) << "the message must start with the file: " << message;
    EXPECT_NE(message.find(finding.error), std::string::npos)
        << finding.file << ": expected an error containing '" << finding.error << "', got '" << message
        << "' (before the fix: " << finding.was << ")";
  }
  // every one of these is tiny: refusing it must not take long
  EXPECT_LT(seconds, 2.0) << finding.file;
}

INSTANTIATE_TEST_SUITE_P(Inputs, FuzzRegression, ::testing::ValuesIn(kFindings),
                         [](const ::testing::TestParamInfo<Finding>& info) {
                           std::string name = info.param.file;
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

TEST(FuzzRegressions, EveryCommittedInputIsListed) {
  std::set<std::string> listed;
  for (const Finding& f : kFindings) listed.insert(f.file);
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dataDir())) {
    ++files;
    EXPECT_TRUE(listed.count(entry.path().filename().string()))
        << entry.path() << " is not in kFindings (say what it must give)";
  }
  EXPECT_EQ(files, listed.size());
}

}  // namespace
}  // namespace wt
