// The context's helpers: Context::fill sets the range it is given and
// nothing else (under Oclgrind it rewrites the whole buffer to do so);
// Context::launch's first launch of a kernel on PoCL is wide enough that
// PoCL compiles one work-group function for every image size.
#include "device_fixture.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>
#include <vector>

namespace wt {
namespace {

TEST(Context, FillSetsItsRangeOnly) {
  Context& ctx = test::deviceContext();
  const std::size_t words = 64;
  cl::Buffer buffer(ctx.context(), CL_MEM_READ_WRITE, words * sizeof(cl_uint));
  ctx.fill(buffer, 7u, 0, words * sizeof(cl_uint));
  ctx.fill(buffer, 0u, 4 * sizeof(cl_uint), 3 * sizeof(cl_uint));
  ctx.fill(buffer, 9u, (words - 1) * sizeof(cl_uint), sizeof(cl_uint));
  std::vector<cl_uint> got(words);
  ctx.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, words * sizeof(cl_uint), got.data());
  for (std::size_t i = 0; i < words; ++i) {
    cl_uint want = i == words - 1 ? 9u : (i >= 4 && i < 7) ? 0u : 7u;
    EXPECT_EQ(got[i], want) << "word " << i;
  }
}

TEST(Context, FillRejectsUnalignedRanges) {
  Context& ctx = test::deviceContext();
  cl::Buffer buffer(ctx.context(), CL_MEM_READ_WRITE, 64);
  EXPECT_THROW(ctx.fill(buffer, 0u, 2, 8), DeviceError);
  EXPECT_THROW(ctx.fill(buffer, 0u, 0, 6), DeviceError);
}

// PoCL's kernel cache folder, as PoCL chooses it (lib/CL/pocl_cache.c).
std::filesystem::path poclKernelCache() {
  if (const char* dir = std::getenv("POCL_CACHE_DIR"); dir && *dir) return dir;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::filesystem::path(xdg) / "pocl/kcache";
  const char* home = std::getenv("HOME");
  return std::filesystem::path(home ? home : "") / ".cache/pocl/kcache";
}

TEST(Context, PoclCompilesOneWorkGroupFunctionForNarrowAndWideLaunches) {
  Context& ctx = test::deviceContext();
  if (!ctx.widenFirstLaunches()) GTEST_SKIP() << "not PoCL's CPU device: " << ctx.info().platformName;
  // a kernel name of its own, so that PoCL compiles it here and its cache
  // folder holds this test's variants only
  const std::string name =
      "widen_probe_" + std::to_string(getpid()) + "_" +
      std::to_string(std::chrono::steady_clock::now().time_since_epoch().count() % 1000000007);
  const std::string source = "__kernel void " + name +
                             "(uint count, __global uint* out) {\n"
                             "  uint i = get_global_id(0);\n"
                             "  if (i >= count) return;\n"
                             "  out[i] = i + 1u;\n"
                             "}\n";
  cl::Program program(ctx.context(), source);
  program.build();
  cl::Kernel kernel(program, name.c_str());
  const cl_uint words = 300;
  cl::Buffer out(ctx.context(), CL_MEM_READ_WRITE, words * sizeof(cl_uint));
  ctx.fill(out, 0u, 0, words * sizeof(cl_uint));
  kernel.setArg(1, out);

  // narrow launches, as a small image makes: the first one wide, the rest as asked
  for (cl_uint count : {100u, 200u}) {
    kernel.setArg(0, count);
    ctx.launch("widen_probe", kernel, count);
    ctx.finish();
    if (count == 100u)
      EXPECT_GE(ctx.lastGlobalSize(), Context::kPoclSmallGridWidth);
    else
      EXPECT_EQ(ctx.lastGlobalSize(), 256u);
  }
  std::vector<cl_uint> got(words);
  ctx.queue().enqueueReadBuffer(out, CL_TRUE, 0, words * sizeof(cl_uint), got.data());
  for (cl_uint i = 0; i < words; ++i) EXPECT_EQ(got[i], i < 200u ? i + 1u : 0u) << "word " << i;

  // PoCL's cache: <kcache>/<xx>/<program hash>/<kernel>/<variant>/
  std::filesystem::path programDir;
  std::vector<std::string> variants;
  std::error_code ec;
  for (const auto& a : std::filesystem::directory_iterator(poclKernelCache(), ec))
    for (const auto& b : std::filesystem::directory_iterator(a.path(), ec))
      if (std::filesystem::is_directory(b.path() / name)) {
        programDir = b.path();
        for (const auto& v : std::filesystem::directory_iterator(b.path() / name)) variants.push_back(v.path().filename());
      }
  ASSERT_FALSE(programDir.empty()) << "no folder for kernel " << name << " in PoCL's cache " << poclKernelCache();
  // the probe's program leaves nothing in the cache, pass or fail
  struct Remove {
    std::filesystem::path dir;
    ~Remove() {
      std::error_code e;
      std::filesystem::remove_all(dir, e);
      std::filesystem::remove(dir.parent_path(), e);  // only if empty
    }
  } remove{programDir};
  ASSERT_EQ(variants.size(), 1u) << "PoCL compiled " << variants.size() << " work-group functions";
  EXPECT_EQ(variants[0].find("smallgrid"), std::string::npos) << "a narrow variant: " << variants[0];
}

// A program released and another built at once may get the same address
// (PoCL allocates both alike): the new program's first launch is still wide,
// or PoCL compiles a narrow variant for it (one per kernel of every later
// program in a process that builds many, as a test binary does).
TEST(Context, EveryNewProgramsFirstLaunchIsWide) {
  Context& ctx = test::deviceContext();
  if (!ctx.widenFirstLaunches()) GTEST_SKIP() << "not PoCL's CPU device: " << ctx.info().platformName;
  const std::string source =
      "__kernel void widen_again(uint count, __global uint* out) {\n"
      "  uint i = get_global_id(0);\n"
      "  if (i >= count) return;\n"
      "  out[i] = i + 1u;\n"
      "}\n";
  cl::Buffer out(ctx.context(), CL_MEM_READ_WRITE, 128 * sizeof(cl_uint));
  for (int round = 0; round < 12; ++round) {
    cl::Program program(ctx.context(), source);
    program.build();
    cl::Kernel kernel(program, "widen_again");
    kernel.setArg(0, cl_uint(100));
    kernel.setArg(1, out);
    ctx.launch("widen_again", kernel, 100);
    ctx.finish();
    EXPECT_GE(ctx.lastGlobalSize(), Context::kPoclSmallGridWidth) << "program " << round;
  }
}

}  // namespace
}  // namespace wt
