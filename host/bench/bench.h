// `wavetrace bench`: BVH build and ray throughput figures for scenes, as a
// table or JSON. Timings belong here, never in tests.
#pragma once

#include <string>
#include <vector>

namespace wt {

struct BenchOptions {
  std::vector<std::string> scenes;  ///< files; empty: the default scene and a generated ~1M-triangle mesh
  std::string device;               ///< --device spec
  bool json = false;
  int primaryWidth = 1024;          ///< primary ray set is width x width
  int pathWidth = 256;              ///< path rays: a render of pathWidth^2 pixels
  int pathSamples = 4;
  int repetitions = 3;              ///< median of this many timed runs after a warm-up
  int meshTriangles = 1000000;      ///< size of the generated mesh
};

/// Run the benchmark and print the results to stdout. Returns an exit code.
int runBench(const BenchOptions& options);

}  // namespace wt
