// The OpenCL device the device tests run on (PoCL in CI), opened once.
#pragma once

#include "device/context.h"
#include "core/embedded.h"
#include "device/program.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

namespace wt::test {

/// What the tests of one binary share: the default device's context and the
/// test-only programs built on it, by root file.
struct SharedDevice {
  std::unique_ptr<Context> context;
  std::map<std::string, cl::Program> programs;
};

inline SharedDevice& sharedDevice() {
  static SharedDevice shared;
  return shared;
}

/// The default device's context, shared by every test in the binary. The
/// test kernels, which the binary does not embed, are read from the source
/// tree; the program cache is off unless WAVETRACE_CACHE_DIR says otherwise
/// (tests never write to ~/.cache; tests/device/test_program_cache.cpp
/// chooses folders of its own).
inline Context& deviceContext() {
  SharedDevice& shared = sharedDevice();
  if (!shared.context) {
    setKernelFallbackDirectory(wt::embedded::sourceDirectory() / "kernels");
    setenv("WAVETRACE_CACHE_DIR", "off", 0);
    shared.context = std::make_unique<Context>(selectDevice(""), /*profiling=*/true);
  }
  return *shared.context;
}

/// A test-only kernel program (kernels/<root>), built once per binary.
inline cl::Program testProgram(const std::string& root) {
  SharedDevice& shared = sharedDevice();
  auto it = shared.programs.find(root);
  if (it == shared.programs.end()) {
    KernelFeatures features;
    features.pbr = true;  // the metallic-roughness BSDF's tests need it compiled in
    features.transmission = true;
    features.specular = features.clearcoat = features.sheen = features.anisotropy = features.iridescence = true;  // and every layer
    features.quadLights = true;  // the rectangle lights' sampler (tests/kernels/test_light_sampling.cpp)
    it = shared.programs.emplace(root, buildProgram(deviceContext(), features, root)).first;
  }
  return it->second;
}

/// kernels/unit_tests.cl: small kernels exposing shared device code.
inline cl::Program unitTestProgram() { return testProgram("unit_tests.cl"); }

/// Release the shared programs and context; test_main calls it before main
/// returns. OpenCL objects must not outlive main: exit() runs thread_local
/// destructors before static ones, and Oclgrind's runtime keeps per-thread
/// state that its clRelease* calls write to, so releasing from a static
/// destructor corrupted the heap ("corrupted double-linked list").
inline void releaseSharedDevice() {
  SharedDevice& shared = sharedDevice();
  shared.programs.clear();
  shared.context.reset();
}

}  // namespace wt::test
