// Kernels and the default scene are compiled into the binary, and kernel
// includes expand from the embedded copies. The test kernels are not
// embedded, and each program holds its own kernels only.
#include "core/embedded.h"
#include "device/program.h"
#include "scene/generators.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

namespace wt {
namespace {

TEST(Embedded, KernelsAndDefaultSceneArePresent) {
  for (const char* root : {"wavetrace.cl", "trace.cl", "stress.cl"})
    EXPECT_TRUE(embedded::find(std::string("kernels/") + root).has_value()) << root;
  EXPECT_TRUE(embedded::find("kernels/shared/types.h").has_value());
  EXPECT_TRUE(embedded::find("scenes/cornell.gltf").has_value());
  EXPECT_FALSE(embedded::find("kernels/nope.cl").has_value());
}

TEST(Embedded, TestKernelsAreNotShipped) {
  for (const embedded::File& file : embedded::files())
    EXPECT_EQ(std::string(file.path).find("_tests.cl"), std::string::npos) << file.path << " is embedded";
  for (const char* root : {"unit_tests.cl", "env_tests.cl", "texture_tests.cl"}) {
    EXPECT_FALSE(embedded::find(std::string("kernels/") + root).has_value()) << root;
    EXPECT_TRUE(std::filesystem::exists(wt::embedded::sourceDirectory() / "kernels" / root))
        << root << ": the tests read it from the source tree";
  }
}

// The render program holds the wavefront stages (with the stream traversal
// its shadow rays may take); accumulation and tone mapping (the frame
// program), the tracers and the stress kernels are programs of their own.
TEST(Embedded, ProgramsHoldTheirOwnKernelsOnly) {
  const std::string render = expandKernelSource("wavetrace.cl");
  for (const char* stage : {"generate(", "extend(", "shade(", "connect(", "connect_stream("})
    EXPECT_NE(render.find(std::string("WT_KERNEL void ") + stage), std::string::npos) << stage;
  for (const char* foreign : {"#line 1 \"trace.cl\"", "#line 1 \"stress.cl\"", "#line 1 \"accumulate.cl\"",
                              "#line 1 \"tonemap.cl\"", "WT_KERNEL void trace_", "WT_KERNEL void test_"})
    EXPECT_EQ(render.find(foreign), std::string::npos) << foreign << " in the render program";
  const std::string frame = expandKernelSource("frame.cl");
  for (const char* stage :
       {"accumulate(", "accumulate_resolve(", "tonemap_log_luminance(", "tonemap_exposure(", "tonemap("})
    EXPECT_NE(frame.find(std::string("WT_KERNEL void ") + stage), std::string::npos) << stage;
  EXPECT_EQ(frame.find("WT_KERNEL void shade("), std::string::npos);
  const std::string trace = expandKernelSource("trace.cl");
  EXPECT_NE(trace.find("WT_KERNEL void trace_occluded_stream("), std::string::npos);
  EXPECT_EQ(trace.find("WT_KERNEL void shade("), std::string::npos);
  const std::string stress = expandKernelSource("stress.cl");
  EXPECT_NE(stress.find("WT_KERNEL void test_accumulate("), std::string::npos);
  EXPECT_EQ(stress.find("WT_KERNEL void shade("), std::string::npos);
}

/// `source` without its comments, so that a switch named in one is not counted as read.
std::string withoutComments(const std::string& source) {
  std::string out;
  for (std::size_t i = 0; i < source.size();) {
    if (source.compare(i, 2, "//") == 0) {
      i = source.find('\n', i);
      if (i == std::string::npos) break;
    } else if (source.compare(i, 2, "/*") == 0) {
      std::size_t end = source.find("*/", i + 2);
      i = end == std::string::npos ? source.size() : end + 2;
    } else {
      out += source[i++];
    }
  }
  return out;
}

// The frame program is built once for every feature set (buildFrameProgram),
// so its code must read no switch of the render program's but the ones
// frameProgramDefines gives it: another would silently read as 0.
TEST(Embedded, TheFrameProgramReadsOnlyItsOwnSwitches) {
  const std::string frame = withoutComments(expandKernelSource("frame.cl"));
  std::vector<std::string> given;
  for (const std::string& d : frameProgramDefines(false)) given.push_back(d.substr(3, d.find('=') - 3));  // "-D NAME=v"
  KernelFeatures every;
  every.primitives.fill(true);
  for (const std::string& d : kernelDefines(every)) {
    const std::string name = d.substr(3, d.find('=') - 3);
    bool read = false;
    for (std::size_t at = frame.find(name); at != std::string::npos && !read; at = frame.find(name, at + 1)) {
      const std::size_t end = at + name.size();
      read = end == frame.size() || !(std::isalnum(static_cast<unsigned char>(frame[end])) || frame[end] == '_');
    }
    const bool isGiven = std::find(given.begin(), given.end(), name) != given.end();
    EXPECT_EQ(read, isGiven) << name << (read ? " is read by the frame program, which is not built with it"
                                              : " is given to the frame program, which never reads it");
  }
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
  setKernelFallbackDirectory(wt::embedded::sourceDirectory() / "kernels");  // the test kernels' folder
  for (const char* root : {"wavetrace.cl", "trace.cl", "stress.cl", "tonemap.cl", "unit_tests.cl", "env_tests.cl",
                           "texture_tests.cl", "tonemap_tests.cl"}) {
    const std::string source = expandKernelSource(root);
    EXPECT_NE(source.find("WT_KERNEL void "), std::string::npos) << root;
    EXPECT_EQ(source.find("__kernel void"), std::string::npos) << root << ": a kernel not declared WT_KERNEL";
  }
  setKernelFallbackDirectory(std::nullopt);
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
  for (const char* layer : {"SPECULAR", "CLEARCOAT", "SHEEN"}) EXPECT_TRUE(has(std::string("-D WT_HAS_") + layer + "=0"));
}

// Only scenes whose materials use a layer compile it in; a layer on a
// Lambertian material (which has none) does not count.
TEST(Embedded, MaterialFeaturesFollowTheMaterials) {
  auto features = [](std::vector<WtMaterial> materials) {
    KernelFeatures f;
    setMaterialFeatures(f, materials);
    return f;
  };
  KernelFeatures plain = features({makeMaterial(glm::vec3(0.5f)), makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f)});
  EXPECT_TRUE(plain.pbr);
  EXPECT_FALSE(plain.transmission || plain.specular || plain.clearcoat || plain.sheen);
  EXPECT_TRUE(features({withClearcoat(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f), 0.5f, 0.1f)}).clearcoat);
  EXPECT_TRUE(features({withSheen(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f), glm::vec3(0.0f, 0.1f, 0.0f), 0.5f)}).sheen);
  EXPECT_TRUE(features({withSpecular(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f), 0.0f)}).specular);
  EXPECT_TRUE(features({withSpecular(makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f), 1.0f, glm::vec3(1, 1, 0.5f))}).specular);
  WtMaterial dense = makePbrMaterial(glm::vec3(0.5f), 0.0f, 0.5f);
  dense.ior = 2.0f;  // the opaque dielectric's F0 is no longer 0.04
  EXPECT_TRUE(features({dense}).specular);
  EXPECT_FALSE(features({withTransmission(dense, 1.0f, 2.0f)}).specular) << "all of it is the interface, which reads ior itself";
  WtMaterial metal = withSpecular(makePbrMaterial(glm::vec3(0.5f), 1.0f, 0.5f), 0.0f);
  EXPECT_FALSE(features({metal}).specular) << "a metal has no dielectric";
  metal.texture_mask |= 1u << WT_TEXTURE_SLOT_METALLIC_ROUGHNESS;
  EXPECT_TRUE(features({metal}).specular) << "a metallic texture can lower metallic below 1";
  EXPECT_TRUE(features({withTransmission(metal, 1.0f)}).transmission) << "the same for transmission";
  WtMaterial lambert = withClearcoat(withSheen(makeMaterial(glm::vec3(0.5f)), glm::vec3(1.0f), 0.5f), 1.0f, 0.5f);
  lambert.model = WT_MATERIAL_DIFFUSE;
  KernelFeatures none = features({lambert});
  EXPECT_FALSE(none.pbr || none.clearcoat || none.sheen);
}

}  // namespace
}  // namespace wt
