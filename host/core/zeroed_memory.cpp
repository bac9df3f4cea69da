#include "core/zeroed_memory.h"

#include <sys/mman.h>

#include <cstdint>

namespace wt {

ZeroedMemory::ZeroedMemory(std::size_t bytes) {
  if (bytes == 0) return;
  const std::size_t size = (bytes + kAlignment - 1) / kAlignment * kAlignment;
  // over-map by one huge page and trim, so the mapping starts on a huge-page boundary
  void* raw = mmap(nullptr, size + kAlignment, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) return;
  const auto base = reinterpret_cast<std::uintptr_t>(raw);
  const std::uintptr_t start = (base + kAlignment - 1) / kAlignment * kAlignment;
  if (start > base) munmap(raw, start - base);
  if (const std::size_t tail = base + size + kAlignment - (start + size); tail > 0)
    munmap(reinterpret_cast<void*>(start + size), tail);
  m_data = reinterpret_cast<std::byte*>(start);
  m_size = size;
  // a hint: without transparent huge pages ("never") the mapping is 4 KiB pages, as malloc's
  madvise(m_data, m_size, MADV_HUGEPAGE);
}

ZeroedMemory::~ZeroedMemory() {
  if (m_data) munmap(m_data, m_size);
}

}  // namespace wt
