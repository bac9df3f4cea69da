// Device tests run over every BVH builder and leaf size: the parameter is
// (builder, leaf size), and options() the build options it names.
#pragma once

#include "bvh/builders.h"

#include <gtest/gtest.h>

#include <string>
#include <tuple>

namespace wt::test {

class TreeParamTest : public ::testing::TestWithParam<std::tuple<BvhBuilder, int>> {
 protected:
  static BvhBuildOptions options() {
    BvhBuildOptions options;
    options.builder = std::get<0>(GetParam());
    options.maxLeafSize = std::get<1>(GetParam());
    return options;
  }
};

/// "lbvh_leaf4" and so on, for INSTANTIATE_TEST_SUITE_P.
inline std::string treeParamName(const ::testing::TestParamInfo<std::tuple<BvhBuilder, int>>& param) {
  return std::string(bvhBuilderName(std::get<0>(param.param))) + "_leaf" + std::to_string(std::get<1>(param.param));
}

}  // namespace wt::test
