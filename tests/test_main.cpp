#include "core/log.h"
#include "device_fixture.h"

#include <gtest/gtest.h>

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  wt::log::setQuiet(true);
  int status = RUN_ALL_TESTS();
  // OpenCL objects are released here, not by static destructors after main.
  wt::test::releaseSharedDevice();
  return status;
}
