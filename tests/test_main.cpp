#include "core/log.h"

#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  wt::log::setQuiet(true);
  return RUN_ALL_TESTS();
}
