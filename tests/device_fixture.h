// The OpenCL device the device tests run on (PoCL in CI), opened once.
#pragma once

#include "device/context.h"
#include "device/program.h"

#include <gtest/gtest.h>

#include <memory>

namespace wt::test {

/// The default device's context, shared by every test in the binary.
inline Context& deviceContext() {
  static std::unique_ptr<Context> context = [] {
    return std::make_unique<Context>(selectDevice(""), /*profiling=*/true);
  }();
  return *context;
}

/// kernels/unit_tests.cl: small kernels exposing shared device code, built once.
inline cl::Program unitTestProgram() {
  static cl::Program program = [] {
    KernelFeatures features;
    features.pbr = true;  // the metallic-roughness BSDF's tests need it compiled in
    return buildProgram(deviceContext(), features, "unit_tests.cl");
  }();
  return program;
}

}  // namespace wt::test
