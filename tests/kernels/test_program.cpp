// Program builds: a broken kernel gives the device's build log, and the
// kernels compile with the host's shared layouts unchanged.
#include "device/program.h"
#include "device_fixture.h"
#include "test_util.h"

#include <gtest/gtest.h>

#include <fstream>

namespace wt {
namespace {

TEST(Program, BuildFailureCarriesTheBuildLog) {
  std::filesystem::path dir = test::scratchDir("broken_kernels");
  std::ofstream(dir / "wavetrace.cl") << "__kernel void generate() { this is not C; }\n";
  setKernelDirectory(dir);
  try {
    buildProgram(test::deviceContext(), KernelFeatures{});
    setKernelDirectory(std::nullopt);
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    setKernelDirectory(std::nullopt);
    std::string what = e.what();
    EXPECT_NE(what.find("building kernels"), std::string::npos) << what;
    EXPECT_NE(what.find("wavetrace.cl:1"), std::string::npos) << "no build log in: " << what;
  }
}

TEST(Program, KernelDirectoryOverridesEmbeddedSources) {
  std::filesystem::path dir = test::scratchDir("kernel_dir");
  std::ofstream(dir / "wavetrace.cl") << "#include \"extra.h\"\n__kernel void k() {}\n";
  std::ofstream(dir / "extra.h") << "// from disk\n";
  setKernelDirectory(dir);
  std::string source = expandKernelSource("wavetrace.cl");
  setKernelDirectory(std::nullopt);
  EXPECT_NE(source.find("// from disk"), std::string::npos);
}

// A second renderer or tracer with the same switches in one context takes
// the program built already; another switch or an edited source builds anew.
TEST(Program, TheSameProgramIsBuiltOncePerContext) {
  std::filesystem::path dir = test::scratchDir("built_once");
  std::ofstream(dir / "wavetrace.cl") << "__kernel void k(__global int* x) { x[0] = WT_BVH_STACK_SIZE; }\n";
  struct Restore {
    ~Restore() { setKernelDirectory(std::nullopt); }
  } restore;
  setKernelDirectory(dir);
  KernelFeatures a;
  a.bvhStackSize = 32;
  KernelFeatures b = a;
  b.bvhStackSize = 48;
  Context& context = test::deviceContext();
  cl::Program first = buildProgram(context, a);
  cl::Program again = buildProgram(context, a);
  cl::Program other = buildProgram(context, b);
  std::ofstream(dir / "wavetrace.cl") << "__kernel void k(__global int* x) { x[0] = -WT_BVH_STACK_SIZE; }\n";
  cl::Program edited = buildProgram(context, a);
  EXPECT_EQ(first(), again());
  EXPECT_NE(first(), other());
  EXPECT_NE(first(), edited());
  EXPECT_NE(other(), edited());
}

// The render program holds the stages; accumulation and tone mapping (the
// frame program) and the tracers are programs of their own.
// Built with the switches a small triangle scene gets on this device (the
// minimal integrator's for the stages, the tracer's own), which other tests
// build too: PoCL's cache then compiles each program once in the suite.
TEST(Program, EmbeddedKernelsBuild) {
  KernelFeatures features;
  features.bvhStackSize = 32;
  features.packetWidth = packetWidthFor(test::deviceContext().info());
  cl::Program program = buildProgram(test::deviceContext(), features);
  for (const char* name : {"generate", "extend", "shade", "connect", "extend_packet", "connect_packet"})
    EXPECT_NO_THROW(cl::Kernel(program, name)) << name;
  EXPECT_THROW(cl::Kernel(program, "trace_closest"), cl::Error) << "the tracers are not render stages";
  cl::Program frame = buildFrameProgram(test::deviceContext(), false);
  for (const char* name : {"accumulate", "accumulate_resolve", "tonemap", "tonemap_log_luminance", "tonemap_exposure"}) {
    EXPECT_NO_THROW(cl::Kernel(frame, name)) << name;
    EXPECT_THROW(cl::Kernel(program, name), cl::Error) << name << " is in the frame program, not the render program";
  }
  features.integratorMinimal = false;  // as Tracer builds it
  cl::Program trace = buildProgram(test::deviceContext(), features, "trace.cl");
  for (const char* name : {"trace_closest", "trace_occluded", "trace_closest_packet", "trace_occluded_packet",
                           "trace_occluded_stream"})
    EXPECT_NO_THROW(cl::Kernel(trace, name)) << name;
}

}  // namespace
}  // namespace wt
