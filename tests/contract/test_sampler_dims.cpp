// The sampler's dimensions (kernels/shared/dims.h): one name per use, each
// a distinct number, and no stage passing a literal number instead.
#include "device/program.h"
#include "shared/dims.h"

#include <gtest/gtest.h>

#include <map>
#include <regex>
#include <string>

namespace wt {
namespace {

// the halves of a 2D sample share a Sobol pair (2k, 2k+1), which the sampler stratifies together
static_assert(WT_DIM_PIXEL_X / 2u == WT_DIM_PIXEL_Y / 2u && WT_DIM_PIXEL_X != WT_DIM_PIXEL_Y);
static_assert(WT_DIM_BSDF_U / 2u == WT_DIM_BSDF_V / 2u && WT_DIM_BSDF_U != WT_DIM_BSDF_V);
static_assert(WT_DIM_LIGHT_U / 2u == WT_DIM_LIGHT_V / 2u && WT_DIM_LIGHT_U != WT_DIM_LIGHT_V);

TEST(SamplerDims, EveryNamedDimensionIsDistinct) {
  const std::string header = expandKernelSource("shared/dims.h");
  const std::regex defineRe(R"(#define (WT_DIM_\w+) (\d+)u)");
  std::map<unsigned, std::string> byValue;
  unsigned count = 0, names = 0;
  for (auto it = std::sregex_iterator(header.begin(), header.end(), defineRe); it != std::sregex_iterator(); ++it) {
    const std::string name = (*it)[1];
    const unsigned value = unsigned(std::stoul((*it)[2]));
    if (name == "WT_DIM_COUNT") {
      count = value;
      continue;
    }
    ++names;
    auto [where, fresh] = byValue.emplace(value, name);
    EXPECT_TRUE(fresh) << name << " and " << where->second << " are both dimension " << value;
  }
  EXPECT_GE(names, 12u) << "the parser found too few WT_DIM_ names";
  EXPECT_EQ(count, WT_DIM_COUNT);
  // bounce << 8 + dimension keys the sampler: a dimension must stay below 256
  for (const auto& [value, name] : byValue) {
    EXPECT_LT(value, count) << name << " is not below WT_DIM_COUNT";
    EXPECT_LT(value, 256u) << name;
  }
}

TEST(SamplerDims, NoRenderStagePassesALiteralDimension) {
  const std::string source = expandKernelSource("wavetrace.cl");
  // the dimension: sampler_get's last argument, rng_uniform's fourth, rng_alpha_key's third
  const std::regex literal(
      R"(sampler_get\([^;()]*,\s*\d+u?\s*\))"
      R"(|rng_uniform\((\s*[^;(),]+,){3}\s*\d+u?\s*,)"
      R"(|rng_alpha_key\((\s*[^;(),]+,){2}\s*\d+u?\s*,)");
  ASSERT_NE(source.find("sampler_get("), std::string::npos);
  for (auto it = std::sregex_iterator(source.begin(), source.end(), literal); it != std::sregex_iterator(); ++it)
    ADD_FAILURE() << "a literal sampler dimension (name it in kernels/shared/dims.h): " << it->str();
}

}  // namespace
}  // namespace wt
