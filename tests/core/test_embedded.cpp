// Kernels and the default scene are compiled into the binary, and kernel
// includes expand from the embedded copies.
#include "core/embedded.h"
#include "device/program.h"

#include <gtest/gtest.h>

namespace wt {
namespace {

TEST(Embedded, KernelsAndDefaultSceneArePresent) {
  EXPECT_TRUE(embedded::find("kernels/wavetrace.cl").has_value());
  EXPECT_TRUE(embedded::find("kernels/shared/types.h").has_value());
  EXPECT_TRUE(embedded::find("scenes/cornell.gltf").has_value());
  EXPECT_FALSE(embedded::find("kernels/nope.cl").has_value());
}

TEST(Embedded, IncludesExpandOnceWithLineMarkers) {
  std::string source = expandKernelSource("wavetrace.cl");
  EXPECT_EQ(source.find("#include \""), std::string::npos);
  // shared/types.h is included by many files but expanded once
  std::size_t first = source.find("typedef struct WtBvhNode");
  ASSERT_NE(first, std::string::npos);
  EXPECT_EQ(source.find("typedef struct WtBvhNode", first + 1), std::string::npos);
  EXPECT_NE(source.find("#line 1 \"geometry/triangle.cl\""), std::string::npos);
  EXPECT_NE(source.find("WT_KERNEL void shade("), std::string::npos);
}

// Every kernel of every program root carries WT_KERNEL's vec_type_hint
// (kernels/common.h): without it Intel's CPU runtime vectorises the kernel
// across work-items and got shading wrong, which PoCL (and so CI) never shows.
TEST(Embedded, EveryKernelIsWtKernel) {
  for (const char* root : {"wavetrace.cl", "unit_tests.cl", "env_tests.cl", "texture_tests.cl"}) {
    const std::string source = expandKernelSource(root);
    EXPECT_NE(source.find("WT_KERNEL void "), std::string::npos) << root;
    EXPECT_EQ(source.find("__kernel void"), std::string::npos) << root << ": a kernel not declared WT_KERNEL";
  }
}

TEST(Embedded, MissingKernelFileIsAClearError) {
  try {
    expandKernelSource("does/not/exist.cl");
    FAIL() << "expected DeviceError";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find("does/not/exist.cl"), std::string::npos);
  }
}

TEST(Embedded, DefinesCarryEveryFeature) {
  KernelFeatures features;
  features.bvhStackSize = 96;
  std::vector<std::string> defines = kernelDefines(features);
  auto has = [&](const std::string& d) { return std::find(defines.begin(), defines.end(), d) != defines.end(); };
  EXPECT_TRUE(has("-D WT_INTEGRATOR_MINIMAL=1"));
  EXPECT_TRUE(has("-D WT_BVH_STACK_SIZE=96"));
  EXPECT_TRUE(has("-D WT_STREAM_PREFETCH=0"));
  features.streamPrefetch = true;
  defines = kernelDefines(features);
  EXPECT_TRUE(has("-D WT_STREAM_PREFETCH=1"));
}

}  // namespace
}  // namespace wt
