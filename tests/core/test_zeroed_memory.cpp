// ZeroedMemory: a huge-page-aligned mapping of whole huge pages, zero and writable.
#include "core/zeroed_memory.h"

#include <gtest/gtest.h>

#include <cstdint>

namespace wt {
namespace {

TEST(ZeroedMemory, AlignedWholeHugePagesOfZeros) {
  const std::size_t bytes = 3 * ZeroedMemory::kAlignment + 12345;
  ZeroedMemory m(bytes);
  ASSERT_NE(m.data(), nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(m.data()) % ZeroedMemory::kAlignment, 0u);
  EXPECT_EQ(m.size(), 4 * ZeroedMemory::kAlignment);
  // every page reads zero and keeps what is written
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < m.size(); i += 4096) nonzero += m.data()[i] != std::byte{0};
  nonzero += m.data()[m.size() - 1] != std::byte{0};
  EXPECT_EQ(nonzero, 0u);
  m.data()[0] = std::byte{7};
  m.data()[m.size() - 1] = std::byte{9};
  EXPECT_EQ(m.data()[0], std::byte{7});
  EXPECT_EQ(m.data()[m.size() - 1], std::byte{9});
}

TEST(ZeroedMemory, NothingForZeroBytes) {
  ZeroedMemory m(0);
  EXPECT_EQ(m.data(), nullptr);
  EXPECT_EQ(m.size(), 0u);
}

}  // namespace
}  // namespace wt
