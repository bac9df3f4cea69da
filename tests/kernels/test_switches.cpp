// The kernels' compile-time switches (kernels/switches.h): every one must be
// set by kernelDefines, and a build without one fails naming it.
#include "device/program.h"
#include "device_fixture.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace wt {
namespace {

/// The build log of the render program (or `root`) built with `options`;
/// `built` says whether the build succeeded.
std::string buildLog(const std::string& options, bool* built, const std::string& root = "wavetrace.cl") {
  Context& context = test::deviceContext();
  cl::Program program(context.context(), expandKernelSource(root));
  *built = true;
  try {
    program.build({context.info().device}, options.c_str());
  } catch (const cl::Error&) {
    *built = false;
  }
  return program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(context.info().device);
}

TEST(Switches, EveryMissingSwitchFailsTheBuildNamingIt) {
  // each -D option of kernelDefines left out in turn: the device compiler
  // stops at kernels/switches.h with the switch's name, never takes a default
  const std::vector<std::string> defines = kernelDefines(KernelFeatures{});
  ASSERT_GE(defines.size(), 15u);
  for (std::size_t omitted = 0; omitted < defines.size(); ++omitted) {
    const std::string name = defines[omitted].substr(3, defines[omitted].find('=') - 3);  // "-D NAME=v"
    std::string options = "-cl-std=CL1.2";
    for (std::size_t i = 0; i < defines.size(); ++i)
      if (i != omitted) options += " " + defines[i];
    bool built = false;
    const std::string log = buildLog(options, &built);
    EXPECT_FALSE(built) << "the program built without " << name;
    EXPECT_NE(log.find(name + " not set"), std::string::npos)
        << "the build log does not name " << name << ":\n" << log.substr(0, 2000);
  }
}

TEST(Switches, TheFrameProgramWithoutItsSwitchFailsNamingIt) {
  // kernels/frame.cl reads WT_AOV alone (frameProgramDefines), and checks it itself
  ASSERT_EQ(frameProgramDefines(false).size(), 1u);
  bool built = true;
  const std::string log = buildLog("-cl-std=CL1.2", &built, "frame.cl");
  EXPECT_FALSE(built) << "the frame program built without WT_AOV";
  EXPECT_NE(log.find("WT_AOV not set"), std::string::npos) << log.substr(0, 2000);
}

TEST(Switches, APacketWidthOtherThan8Or16FailsTheBuild) {
  std::string options = "-cl-std=CL1.2";
  for (const std::string& d : kernelDefines(KernelFeatures{}))
    options += " " + (d.find("WT_PACKET_WIDTH=") != std::string::npos ? std::string("-D WT_PACKET_WIDTH=4") : d);
  bool built = true;
  const std::string log = buildLog(options, &built);
  EXPECT_FALSE(built);
  EXPECT_NE(log.find("WT_PACKET_WIDTH must be 8 or 16"), std::string::npos) << log.substr(0, 2000);
}

TEST(Switches, TheDefinesOfAFeatureSetBuild) {
  // the complement: with every define given, the same source builds
  std::string options = "-cl-std=CL1.2";
  for (const std::string& d : kernelDefines(KernelFeatures{})) options += " " + d;
  bool built = false;
  const std::string log = buildLog(options, &built);
  EXPECT_TRUE(built) << log.substr(0, 2000);
  // PoCL prints clang's warning count to the user's terminal on a cold build
  EXPECT_EQ(log.find("warning"), std::string::npos) << log.substr(0, 2000);
}

}  // namespace
}  // namespace wt
