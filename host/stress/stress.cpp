// The stress suite's runner and `wavetrace stress`, and the accumulation
// rows (which run the accumulate stage's update code as a small kernel).
#include "stress/stress.h"

#include "device/program.h"
#include "shared/rng.h"
#include "shared/types.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace wt {
namespace {

std::string format(const char* fmt, double v) { return stressFormat(fmt, v); }

/// Worst relative error of `samples` running-mean updates (kernels/stress.cl,
/// test_accumulate) over `items` work-items, against the same sum in double.
double accumulationError(Context& context, cl::Program& program, cl_uint mode, cl_uint distribution, cl_uint samples,
                         cl_uint items) {
  cl::Buffer out(context.context(), CL_MEM_WRITE_ONLY, items * sizeof(float));
  cl::Kernel k(program, "test_accumulate");
  k.setArg(0, items), k.setArg(1, samples), k.setArg(2, mode), k.setArg(3, distribution), k.setArg(4, out);
  context.launch("test_accumulate", k, items, 8);
  std::vector<float> got(items);
  context.queue().enqueueReadBuffer(out, CL_TRUE, 0, items * sizeof(float), got.data());
  double worst = 0.0;
  for (cl_uint i = 0; i < items; ++i) {
    double sum = 0.0;
    for (cl_uint s = 0; s < samples; ++s)
      sum += distribution == 0 ? double(0.7f) : double(0.5f + rng_uniform(i, s, 0, 0, 3));
    double exact = sum / samples;
    worst = std::max(worst, std::abs(double(got[i]) - exact) / exact);
  }
  return worst;
}

}  // namespace

std::string stressFormat(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

std::vector<StressRow> stressAccumulation(Context& context, const StressOptions& options) {
  cl::Program program = buildProgram(context, KernelFeatures{}, "stress.cl");
  const cl_uint samples = options.quick ? 1u << 16 : 1u << 20, items = options.quick ? 4 : 16;
  const std::string count = options.quick ? "2^16" : "2^20";
  struct Mode {
    cl_uint mode;
    const char* name;
    double noisyLimit;  ///< the result is a float: a few ulp (6e-8 each) is the floor
    const char* note;
  };
  const Mode modes[] = {
      {WT_ACCUMULATE_SINGLE, "single", 1e-3, " (measured, not the default: drifts with the sample count)"},
      {WT_ACCUMULATE_KAHAN, "kahan (compensated single, the default)", 4e-7, ""},
      {WT_ACCUMULATE_DOUBLE, "double", 1.2e-7, ""},
  };
  std::vector<StressRow> rows;
  for (const Mode& m : modes) {
    for (cl_uint distribution : {0u, 1u}) {
      auto start = std::chrono::steady_clock::now();
      StressRow row;
      row.group = "accumulation";
      row.name = std::string(m.name) + ": " + count + " samples of " + (distribution == 0 ? "the constant 0.7" : "0.5 + U[0,1)");
      if (m.mode == WT_ACCUMULATE_DOUBLE && !context.info().fp64) {
        row.figure = "skipped: the device has no fp64";
        row.criterion = "needs fp64";
        row.pass = true;
        rows.push_back(row);
        continue;
      }
      double error = accumulationError(context, program, m.mode, distribution, samples, items);
      row.figure = "worst relative error of the mean " + format("%.3g", error) + " (of " + std::to_string(items) +
                   " pixels, against double on the host)";
      row.criterion = distribution == 0 ? "exactly 0 (every update after the first adds 0)"
                                        : "< " + format("%.1e", m.noisyLimit) + m.note;
      row.pass = distribution == 0 ? error == 0.0 : error < m.noisyLimit;
      row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      rows.push_back(row);
    }
  }
  return rows;
}

const std::vector<std::pair<std::string, StressGroup>>& stressGroups() {
  static const std::vector<std::pair<std::string, StressGroup>> groups = {
      {"transform", stressTransforms},   {"cracks", stressCracks},       {"self-intersection", stressSelfIntersection},
      {"degenerate", stressDegenerate},  {"materials", stressMaterials}, {"textures", stressTextures},
      {"accumulation", stressAccumulation},
      {"non-finite", stressNonFinite},  {"primitives", stressPrimitives}, {"far-furnace", stressFarFurnace},
  };
  return groups;
}

std::vector<StressRow> runStress(Context& context, const StressOptions& options,
                                 const std::function<void(const StressRow&)>& onRow) {
  for (const std::string& g : options.groups)
    if (std::none_of(stressGroups().begin(), stressGroups().end(), [&](const auto& e) { return e.first == g; }))
      throw std::invalid_argument("no stress group '" + g + "'");
  std::vector<StressRow> all;
  for (const auto& [name, run] : stressGroups()) {
    if (!options.groups.empty() && std::find(options.groups.begin(), options.groups.end(), name) == options.groups.end())
      continue;
    std::vector<StressRow> rows;
    try {
      rows = run(context, options);
    } catch (const std::exception& e) {
      // a group that throws fails as a whole row, and the others still run
      StressRow row;
      row.group = name;
      row.name = "(the whole group)";
      row.figure = std::string("failed: ") + e.what();
      row.criterion = "runs";
      rows.push_back(row);
    }
    for (const StressRow& row : rows) {
      if (onRow) onRow(row);
      all.push_back(row);
    }
  }
  return all;
}

int runStressCommand(const StressOptions& options, const std::string& device, bool json) {
  Context context(selectDevice(device));
  auto start = std::chrono::steady_clock::now();
  std::string lastGroup;
  auto print = [&](const StressRow& row) {
    if (json) return;
    if (row.group != lastGroup) std::printf("\n[%s]\n", row.group.c_str());
    lastGroup = row.group;
    std::printf("%s  %s\n      %s\n      criterion: %s  (%.1f s)\n", row.pass ? "PASS" : "FAIL", row.name.c_str(),
                row.figure.c_str(), row.criterion.c_str(), row.seconds);
    std::fflush(stdout);
  };
  if (!json)
    std::printf("wavetrace stress (%s) on %s\n", options.quick ? "quick" : "full", context.info().name.c_str());
  std::vector<StressRow> rows = runStress(context, options, print);
  int failed = int(std::count_if(rows.begin(), rows.end(), [](const StressRow& r) { return !r.pass; }));
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (json) {
    nlohmann::json out = nlohmann::json::array();
    for (const StressRow& r : rows)
      out.push_back({{"group", r.group}, {"name", r.name}, {"figure", r.figure}, {"criterion", r.criterion},
                     {"pass", r.pass}, {"seconds", r.seconds}});
    std::printf("%s\n", out.dump(1).c_str());
  } else {
    std::printf("\n%zu rows, %d failed, %.0f s\n", rows.size(), failed, seconds);
  }
  return failed ? 1 : 0;
}

}  // namespace wt
