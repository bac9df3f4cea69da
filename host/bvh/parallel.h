// Small thread helpers the BVH builders share: a fixed team of threads with a
// reusable barrier, chunking of index ranges, cache-line padded slots.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace wt::bvh_detail {

/// The most threads a builder's team takes (per-thread tables are sized by it).
constexpr int kMaxBuildThreads = 64;

/// A requested thread count resolved: 0 means every hardware thread; at
/// least one (hardware_concurrency may report none), at most `most`.
inline int resolveThreads(int requested, int most = kMaxBuildThreads) {
  const int threads = requested > 0 ? requested : int(std::thread::hardware_concurrency());
  return std::clamp(threads, 1, most);
}

/// Below this many items per thread, starting a thread costs more than it saves.
constexpr std::size_t kMinItemsPerThread = 16384;

/// resolveThreads(requested), but no more threads than `items` keep busy.
inline int teamThreads(int requested, std::size_t items) {
  return int(std::min<std::size_t>(std::size_t(resolveThreads(requested)), items / kMinItemsPerThread + 1));
}

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

/// Work through a tree of tasks on up to `threads` threads: process(task,
/// children) handles one task and fills up to two children, returning how
/// many. Children for which big(child) holds go through a shared queue for
/// any thread to take; the others are finished by the thread that made them.
template <class Task, class Process, class Big>
void runTaskTree(int threads, const Task& root, Process&& process, Big&& big) {
  std::mutex mutex;
  std::condition_variable wake;
  std::vector<Task> queue{root};
  int busy = 0;
  runTeam(threads, [&](int, int, Barrier&) {
    std::vector<Task> local;
    std::array<Task, 2> children;
    std::unique_lock lock(mutex);
    for (;;) {
      wake.wait(lock, [&] { return !queue.empty() || busy == 0; });
      if (queue.empty()) break;  // and nobody busy: no task can appear any more
      local.assign(1, queue.back());
      queue.pop_back();
      ++busy;
      lock.unlock();
      while (!local.empty()) {
        const Task task = local.back();
        local.pop_back();
        const int count = process(task, children);
        for (int c = count - 1; c >= 0; --c) {
          if (!big(children[c])) {
            local.push_back(children[c]);
            continue;
          }
          std::lock_guard guard(mutex);
          queue.push_back(children[c]);
          wake.notify_one();
        }
      }
      lock.lock();
      if (--busy == 0 && queue.empty()) wake.notify_all();
    }
  });
}

}  // namespace wt::bvh_detail
