// The context's helpers: Context::fill sets the range it is given and
// nothing else (under Oclgrind it rewrites the whole buffer to do so).
#include "device_fixture.h"

#include <gtest/gtest.h>

#include <vector>

namespace wt {
namespace {

TEST(Context, FillSetsItsRangeOnly) {
  Context& ctx = test::deviceContext();
  const std::size_t words = 64;
  cl::Buffer buffer(ctx.context(), CL_MEM_READ_WRITE, words * sizeof(cl_uint));
  ctx.fill(buffer, 7u, 0, words * sizeof(cl_uint));
  ctx.fill(buffer, 0u, 4 * sizeof(cl_uint), 3 * sizeof(cl_uint));
  ctx.fill(buffer, 9u, (words - 1) * sizeof(cl_uint), sizeof(cl_uint));
  std::vector<cl_uint> got(words);
  ctx.queue().enqueueReadBuffer(buffer, CL_TRUE, 0, words * sizeof(cl_uint), got.data());
  for (std::size_t i = 0; i < words; ++i) {
    cl_uint want = i == words - 1 ? 9u : (i >= 4 && i < 7) ? 0u : 7u;
    EXPECT_EQ(got[i], want) << "word " << i;
  }
}

TEST(Context, FillRejectsUnalignedRanges) {
  Context& ctx = test::deviceContext();
  cl::Buffer buffer(ctx.context(), CL_MEM_READ_WRITE, 64);
  EXPECT_THROW(ctx.fill(buffer, 0u, 2, 8), DeviceError);
  EXPECT_THROW(ctx.fill(buffer, 0u, 0, 6), DeviceError);
}

}  // namespace
}  // namespace wt
