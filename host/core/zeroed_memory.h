// Zero-filled anonymous memory for a CPU device's per-pixel buffers
// (PathState, CL_MEM_USE_HOST_PTR), mapped on huge-page boundaries and
// marked for transparent huge pages: a stage's first touch then faults once
// per 2 MiB instead of once per 4 KiB where the kernel grants them.
#pragma once

#include <cstddef>

namespace wt {

class ZeroedMemory {
 public:
  ZeroedMemory() = default;
  /// Map `bytes`, rounded up to whole huge pages; an empty mapping (data()
  /// null) where the system refuses.
  explicit ZeroedMemory(std::size_t bytes);
  ~ZeroedMemory();
  ZeroedMemory(const ZeroedMemory&) = delete;
  ZeroedMemory& operator=(const ZeroedMemory&) = delete;

  /// The mapping, zero where never written; null where none.
  std::byte* data() const { return m_data; }
  std::size_t size() const { return m_size; }

  /// Alignment of the mapping (the huge page size it asks for).
  static constexpr std::size_t kAlignment = std::size_t(2) << 20;

 private:
  std::byte* m_data = nullptr;
  std::size_t m_size = 0;
};

}  // namespace wt
