// Small thread helpers the BVH builders share: a fixed team of threads with a
// reusable barrier, chunking of index ranges, cache-line padded slots.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <system_error>
#include <thread>
#include <vector>

namespace wt::bvh_detail {

/// Reusable barrier for a team whose size is fixed before any member waits.
class Barrier {
 public:
  void init(int count) { m_count = count; }

  void arriveAndWait() {
    // The generation cannot advance before this thread arrives, so reading it first is safe.
    const std::uint32_t generation = m_generation.load(std::memory_order_acquire);
    if (m_arrived.fetch_add(1, std::memory_order_acq_rel) + 1 == m_count) {
      m_arrived.store(0, std::memory_order_relaxed);
      m_generation.fetch_add(1, std::memory_order_release);
      m_generation.notify_all();
      return;
    }
    while (m_generation.load(std::memory_order_acquire) == generation)
      m_generation.wait(generation, std::memory_order_acquire);
  }

 private:
  int m_count = 1;
  std::atomic<int> m_arrived{0};
  std::atomic<std::uint32_t> m_generation{0};
};

/// Run fn(rank, size, barrier) on up to `wanted` threads, the caller being rank 0.
/// The team shrinks when a thread cannot be started, so a failed spawn never deadlocks.
template <class Fn>
void runTeam(int wanted, Fn&& fn) {
  Barrier barrier;
  if (wanted <= 1) {
    fn(0, 1, barrier);
    return;
  }
  std::atomic<int> teamSize{0};
  std::vector<std::thread> workers;
  workers.reserve(static_cast<std::size_t>(wanted - 1));
  for (int rank = 1; rank < wanted; ++rank) {
    try {
      workers.emplace_back([&teamSize, &barrier, &fn, rank] {
        teamSize.wait(0);
        fn(rank, teamSize.load(), barrier);
      });
    } catch (const std::system_error&) {
      break;
    }
  }
  const int size = 1 + static_cast<int>(workers.size());
  barrier.init(size);
  teamSize.store(size);
  teamSize.notify_all();
  fn(0, size, barrier);
  for (std::thread& worker : workers) worker.join();
}

struct Range {
  std::size_t begin;
  std::size_t end;
};

inline Range chunkOf(std::size_t n, int size, int rank) {
  return {n * static_cast<std::size_t>(rank) / static_cast<std::size_t>(size),
          n * static_cast<std::size_t>(rank + 1) / static_cast<std::size_t>(size)};
}

/// Per-thread slot padded to a cache line, so that neighbours do not share one.
template <class T>
struct alignas(64) PerThread {
  T value{};
};

}  // namespace wt::bvh_detail
