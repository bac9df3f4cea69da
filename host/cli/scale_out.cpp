#include "cli/scale_out.h"

#include "core/log.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <unistd.h>

#if WT_MPI
#include <mpi.h>
#endif

namespace wt {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The message tags of the protocol (docs/scale-out.md, "Protocol").
enum Tag : int {
  kTagRequest = 1,   ///< worker -> 0: a device of mine wants a chunk (no payload)
  kTagAssign = 2,    ///< 0 -> worker: int[3] chunk index, first sample, sample count
  kTagStop = 3,      ///< 0 -> worker: no more chunks (the reply to a request)
  kTagResult = 4,    ///< worker -> 0: ResultHeader, then mean, m2 (double) and counts (uint32)
  kTagError = 5,     ///< worker -> 0: a device failed: its message
  kTagFinished = 6,  ///< worker -> 0: all my devices are done and their results sent
};

/// The fixed part of a result message.
struct ResultHeader {
  std::int32_t index, firstSample, sampleCount, sampleEnd;
  std::uint64_t nonFiniteSamples, raysTraced, pixels;
  double seconds;
};
static_assert(sizeof(ResultHeader) == 48);

[[maybe_unused]] std::vector<std::uint8_t> packResult(const ChunkResult& r) {
  const std::size_t pixels = r.moments.pixels();
  ResultHeader h{r.chunk.index, r.chunk.firstSample, r.chunk.sampleCount, r.moments.sampleEnd,
                 r.moments.nonFiniteSamples, r.raysTraced, pixels, r.seconds};
  std::vector<std::uint8_t> bytes(sizeof h + pixels * (6 * sizeof(double) + sizeof(std::uint32_t)));
  std::uint8_t* p = bytes.data();
  std::memcpy(p, &h, sizeof h), p += sizeof h;
  std::memcpy(p, r.moments.mean.data(), 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(p, r.moments.m2.data(), 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(p, r.moments.count.data(), pixels * sizeof(std::uint32_t));
  return bytes;
}

[[maybe_unused]] ChunkResult unpackResult(const std::vector<std::uint8_t>& bytes, std::size_t expectedPixels) {
  ResultHeader h;
  if (bytes.size() < sizeof h) throw std::runtime_error("a result message of " + std::to_string(bytes.size()) + " bytes");
  std::memcpy(&h, bytes.data(), sizeof h);
  const std::size_t pixels = h.pixels;
  if (pixels != expectedPixels || bytes.size() != sizeof h + pixels * (6 * sizeof(double) + sizeof(std::uint32_t)))
    throw std::runtime_error("a result message of " + std::to_string(bytes.size()) + " bytes for " +
                             std::to_string(pixels) + " pixels (this image has " + std::to_string(expectedPixels) + ")");
  ChunkResult r;
  r.chunk = {h.index, h.firstSample, h.sampleCount};
  r.raysTraced = h.raysTraced;
  r.seconds = h.seconds;
  r.moments = emptyMoments(pixels, h.firstSample);
  r.moments.sampleEnd = h.sampleEnd;
  r.moments.nonFiniteSamples = h.nonFiniteSamples;
  const std::uint8_t* p = bytes.data() + sizeof h;
  std::memcpy(r.moments.mean.data(), p, 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(r.moments.m2.data(), p, 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(r.moments.count.data(), p, pixels * sizeof(std::uint32_t));
  return r;
}

/// One thread per device, each counted out when its loop ends.
class DeviceThreads {
 public:
  DeviceThreads(DeviceSet& devices, ChunkSource& source, ResultQueue& results, std::atomic<bool>& stop) {
    for (std::size_t d = 0; d < devices.renderers.size(); ++d)
      m_threads.emplace_back([&, d] {
        runDeviceWorker(*devices.renderers[d], source, results, stop, devices.names[d]);
        ++m_finished;
      });
  }
  ~DeviceThreads() { join(); }
  void join() {
    for (std::thread& t : m_threads)
      if (t.joinable()) t.join();
  }
  bool allFinished() const { return m_finished.load() == int(m_threads.size()); }

 private:
  std::vector<std::thread> m_threads;
  std::atomic<int> m_finished{0};
};

/// A worker rank's chunk source: a device that wants a chunk waits here
/// while the main thread asks rank 0 for one.
class FedSource : public ChunkSource {
 public:
  std::optional<SampleChunk> next() override {
    std::unique_lock<std::mutex> lock(m_mutex);
    ++m_waiting;
    m_cv.wait(lock, [&] { return !m_chunks.empty() || m_closed; });
    --m_waiting;
    if (m_chunks.empty()) return std::nullopt;
    SampleChunk c = m_chunks.front();
    m_chunks.pop_front();
    return c;
  }
  /// Devices waiting with no chunk on its way yet.
  int wanting(int requested) {
    std::lock_guard<std::mutex> lock(m_mutex);
    return m_closed ? 0 : m_waiting - int(m_chunks.size()) - requested;
  }
  void supply(const SampleChunk& c) {
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_chunks.push_back(c);
    }
    m_cv.notify_all();
  }
  void close() {
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_closed = true;
    }
    m_cv.notify_all();
  }

 private:
  std::mutex m_mutex;
  std::condition_variable m_cv;
  std::deque<SampleChunk> m_chunks;
  int m_waiting = 0;
  bool m_closed = false;
};

}  // namespace

// ---------------------------------------------------------------- MpiWorld

bool MpiWorld::builtWithMpi() { return WT_MPI != 0; }

MpiWorld::MpiWorld([[maybe_unused]] int& argc, [[maybe_unused]] char**& argv) {
#if WT_MPI
  // only under a launcher: a plain run needs no MPI start-up
  const bool launched = std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK") || std::getenv("PMI_RANK");
  if (!launched) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  m_initialized = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &m_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &m_size);
  // a failure is reported by the rank that sees it, not by MPI's handler
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
#else
  // under mpirun without MPI every process would render, and write, the whole image
  const char* size = std::getenv("OMPI_COMM_WORLD_SIZE");
  if (!size) size = std::getenv("PMI_SIZE");
  if (size && std::atoi(size) > 1)
    log::warnOnce(std::string("started as one of ") + size +
                  " MPI processes, but this wavetrace was built without MPI (WT_MPI): each renders the whole image");
#endif
}

MpiWorld::~MpiWorld() {
#if WT_MPI
  if (m_initialized) MPI_Finalize();
#endif
}

void MpiWorld::abort(int code) {
  std::fflush(stdout);
  std::fflush(stderr);
#if WT_MPI
  if (m_initialized) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::_Exit(code);
}

void MpiWorld::agreeOnStart(const std::string& error, std::uint64_t renderHash) const {
#if WT_MPI
  if (!active()) {
    if (!error.empty()) throw std::runtime_error(error);
    return;
  }
  constexpr int kMessage = 1024;
  std::vector<char> mine(kMessage + 8, 0), all(std::size_t(m_size) * (kMessage + 8));
  std::memcpy(mine.data(), &renderHash, 8);
  std::strncpy(mine.data() + 8, error.c_str(), kMessage - 1);
  MPI_Allgather(mine.data(), kMessage + 8, MPI_CHAR, all.data(), kMessage + 8, MPI_CHAR, MPI_COMM_WORLD);
  std::string report;
  std::uint64_t hash0;
  std::memcpy(&hash0, all.data(), 8);
  for (int r = 0; r < m_size; ++r) {
    const char* entry = all.data() + std::size_t(r) * (kMessage + 8);
    std::uint64_t hash;
    std::memcpy(&hash, entry, 8);
    std::string message(entry + 8);
    if (message.empty() && hash != hash0)
      message = "renders another scene or other settings than rank 0 (every rank must be given the same ones)";
    if (!message.empty()) report += (report.empty() ? "" : "; ") + ("rank " + std::to_string(r) + ": " + message);
  }
  if (!report.empty()) throw std::runtime_error(m_rank == 0 ? "the job could not start: " + report : std::string());
#else
  (void)renderHash;
  if (!error.empty()) throw std::runtime_error(error);
#endif
}

// ---------------------------------------------------------------- rank 0

ScaleOutResult coordinateRender(DeviceSet& devices, const ScaleOutOptions& options, Moments start,
                                const MpiWorld& world) {
  ScaleOutResult result;
  result.chunksByRank.assign(std::size_t(world.size()), 0);
  [[maybe_unused]] const std::size_t pixels = start.pixels();  // checks result messages
  const int resumed = start.sampleEnd;
  ChunkPlan plan(start.sampleEnd, options.samplesPerPixel, options.chunkSpp);
  OrderedMerge merge(std::move(start));
  Halting halting({options.samplesPerPixel, options.timeSeconds, 0.0}, resumed);
  ResultQueue results;
  PlanSource source(plan);
  std::atomic<bool> stop{false};
  const auto t0 = Clock::now();
  auto lastReport = t0, lastCheckpoint = t0;
  int checkpointed = resumed;
  const bool tty = isatty(STDERR_FILENO);
  int remoteActive = world.size() - 1;

  auto progress = [&](bool last) {
    const int done = merge.samplesDone(), rendered = done - resumed;
    const double t = since(t0);
    const std::string line = progressLine(halting, done, t > 0.0 ? double(result.raysTraced) / t * 1e-6 : 0.0, t,
                                          rendered > 0 ? t / rendered : 0.0, last);
    std::fprintf(stderr, tty ? "\r%-78s%s" : "%s%s\n", line.c_str(), tty && last ? "\n" : "");
    std::fflush(stderr);
    lastReport = Clock::now();
  };
  auto take = [&](ChunkResult r, int rank, bool local) {
    if (!r.error.empty()) {
      if (result.failure.empty())
        result.failure = world.active() ? "rank " + std::to_string(rank) + ", " + r.error : r.error;
      plan.close();
      return;
    }
    result.raysTraced += r.raysTraced;
    if (local) result.localOverheadSeconds += r.overheadSeconds, ++result.localChunks;
    ++result.chunksByRank[std::size_t(rank)];
    merge.add(r.chunk.index, std::move(r.moments));
  };

  DeviceThreads threads(devices, source, results, stop);
  while (true) try {
    bool busy = false;
    while (std::optional<ChunkResult> r = results.pop(0.0)) take(std::move(*r), 0, true), busy = true;
#if WT_MPI
    // a bounded batch: the checks below (signal, time, checkpoint) must not starve
    for (int flag = 1, batch = 0; world.active() && flag && batch < 16; ++batch) {
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
      if (!flag) break;
      busy = true;
      int bytes = 0;
      MPI_Get_count(&status, MPI_BYTE, &bytes);
      const auto receiveStart = Clock::now();
      std::vector<std::uint8_t> message(std::size_t(std::max(bytes, 0)));
      const int from = status.MPI_SOURCE;
      // polled, not blocking: a rank that dies mid-message must not hold rank 0
      // past the signal mpirun then sends (a blocking receive never returns)
      MPI_Request request;
      int received = 0;
      bool lost = MPI_Irecv(message.data(), bytes, MPI_BYTE, from, status.MPI_TAG, MPI_COMM_WORLD, &request) != MPI_SUCCESS;
      while (!lost && !received) {
        lost = MPI_Test(&request, &received, MPI_STATUS_IGNORE) != MPI_SUCCESS ||
               (options.interrupted && options.interrupted());
        if (!received) std::this_thread::yield();
      }
      if (lost) {
        if (!(options.interrupted && options.interrupted()))
          throw std::runtime_error("receiving a message from rank " + std::to_string(from) + " failed");
        break;  // the interrupt is handled below
      }
      switch (status.MPI_TAG) {
        case kTagRequest: {
          std::optional<SampleChunk> c = plan.next();
          if (c) {
            const int assign[3] = {c->index, c->firstSample, c->sampleCount};
            MPI_Send(assign, 3, MPI_INT, from, kTagAssign, MPI_COMM_WORLD);
          } else {
            MPI_Send(nullptr, 0, MPI_INT, from, kTagStop, MPI_COMM_WORLD);
          }
          break;
        }
        case kTagResult: {
          ChunkResult r = unpackResult(message, pixels);
          result.receiveSeconds += since(receiveStart);
          result.bytesReceived += std::uint64_t(bytes);
          take(std::move(r), from, false);
          break;
        }
        case kTagError: {
          ChunkResult r;
          r.error = std::string(message.begin(), message.end());
          take(std::move(r), from, false);
          break;
        }
        case kTagFinished: --remoteActive; break;
        default: break;
      }
    }
#endif
    if (options.interrupted && options.interrupted()) {
      // under mpirun also what a dying rank brings: mpirun stops the job
      result.interrupted = true;
      break;
    }
    const double elapsed = since(t0);
    if (result.reason == HaltReason::None) {
      const HaltReason why = halting.check(merge.samplesDone(), elapsed);
      if (why == HaltReason::Time) plan.close();
      if (why != HaltReason::None) result.reason = why;
    }
    if (options.checkpoint && options.checkpointSeconds > 0.0 && since(lastCheckpoint) >= options.checkpointSeconds &&
        merge.samplesDone() > checkpointed) {
      options.checkpoint(merge.merged());
      checkpointed = merge.samplesDone();
      lastCheckpoint = Clock::now();
    }
    if (!options.quiet && since(lastReport) > (tty ? 0.1 : 5.0)) progress(false);
    if (threads.allFinished() && remoteActive == 0) {
      // the last results may have arrived after the drain above
      while (std::optional<ChunkResult> r = results.pop(0.0)) take(std::move(*r), 0, true);
      break;
    }
    if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  } catch (const std::exception& e) {
    // a checkpoint that cannot be written, a malformed message: stop the devices, keep what was merged
    if (result.failure.empty()) result.failure = e.what();
    break;
  }
  stop = true;
  plan.close();
  threads.join();
  result.seconds = since(t0);
  result.mergeSeconds = merge.mergeSeconds();
  result.chunks = merge.mergedChunks();
  if (!options.quiet && merge.samplesDone() > resumed) progress(true);
  if (result.reason == HaltReason::None && merge.samplesDone() >= options.samplesPerPixel)
    result.reason = HaltReason::Samples;
  if (merge.waiting() > 0 && result.failure.empty() && !result.interrupted)
    result.failure = std::to_string(merge.waiting()) + " rendered chunks could not be merged (an earlier chunk is missing)";
  result.merged = merge.merged();
  return result;
}

// ---------------------------------------------------------------- ranks > 0

int serveRender([[maybe_unused]] DeviceSet& devices, [[maybe_unused]] const MpiWorld& world,
                [[maybe_unused]] const std::function<bool()>& interrupted) {
#if WT_MPI
  FedSource source;
  ResultQueue results;
  std::atomic<bool> stop{false};
  int requested = 0, status = 0;
  bool stopped = false;
  DeviceThreads threads(devices, source, results, stop);
  // every finished chunk (or a device's error) to rank 0
  auto sendResults = [&] {
    while (std::optional<ChunkResult> r = results.pop(0.0)) {
      if (!r->error.empty()) {
        MPI_Send(r->error.data(), int(r->error.size()), MPI_CHAR, 0, kTagError, MPI_COMM_WORLD);
        status = 1;
        continue;
      }
      std::vector<std::uint8_t> bytes = packResult(*r);
      MPI_Send(bytes.data(), int(bytes.size()), MPI_BYTE, 0, kTagResult, MPI_COMM_WORLD);
    }
  };
  while (true) {
    // results before requests: rank 0 merges a device's chunk before handing it the next
    sendResults();
    for (int n = stopped ? 0 : source.wanting(requested); n > 0; --n, ++requested)
      MPI_Send(nullptr, 0, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
    int flag = 1;
    bool busy = false;
    while (requested > 0) {
      MPI_Status st;
      MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
      if (!flag) break;
      busy = true;
      int assign[3] = {0, 0, 0};
      MPI_Recv(assign, 3, MPI_INT, 0, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      --requested;
      if (st.MPI_TAG == kTagAssign && !stopped)
        source.supply({assign[0], assign[1], assign[2]});
      else if (st.MPI_TAG == kTagStop)
        stopped = true, source.close();
    }
    if (interrupted && interrupted()) {
      stop = true;
      source.close();
      threads.join();
      return 130;
    }
    if (threads.allFinished() && requested == 0) {
      sendResults();
      break;
    }
    // a device that failed ends its own loop; the others stop asking too
    if (status != 0 && !stopped) stopped = true, source.close();
    if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  threads.join();
  MPI_Send(nullptr, 0, MPI_INT, 0, kTagFinished, MPI_COMM_WORLD);
  return status;
#else
  throw std::logic_error("serveRender without MPI");
#endif
}

}  // namespace wt
