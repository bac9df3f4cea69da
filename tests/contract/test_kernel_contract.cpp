// The render stages' host declarations (host/render/stage_params.h) against
// the kernels themselves, read back through -cl-kernel-arg-info: every name
// in order, and the element type of every path-state buffer bound by name;
// and that a swapped, missing or unset argument is an error naming both.
#include "device/kernel_args.h"
#include "device/program.h"
#include "device/trace_params.h"
#include "device_fixture.h"
#include "render/path_state.h"
#include "render/stage_params.h"
#include "shared/tonemap.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

namespace wt {
namespace {

/// A program (`root`: the render program, the frame program frame.cl, or
/// the tracers' trace.cl) as the product builds it (with argument info), once
/// per binary, released with the shared device (device_fixture.h).
cl::Program programFor(bool alpha, const std::string& root) {
  auto& programs = test::sharedDevice().programs;
  const std::string key = root + (alpha ? " with alpha" : "");
  auto it = programs.find(key);
  if (it == programs.end() && root == "frame.cl") {
    // no scene switch: the renders' build without AOVs, whatever alpha is
    it = programs.emplace(key, buildFrameProgram(test::deviceContext(), false)).first;
  } else if (it == programs.end()) {
    // switches other tests build too (a small scene on this device; a
    // textured one where it has holes), so that PoCL's cache compiles each
    // program once in the suite: the parameters depend on alpha alone
    // (ParamFeatures)
    KernelFeatures features;
    features.bvhStackSize = 32;
    features.packetWidth = packetWidthFor(test::deviceContext().info());
    features.integratorMinimal = root != "trace.cl";  // the tracers' own integrator setting (Tracer)
    features.alpha = features.textures = alpha;
    features.pbr = alpha && root != "trace.cl";
    it = programs.emplace(key, buildProgram(test::deviceContext(), features, root)).first;
  }
  return it->second;
}

template <class Decl>
void expectContract(bool alpha, const std::string& root) {
  SCOPED_TRACE(std::string(Decl::kName) + (alpha ? " with alpha" : " without alpha"));
  const cl::Program program = programFor(alpha, root);
  KernelArgs<Decl> args;
  // the constructor compares the count and, with argument info, every name
  ASSERT_NO_THROW(args = KernelArgs<Decl>(program, ParamFeatures{alpha}));
  const auto names = kernelArgNames(args.kernel());
  const auto types = kernelArgTypeNames(args.kernel());
  ASSERT_TRUE(names && types) << "buildProgram must keep argument info (-cl-kernel-arg-info): without it "
                                 "KernelBinding checks only the argument count at start-up";
  for (const PathBufferDesc& b : PathState::kBuffers) {
    for (std::size_t i = 0; i < names->size(); ++i) {
      if ((*names)[i] != b.name) continue;
      EXPECT_EQ((*types)[i], std::string(b.deviceType) + "*")
          << "kernel '" << Decl::kName << "' takes " << b.name << " as " << (*types)[i] << ", PathState says "
          << b.deviceType;
    }
  }
}

template <class... Decls>
void expectAll(bool alpha, const std::string& root) {
  (expectContract<Decls>(alpha, root), ...);
}

TEST(KernelContract, RenderStagesMatchTheirHostDeclarations) {
  for (bool alpha : {false, true})
    expectAll<stage::Generate, stage::Extend, stage::ExtendPacket, stage::Shade, stage::Connect,
              stage::ConnectPacket, stage::ConnectStream>(alpha, "wavetrace.cl");
}

TEST(KernelContract, FrameStagesMatchTheirHostDeclarations) {
  expectAll<stage::Accumulate, stage::Resolve, stage::Tonemap, stage::LogLuminance, stage::TonemapExposure>(
      false, "frame.cl");
}

TEST(KernelContract, TraceKernelsMatchTheirHostDeclarations) {
  for (bool alpha : {false, true})
    expectAll<trace::Closest, trace::ClosestPacket, trace::Occluded, trace::OccludedPacket, trace::OccludedStream>(
        alpha, "trace.cl");
}

// what the checks must catch: a declaration that swaps, drops or leaves an argument unset
struct SwappedTonemap {
  static constexpr std::string_view kName = "tonemap";
  static constexpr auto kParams = params("frame", "tonemap", "exposure", "pixels", "mean");
};
struct ShortTonemap {
  static constexpr std::string_view kName = "tonemap";
  static constexpr auto kParams = params("frame", "mean");
};

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

TEST(KernelContract, ASwappedArgumentIsAStartUpErrorNamingKernelAndArgument) {
  const std::string what = errorOf([] { KernelArgs<SwappedTonemap>(programFor(false, "frame.cl"), {}); });
  EXPECT_NE(what.find("'tonemap'"), std::string::npos) << what;
  EXPECT_NE(what.find("'mean'"), std::string::npos) << what;
  EXPECT_NE(what.find("'pixels'"), std::string::npos) << what;
}

TEST(KernelContract, AMissingArgumentIsAStartUpError) {
  const std::string what = errorOf([] { KernelArgs<ShortTonemap>(programFor(false, "frame.cl"), {}); });
  EXPECT_NE(what.find("'tonemap' takes 5 arguments, its host declaration 2"), std::string::npos) << what;
}

TEST(KernelContract, AnArgumentNeverSetIsAnErrorAtLaunch) {
  KernelArgs<stage::Tonemap> args(programFor(false, "frame.cl"), {});
  cl::Buffer b(test::deviceContext().context(), CL_MEM_READ_WRITE, 16);
  args.set("frame", WtFrameParams{}).set("tonemap", WtTonemapParams{}).set("exposure", b).set("pixels", b);
  const std::string what = errorOf([&] { args.requireBound(); });
  EXPECT_NE(what.find("'tonemap' launched with argument 'mean' (3) never set"), std::string::npos) << what;
  args.set("mean", b);
  EXPECT_NO_THROW(args.requireBound());
}

TEST(KernelContract, AFeatureGatedArgumentIsAbsentWithoutItsFeature) {
  KernelArgs<stage::Extend> args(programFor(false, "wavetrace.cl"), {});
  const std::string what = errorOf([&] { args.set("alpha_key", cl_uint(0)); });
  EXPECT_NE(what.find("'extend' has no argument 'alpha_key'"), std::string::npos) << what;
}

}  // namespace
}  // namespace wt
