// The stress suite's quick variant, one test per group: every row must pass.
// The full suite (`wavetrace stress`, larger images and millions of rays) is
// the CTest test stress.full, labelled slow.
#include "device_fixture.h"
#include "stress/stress.h"

#include <gtest/gtest.h>

namespace wt {
namespace {

class StressGroupQuick : public ::testing::TestWithParam<std::string> {};

TEST_P(StressGroupQuick, EveryRowPasses) {
  StressOptions options;
  options.quick = true;
  options.groups = {GetParam()};
  std::vector<StressRow> rows = runStress(test::deviceContext(), options);
  ASSERT_FALSE(rows.empty());
  for (const StressRow& row : rows)
    EXPECT_TRUE(row.pass) << row.group << ": " << row.name << "\n  " << row.figure << "\n  criterion: " << row.criterion;
}

std::vector<std::string> groupNames() {
  std::vector<std::string> names;
  for (const auto& [name, run] : stressGroups()) names.push_back(name);
  return names;
}

INSTANTIATE_TEST_SUITE_P(Groups, StressGroupQuick, ::testing::ValuesIn(groupNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace wt
