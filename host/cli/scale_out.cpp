#include "cli/scale_out.h"

#include "core/log.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <csignal>
#include <stdexcept>
#include <thread>
#include <iterator>
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
  kTagHeartbeat = 7, ///< worker -> 0: uint64 sample passes its devices have done (a sign of progress);
                     ///< 0 -> worker: no payload (rank 0 is alive)
  kTagStarted = 8,   ///< worker -> 0: set up (or failed to), about to join the start-up collective;
                     ///< 0 -> worker: every rank has (join it)
  kTagRelease = 9,   ///< 0 -> worker: int 1: you were lost, 0: the job ends early; either way stop
                     ///< watching rank 0, which sends no more heartbeats and ends the job itself
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
  const std::size_t aovBytes = r.moments.hasAovs() ? pixels * (kAovSumBytes + kAovIdBytes) : 0;
  std::vector<std::uint8_t> bytes(sizeof h + pixels * (6 * sizeof(double) + sizeof(std::uint32_t)) + aovBytes);
  std::uint8_t* p = bytes.data();
  std::memcpy(p, &h, sizeof h), p += sizeof h;
  std::memcpy(p, r.moments.mean.data(), 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(p, r.moments.m2.data(), 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(p, r.moments.count.data(), pixels * sizeof(std::uint32_t)), p += pixels * sizeof(std::uint32_t);
  if (aovBytes) {
    // a chunk's AOV sums are its device's floats: sent as floats, exactly
    const std::vector<float> sums(r.moments.aovSum.begin(), r.moments.aovSum.end());
    std::memcpy(p, sums.data(), pixels * kAovSumBytes), p += pixels * kAovSumBytes;
    std::memcpy(p, r.moments.aovIds.data(), pixels * kAovIdBytes);
  }
  return bytes;
}

[[maybe_unused]] ChunkResult unpackResult(const std::vector<std::uint8_t>& bytes, std::size_t expectedPixels, bool aovs) {
  ResultHeader h;
  if (bytes.size() < sizeof h) throw std::runtime_error("a result message of " + std::to_string(bytes.size()) + " bytes");
  std::memcpy(&h, bytes.data(), sizeof h);
  const std::size_t pixels = h.pixels;
  const std::size_t aovBytes = aovs ? pixels * (kAovSumBytes + kAovIdBytes) : 0;
  if (pixels != expectedPixels ||
      bytes.size() != sizeof h + pixels * (6 * sizeof(double) + sizeof(std::uint32_t)) + aovBytes)
    throw std::runtime_error("a result message of " + std::to_string(bytes.size()) + " bytes for " +
                             std::to_string(pixels) + " pixels (this image has " + std::to_string(expectedPixels) +
                             (aovs ? ", with AOVs)" : ")"));
  ChunkResult r;
  r.chunk = {h.index, h.firstSample, h.sampleCount};
  r.raysTraced = h.raysTraced;
  r.seconds = h.seconds;
  r.moments = emptyMoments(pixels, h.firstSample, aovs);
  r.moments.sampleEnd = h.sampleEnd;
  r.moments.nonFiniteSamples = h.nonFiniteSamples;
  const std::uint8_t* p = bytes.data() + sizeof h;
  std::memcpy(r.moments.mean.data(), p, 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(r.moments.m2.data(), p, 3 * pixels * sizeof(double)), p += 3 * pixels * sizeof(double);
  std::memcpy(r.moments.count.data(), p, pixels * sizeof(std::uint32_t)), p += pixels * sizeof(std::uint32_t);
  if (aovs) {
    std::vector<float> sums(16 * pixels);
    std::memcpy(sums.data(), p, pixels * kAovSumBytes), p += pixels * kAovSumBytes;
    std::copy(sums.begin(), sums.end(), r.moments.aovSum.begin());
    std::memcpy(r.moments.aovIds.data(), p, pixels * kAovIdBytes);
  }
  return r;
}

/// A hidden test hook (tests/cli_scale_out.sh): WT_TEST_STALL="RANK:process"
/// makes that rank's main thread stop talking (a hung or dead process): a
/// worker once it holds its first chunk, rank 0 once it has checkpointed (or
/// merged) a chunk; "RANK:device" makes the first of that rank's devices to
/// take a chunk hang on it (a hung device; a worker's heartbeat goes on);
/// "RANK:pause" (a worker) makes that rank stop itself (SIGSTOP: every
/// thread) once it holds its first chunk, until the test continues it
/// (SIGCONT), and makes rank 0, having lost a rank, go on taking messages
/// for 2 --rank-timeout before it ends the job: time for the lost rank to
/// come back, hear that it was given up on, and not end the job itself.
/// Rank 0 is also the only process of a render without MPI.
struct StallHook {
  bool process = false, device = false, pause = false;
  bool linger = false;  ///< rank 0: a worker pauses
  explicit StallHook(int rank) {
    const char* v = std::getenv("WT_TEST_STALL");
    if (!v) return;
    const std::string s(v);
    const std::size_t colon = s.find(':');
    if (colon == std::string::npos) return;
    const int target = std::atoi(s.substr(0, colon).c_str());
    const std::string mode = s.substr(colon + 1);
    linger = rank == 0 && target != 0 && mode == "pause";
    if (target != rank) return;
    process = mode == "process";
    device = mode == "device";
    pause = mode == "pause" && rank != 0;
  }
  [[noreturn]] static void forever() {
    while (true) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
};

/// The time a watching loop itself did not run: a gap between two of its
/// turns longer than `limit` (its process was stopped, by SIGSTOP or a
/// suspended Slurm job, or not scheduled). A watcher moves its clocks of the
/// others on by it: their silence counts only while the watcher ran, so a
/// job stopped and continued as a whole loses no rank.
class AwayClock {
 public:
  explicit AwayClock(double limitSeconds)
      : m_limit(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(limitSeconds))) {}
  /// The time away since the last call; zero within the limit.
  Clock::duration away() {
    const Clock::time_point now = Clock::now();
    const Clock::duration gap = now - m_last;
    m_last = now;
    return gap > m_limit ? gap : Clock::duration::zero();
  }

 private:
  Clock::duration m_limit;
  Clock::time_point m_last = Clock::now();
};

/// Rank 0's main thread holds this gate except inside MPI calls. Open MPI
/// can block a call for good (across machines its TCP transport, reporting
/// a peer that died, waits on mpirun, which is ending the job); a watchdog
/// that takes the gate then finds the merged samples as the main thread left
/// them, and the main thread, should the call return, waits at the gate.
class MpiGate {
 public:
  MpiGate() { m_mutex.lock(); }  // on the main thread
  /// Around one MPI call of the main thread; `peer`: the rank it talks to, -1: any.
  class Call {
   public:
    Call(MpiGate* gate, const char* name, int peer) : m_gate(gate) {
      if (!m_gate) return;
      m_gate->m_name = name;
      m_gate->m_peer = peer;
      m_gate->m_start = Clock::now().time_since_epoch().count();
      m_gate->m_mutex.unlock();
    }
    ~Call() {
      if (!m_gate) return;
      m_gate->m_mutex.lock();
      m_gate->m_start = 0;
    }
    Call(const Call&) = delete;
    Call& operator=(const Call&) = delete;

   private:
    MpiGate* m_gate;
  };
  /// When the main thread's current MPI call began (0: none), its name and peer.
  Clock::rep callStart() const { return m_start.load(); }
  const char* callName() const { return m_name.load(); }
  int callPeer() const { return m_peer.load(); }
  /// The watchdog: the main thread is inside an MPI call, or waits at the gate after one.
  bool take() { return m_mutex.try_lock(); }
  void giveBack() { m_mutex.unlock(); }

 private:
  std::mutex m_mutex;
  std::atomic<Clock::rep> m_start{0};
  std::atomic<const char*> m_name{""};
  std::atomic<int> m_peer{-1};
};

/// What the coordinator sees of one device thread: the chunk it holds and
/// its sample passes, so that a hung device can be told from a slow one.
struct DeviceWatch {
  std::atomic<int> chunk{-1};            ///< the chunk it renders; -1: none
  std::atomic<std::uint64_t> passes{0};  ///< sample passes done
  std::atomic<bool> finished{false};     ///< its loop ended
  std::atomic<bool> lost{false};         ///< given up on: it gets no more chunks
};

/// One device's view of the shared source: records the chunk it takes; with
/// the stall hook, the first device to take a chunk hangs on it.
class WatchedSource : public ChunkSource {
 public:
  WatchedSource(ChunkSource& inner, DeviceWatch& watch, std::atomic<bool>* stallFirst)
      : m_inner(inner), m_watch(watch), m_stallFirst(stallFirst) {}
  std::optional<SampleChunk> next() override {
    m_watch.chunk = -1;
    if (m_watch.lost) return std::nullopt;  // back from a hang: its chunk went to another
    std::optional<SampleChunk> c = m_inner.next();
    if (c) {
      m_watch.chunk = c->index;
      if (m_stallFirst && !m_stallFirst->exchange(true)) StallHook::forever();
    }
    return c;
  }

 private:
  ChunkSource& m_inner;
  DeviceWatch& m_watch;
  std::atomic<bool>* m_stallFirst;
};

/// One thread per device, each watched (DeviceWatch) and counted out when
/// its loop ends. A lost device's thread may never end: it is left behind
/// (detached), and the process must end without returning to it.
class DeviceThreads {
 public:
  DeviceThreads(DeviceSet& devices, ChunkSource& source, ResultQueue& results, std::atomic<bool>& stop,
                bool stallFirst = false) {
    const std::size_t n = devices.renderers.size();
    for (std::size_t d = 0; d < n; ++d) {
      m_watches.push_back(std::make_unique<DeviceWatch>());
      m_sources.push_back(
          std::make_unique<WatchedSource>(source, *m_watches[d], stallFirst ? &m_stallTaken : nullptr));
    }
    for (std::size_t d = 0; d < n; ++d)
      m_threads.emplace_back([&, d] {
        runDeviceWorker(*devices.renderers[d], *m_sources[d], results, stop, devices.names[d], &m_watches[d]->passes);
        m_watches[d]->finished = true;
      });
  }
  ~DeviceThreads() { join(); }
  /// Joins every thread, except a lost device's that has not ended: left behind.
  void join() {
    for (std::size_t d = 0; d < m_threads.size(); ++d) {
      if (!m_threads[d].joinable()) continue;
      if (m_watches[d]->lost && !m_watches[d]->finished)
        m_threads[d].detach(), m_leftBehind = true;
      else
        m_threads[d].join();
    }
  }
  std::size_t size() const { return m_threads.size(); }
  DeviceWatch& watch(std::size_t d) { return *m_watches[d]; }
  /// Every device's loop ended, or the device was lost.
  bool allFinished() const { return live() == 0; }
  int live() const {
    int n = 0;
    for (const auto& w : m_watches) n += !w->finished && !w->lost;
    return n;
  }
  std::uint64_t passes() const {
    std::uint64_t n = 0;
    for (const auto& w : m_watches) n += w->passes.load();
    return n;
  }
  bool leftBehind() const { return m_leftBehind; }

 private:
  std::vector<std::unique_ptr<DeviceWatch>> m_watches;
  std::vector<std::unique_ptr<WatchedSource>> m_sources;
  std::vector<std::thread> m_threads;
  std::atomic<bool> m_stallTaken{false};
  bool m_leftBehind = false;
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

/// Rank 0's own devices: they take given-back chunks too, so they wait while
/// chunks are out on other ranks (one may be lost and its chunks given back).
class ReserveSource : public ChunkSource {
 public:
  ReserveSource(ChunkPlan& plan, const std::atomic<bool>& stop) : m_plan(plan), m_stop(stop) {}
  std::optional<SampleChunk> next() override { return m_plan.nextOrWait(m_stop); }

 private:
  ChunkPlan& m_plan;
  const std::atomic<bool>& m_stop;
};

}  // namespace

double heartbeatSeconds(double rankTimeoutSeconds) { return std::clamp(rankTimeoutSeconds / 4.0, 0.01, 1.0); }

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

namespace {

/// Open MPI's mpirun under --enable-recovery exits 0 whatever its ranks
/// do (MPI_Abort's code, an exit status, a signal), but not when it is
/// itself stopped by a signal: the way to end such a job as failed is to
/// stop the launcher the way a user would. Only for Open MPI's own
/// launcher, found as this process's parent: not its daemon (orted, the
/// parent of a rank on another machine), whose stop leaves mpirun waiting
/// forever. The name of that launcher, "" where it is not one.
bool underRecovery() {
  const char* recovery = std::getenv("OMPI_MCA_orte_enable_recovery");
  return recovery && (std::strcmp(recovery, "1") == 0 || std::strcmp(recovery, "true") == 0);
}

std::string parentName() {
  char path[64], name[32] = {};
  std::snprintf(path, sizeof path, "/proc/%d/comm", int(getppid()));
  std::FILE* f = std::fopen(path, "r");
  if (!f) return "";
  const bool read = std::fgets(name, sizeof name, f) != nullptr;
  std::fclose(f);
  if (!read) return "";
  name[std::strcspn(name, "\n")] = 0;
  return name;
}

std::string recoveringLauncher() {
  if (!underRecovery()) return "";
  const std::string name = parentName();
  static const char* const launchers[] = {"mpirun", "mpiexec", "orterun"};
  if (std::none_of(std::begin(launchers), std::end(launchers), [&](const char* l) { return name == l; })) return "";
  return name;
}

[[maybe_unused]] bool stopRecoveringLauncher() {
  const std::string name = recoveringLauncher();
  if (name.empty()) return false;
  const pid_t parent = getppid();
  log::error("ending the job as failed by stopping " + name +
             " (SIGTERM): under --enable-recovery Open MPI's mpirun exits 0 whatever its ranks' exit status");
  std::fflush(stderr);
  return ::kill(parent, SIGTERM) == 0;
}

}  // namespace

bool MpiWorld::launcherIgnoresExitStatus() const { return m_initialized && !recoveringLauncher().empty(); }

void MpiWorld::abort(int code) const {
  std::fflush(stdout);
  std::fflush(stderr);
#if WT_MPI
  if (m_initialized && code != 0 && stopRecoveringLauncher()) {
    // the launcher stops every rank, this one too (SIGTERM, which sets the
    // interrupt flag only, then SIGKILL); MPI_Abort only if it does not
    std::this_thread::sleep_for(std::chrono::seconds(30));
  }
  if (m_initialized) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::_Exit(code);
}

void MpiWorld::exitWithoutMpi(int code) const {
  std::fflush(stdout);
  std::fflush(stderr);
  if (m_initialized && code != 0) (void)stopRecoveringLauncher();
  std::_Exit(code);
}

bool MpiWorld::launchedBySrun() const {
  return m_initialized && std::getenv("SLURM_STEP_ID") && !std::getenv("OMPI_COMM_WORLD_SIZE");
}

std::string MpiWorld::host(int rank) const {
  return rank >= 0 && std::size_t(rank) < m_hosts.size() ? m_hosts[std::size_t(rank)] : std::string("?");
}

bool MpiWorld::onRecoveringDaemon() const { return m_initialized && underRecovery() && parentName() == "orted"; }

std::string MpiWorld::unsupportedLaunch() const {
  if (!onRecoveringDaemon()) return "";
  return "started by Open MPI's daemon (orted) on a machine other than mpirun's, under mpirun --enable-recovery: "
         "across machines Open MPI 4.1 then cannot end a job whose rank died or hung (it waits forever); run "
         "without --enable-recovery";
}

void MpiWorld::agreeOnStart(const std::string& error, std::uint64_t renderHash, [[maybe_unused]] double timeoutSeconds) {
#if WT_MPI
  if (!active()) {
    if (!error.empty()) throw std::runtime_error(error);
    return;
  }
  // each worker says it got here before the collective, so that rank 0 can
  // name a rank that never does (the collective would wait for it forever),
  // and rank 0 answers once all have, so that a worker can name a rank 0
  // that never gets here
  if (const char* stall = std::getenv("WT_TEST_STALL"); stall && stall == std::to_string(m_rank) + ":startup")
    StallHook::forever();  // the test hook: a rank hung while starting
  if (m_rank != 0) {
    MPI_Send(nullptr, 0, MPI_INT, 0, kTagStarted, MPI_COMM_WORLD);
    const auto t0 = Clock::now();
    for (int flag = 0; !flag;) {
      MPI_Iprobe(0, kTagStarted, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
      if (flag) break;
      if (since(t0) > timeoutSeconds) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "the job could not start: rank 0 had not finished starting %.3g s after rank %d "
                      "(--start-timeout); hung or dead while loading the scene or building its program?",
                      timeoutSeconds, m_rank);
        log::error(text);
        abort(1);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    MPI_Recv(nullptr, 0, MPI_INT, 0, kTagStarted, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  } else {
    std::vector<bool> arrived(std::size_t(m_size), false);
    int missing = m_size - 1;
    const auto t0 = Clock::now();
    while (missing > 0) {
      int flag = 0;
      MPI_Status status;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagStarted, MPI_COMM_WORLD, &flag, &status);
      if (flag) {
        MPI_Recv(nullptr, 0, MPI_INT, status.MPI_SOURCE, kTagStarted, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (!arrived[std::size_t(status.MPI_SOURCE)]) arrived[std::size_t(status.MPI_SOURCE)] = true, --missing;
        continue;
      }
      if (since(t0) > timeoutSeconds) {
        std::string names;
        for (int r = 1; r < m_size; ++r)
          if (!arrived[std::size_t(r)]) names += (names.empty() ? "" : ", ") + std::to_string(r);
        char text[160];
        std::snprintf(text, sizeof text, " had not finished starting %.3g s after rank 0 (--start-timeout)", timeoutSeconds);
        log::error("the job could not start: rank" + std::string(missing > 1 ? "s " : " ") + names + text +
                   "; hung or dead while loading the scene or building its program?");
        abort(1);  // the others wait in the collective
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    for (int r = 1; r < m_size; ++r) MPI_Send(nullptr, 0, MPI_INT, r, kTagStarted, MPI_COMM_WORLD);
  }
  // each entry: the hash, the start-up error, the host name (to name a lost rank's machine)
  constexpr int kMessage = 1024, kHost = 64, kEntry = 8 + kMessage + kHost;
  std::vector<char> mine(kEntry, 0), all(std::size_t(m_size) * kEntry);
  std::memcpy(mine.data(), &renderHash, 8);
  std::strncpy(mine.data() + 8, error.c_str(), kMessage - 1);
  {
    char name[MPI_MAX_PROCESSOR_NAME + 1] = {};
    int length = 0;
    MPI_Get_processor_name(name, &length);
    std::strncpy(mine.data() + 8 + kMessage, name, kHost - 1);
  }
  MPI_Allgather(mine.data(), kEntry, MPI_CHAR, all.data(), kEntry, MPI_CHAR, MPI_COMM_WORLD);
  std::string report;
  std::uint64_t hash0;
  std::memcpy(&hash0, all.data(), 8);
  m_hosts.clear();
  for (int r = 0; r < m_size; ++r) {
    const char* entry = all.data() + std::size_t(r) * kEntry;
    m_hosts.emplace_back(entry + 8 + kMessage);
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
  [[maybe_unused]] const bool aovs = start.hasAovs();
  const int resumed = start.sampleEnd;
  // what the device threads use, on the heap: a lost device's thread, left
  // behind, may still return into it after this function has (the process
  // then ends without freeing it)
  struct Shared {
    ChunkPlan plan;
    ResultQueue results;
    std::atomic<bool> stop{false};
    ReserveSource source{plan, stop};
    std::unique_ptr<DeviceThreads> threads;
    Shared(int first, int spp, int chunkSpp) : plan(first, spp, chunkSpp) {}
  };
  auto shared = std::make_unique<Shared>(start.sampleEnd, options.samplesPerPixel, options.chunkSpp);
  ChunkPlan& plan = shared->plan;
  std::atomic<bool>& stop = shared->stop;
  ResultQueue& results = shared->results;
  OrderedMerge merge(std::move(start));
  Halting halting({options.samplesPerPixel, options.timeSeconds, options.targetError}, resumed);
  // every chunk boundary, in chunk order: the reference log, and the error
  // estimate for --target-error (on the merged prefix, so the stopping
  // point does not depend on how many devices or ranks render)
  merge.onMerged([&](const Moments& m) {
    if (options.merged) options.merged(m);
    if (halting.wantsErrorEstimate(m.sampleEnd)) {
      const Image image = imageFromMoments(m, 1, int(m.pixels()));
      halting.recordError(m.sampleEnd, std::sqrt(estimatedRelMse(image)), 0.0, 0.0);
      result.lastError = halting.lastError();
      result.lastErrorSamples = m.sampleEnd;
      if (halting.check(m.sampleEnd, 0.0) == HaltReason::TargetError) {
        result.reason = HaltReason::TargetError;
        plan.cancel();
        stop = true;  // this process's devices drop the chunks they hold
        return false;
      }
    }
    return true;
  });
  const auto t0 = Clock::now();
  auto lastReport = t0, lastCheckpoint = t0;
  [[maybe_unused]] auto lastBeat = t0;  // rank 0's heartbeat (MPI only)
  const StallHook stall(0);
  // the watchdog's gate (MpiGate), where a rescue is given and MPI is in use
  std::optional<MpiGate> gateHolder;
  MpiGate* gate = world.active() && options.rescue ? &gateHolder.emplace() : nullptr;
  std::optional<Clock::time_point> lingerFrom;  // the test hook (StallHook::linger)
  int checkpointed = resumed;
  const bool tty = isatty(STDERR_FILENO);
  int remoteActive = world.size() - 1;

  // what rank 0 knows of each worker rank (the heartbeat's bookkeeping)
  struct RankState {
    bool lost = false, finished = false;
    Clock::time_point lastProgress;  ///< the last message that showed progress
    Clock::time_point lastMessage;   ///< the last message of any kind
    std::uint64_t passes = 0;        ///< its heartbeat's pass count
    std::set<int> chunks;            ///< chunks assigned to it, not yet returned
    int requests = 0;                ///< its devices' requests not yet answered
  };
  std::vector<RankState> ranks(std::size_t(world.size()));
  for (RankState& r : ranks) r.lastProgress = r.lastMessage = t0;
  // after a signal or a block: the rank most likely gone, "" if none is running
  auto silentLongest = [&] {
    int quiet = -1;
    double quietFor = 0.0;
    for (int r = 1; r < world.size(); ++r) {
      const RankState& st = ranks[std::size_t(r)];
      if (!st.lost && !st.finished && since(st.lastMessage) > quietFor) quiet = r, quietFor = since(st.lastMessage);
    }
    if (quiet < 0) return std::string();
    char text[200];
    std::snprintf(text, sizeof text, "rank %d on host %s, for %.3g s", quiet, world.host(quiet).c_str(), quietFor);
    return std::string(text);
  };
  [[maybe_unused]] std::vector<std::vector<std::uint8_t>> abandoned;  // buffers of receives cancelled from lost ranks
  // a silent rank: its chunks go back to the plan, for the others (rank 0's
  // own devices wait for them); whatever it sends later is dropped
  [[maybe_unused]] auto loseRank = [&](int rank, const std::string& why) {
    RankState& st = ranks[std::size_t(rank)];
    if (st.lost) return;
    st.lost = true;
    if (!st.finished) --remoteActive;
    std::string held;
    for (int c : st.chunks) {
      const SampleChunk chunk = plan.chunk(c);
      held += (held.empty() ? "" : ", ") + std::to_string(c) + " (samples " + std::to_string(chunk.firstSample) + "-" +
              std::to_string(chunk.firstSample + chunk.sampleCount - 1) + ")";
      plan.giveBack(c);
    }
    const std::string message = "rank " + std::to_string(rank) + " " + why +
                                (held.empty() ? "; it held no chunk" : "; its chunks " + held + " were handed out again");
    result.lostRanks.push_back(message);
    log::warnOnce(message);
    st.chunks.clear();
#if WT_MPI
    // it may be alive (a hung device): it must not take rank 0's silence
    // towards it for a hung rank 0 and end the job before the image is written
    const int lost = 1;
    MpiGate::Call call(gate, "MPI_Send", rank);
    MPI_Send(&lost, 1, MPI_INT, rank, kTagRelease, MPI_COMM_WORLD);
#endif
  };
  // this process's devices, watched like the ranks: one that holds a chunk
  // with no sample pass done for the timeout is lost (a hung driver), its
  // chunk goes to the others, and the job ends without waiting for it
  struct DeviceSeen {
    int chunk = -1;
    std::uint64_t passes = 0;
    Clock::time_point since;
  };
  std::vector<DeviceSeen> seen(devices.renderers.size(), DeviceSeen{-1, 0, t0});
  // called before every check of a silence: a stop anywhere in the loop is discounted
  AwayClock awayClock(heartbeatSeconds(options.rankTimeoutSeconds));
  auto discountAway = [&] {
    const Clock::duration gap = awayClock.away();
    for (RankState& r : ranks) r.lastProgress += gap, r.lastMessage += gap;
    for (DeviceSeen& d : seen) d.since += gap;
    return gap;
  };
  auto watchDevices = [&] {
    DeviceThreads& threads = *shared->threads;
    discountAway();
    const auto now = Clock::now();
    for (std::size_t d = 0; d < threads.size(); ++d) {
      DeviceWatch& w = threads.watch(d);
      if (w.lost || w.finished) continue;
      const int chunk = w.chunk.load();
      const std::uint64_t passes = w.passes.load();
      if (chunk < 0 || chunk != seen[d].chunk || passes != seen[d].passes) {
        seen[d] = {chunk, passes, now};
        continue;
      }
      const double silent = std::chrono::duration<double>(now - seen[d].since).count();
      if (silent <= options.rankTimeoutSeconds) continue;
      w.lost = true;
      const SampleChunk c = plan.chunk(chunk);
      plan.giveBack(chunk);
      char text[320];
      std::snprintf(text, sizeof text,
                    "%s%s did no sample pass for %.3g s (--rank-timeout %g) on its chunk %d (samples %d-%d): handed "
                    "out again; the job ends without waiting for it",
                    devices.names[d].c_str(), world.active() ? " of rank 0" : "", silent, options.rankTimeoutSeconds,
                    chunk, c.firstSample, c.firstSample + c.sampleCount - 1);
      result.lostDevices.push_back(text);
      log::warnOnce(text);
    }
  };
  // rank 0 is alive: the workers end the job if they stop hearing it
  [[maybe_unused]] auto beat = [&] {
#if WT_MPI
    if (since(lastBeat) < heartbeatSeconds(options.rankTimeoutSeconds)) return;
    for (int r = 1; r < world.size(); ++r)
      if (!ranks[std::size_t(r)].lost && !ranks[std::size_t(r)].finished) {
        MpiGate::Call call(gate, "MPI_Send", r);
        MPI_Send(nullptr, 0, MPI_BYTE, r, kTagHeartbeat, MPI_COMM_WORLD);
      }
    lastBeat = Clock::now();
#endif
  };

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
      plan.cancel();
      return;
    }
    result.raysTraced += r.raysTraced;
    if (local) result.localOverheadSeconds += r.overheadSeconds, ++result.localChunks;
    ++result.chunksByRank[std::size_t(rank)];
    merge.add(r.chunk.index, std::move(r.moments));  // false: a duplicate, or after the target error
    plan.complete(r.chunk.index);
  };

  shared->threads = std::make_unique<DeviceThreads>(devices, shared->source, results, stop, stall.device);
  DeviceThreads& threads = *shared->threads;
  // the watchdog: a main thread inside one MPI call for 0.3 s once a signal
  // has come (mpirun's SIGKILL follows its SIGTERM by a second), or for
  // --rank-timeout (nothing else would end the job), is given up on: the
  // devices are stopped and the merged samples go to options.rescue
  std::atomic<bool> watchdogEnd{false};
  std::thread watchdog;
  struct JoinWatchdog {
    std::atomic<bool>& end;
    std::thread& thread;
    ~JoinWatchdog() {
      end = true;
      if (thread.joinable()) thread.join();
    }
  } joinWatchdog{watchdogEnd, watchdog};
  if (gate)
    watchdog = std::thread([&] {
      AwayClock awayClock(heartbeatSeconds(options.rankTimeoutSeconds));
      Clock::rep seen = 0;
      Clock::time_point callFrom = Clock::now();
      while (!watchdogEnd) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        const Clock::duration away = awayClock.away();
        const Clock::rep start = gate->callStart();
        if (start == 0) continue;
        if (start != seen) seen = start, callFrom = Clock::time_point(Clock::duration(start));
        const bool signalled = options.interrupted && options.interrupted();
        if (!signalled) callFrom += away;  // a stopped process's time is not the call's
        const double in = since(callFrom);
        if (in <= (signalled ? 0.3 : options.rankTimeoutSeconds) || !gate->take()) continue;
        const int peer = gate->callPeer();
        char text[480];
        std::snprintf(text, sizeof text, "rank 0 was blocked for %.3g s inside Open MPI (%s%s)%s", in,
                      gate->callName(),
                      peer > 0 ? (" with rank " + std::to_string(peer) + " on host " + world.host(peer)).c_str() : "",
                      signalled ? " when a signal came (mpirun stops every rank when one dies)"
                                : " for longer than --rank-timeout");
        std::string failure = text;
        if (const std::string quiet = silentLongest(); !quiet.empty()) failure += "; the rank silent longest: " + quiet;
        stop = true;
        plan.cancel();
        threads.join();
        for (std::size_t d = 0; d < threads.size(); ++d)
          if (!threads.watch(d).lost) {
            result.outputDevice = int(d);
            break;
          }
        result.failure = failure;
        result.seconds = since(t0);
        result.chunks = merge.mergedChunks();
        result.merged = merge.merged();
        options.rescue(result);  // does not return
      }
    });
  while (true) try {
    bool busy = false;
    discountAway();
    beat();
    while (std::optional<ChunkResult> r = results.pop(0.0)) take(std::move(*r), 0, true), busy = true;
#if WT_MPI
    // a bounded batch: the checks below (signal, time, checkpoint) must not starve
    bool drained = !world.active();
    for (int flag = 1, batch = 0; world.active() && flag && batch < 16; ++batch) {
      beat();
      MPI_Status status;
      {
        MpiGate::Call call(gate, "MPI_Iprobe", -1);
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
      }
      if (!flag) {
        drained = true;
        break;
      }
      busy = true;
      int bytes = 0;
      MPI_Get_count(&status, MPI_BYTE, &bytes);
      auto receiveStart = Clock::now();
      std::vector<std::uint8_t> message(std::size_t(std::max(bytes, 0)));
      const int from = status.MPI_SOURCE;
      RankState& sender = ranks[std::size_t(from)];
      // polled, not blocking: a rank that dies mid-message must not hold rank 0
      // past the signal mpirun then sends, nor past the rank timeout
      MPI_Request request;
      int received = 0;
      bool failed = false;
      {
        MpiGate::Call call(gate, "MPI_Irecv", from);
        failed = MPI_Irecv(message.data(), bytes, MPI_BYTE, from, status.MPI_TAG, MPI_COMM_WORLD, &request) != MPI_SUCCESS;
      }
      bool timedOut = false, interrupted = false;
      while (!failed && !received && !timedOut && !interrupted) {
        {
          MpiGate::Call call(gate, "MPI_Test", from);
          failed = MPI_Test(&request, &received, MPI_STATUS_IGNORE) != MPI_SUCCESS;
        }
        if (received || failed) break;
        receiveStart += discountAway();
        timedOut = since(receiveStart) > options.rankTimeoutSeconds;
        interrupted = options.interrupted && options.interrupted();
        beat();
        std::this_thread::yield();
      }
      if (interrupted) break;  // handled below
      if (timedOut || failed) {
        // a rank that died mid-message (under a launcher that lets the job
        // go on, the receive fails) or stopped sending: lost, not the job
        if (timedOut) {
          MpiGate::Call call(gate, "MPI_Cancel", from);
          MPI_Cancel(&request);
          MPI_Request_free(&request);
        }
        abandoned.push_back(std::move(message));  // MPI may still write into it
        char why[160];
        if (timedOut)
          std::snprintf(why, sizeof why, "stopped sending a %d-byte message for %.3g s (--rank-timeout)", bytes,
                        options.rankTimeoutSeconds);
        else
          std::snprintf(why, sizeof why, "failed while sending a %d-byte message (it died?)", bytes);
        loseRank(from, why);
        continue;
      }
      sender.lastMessage = Clock::now();
      if (sender.lost) continue;  // too late: its chunks went to the others
      if (status.MPI_TAG != kTagHeartbeat) sender.lastProgress = Clock::now();
      switch (status.MPI_TAG) {
        case kTagRequest:
          ++sender.requests;  // answered below
          break;
        case kTagResult: {
          ChunkResult r = unpackResult(message, pixels, aovs);
          result.receiveSeconds += since(receiveStart);
          result.bytesReceived += std::uint64_t(bytes);
          sender.chunks.erase(r.chunk.index);
          take(std::move(r), from, false);
          break;
        }
        case kTagError: {
          ChunkResult r;
          r.error = std::string(message.begin(), message.end());
          take(std::move(r), from, false);
          break;
        }
        case kTagFinished:
          sender.finished = true;
          --remoteActive;
          break;
        case kTagHeartbeat: {
          std::uint64_t passes = 0;
          if (message.size() == sizeof passes) std::memcpy(&passes, message.data(), sizeof passes);
          // alive and idle, or a pass further on its chunks
          if (passes != sender.passes || sender.chunks.empty()) sender.lastProgress = Clock::now();
          sender.passes = passes;
          break;
        }
        default: break;
      }
    }
    // a request is answered with a chunk, or with stop once no chunk is out
    // that could still be given back (the asking rank may have to take it)
    for (int r = 1; r < world.size(); ++r)
      for (RankState& st = ranks[std::size_t(r)]; st.requests > 0 && !st.lost; --st.requests) {
        if (std::optional<SampleChunk> c = plan.next()) {
          const int assign[3] = {c->index, c->firstSample, c->sampleCount};
          MpiGate::Call call(gate, "MPI_Send", r);
          MPI_Send(assign, 3, MPI_INT, r, kTagAssign, MPI_COMM_WORLD);
          st.chunks.insert(c->index);
        } else if (plan.settled()) {
          MpiGate::Call call(gate, "MPI_Send", r);
          MPI_Send(nullptr, 0, MPI_INT, r, kTagStop, MPI_COMM_WORLD);
        } else {
          break;
        }
      }
    // only with every waiting message taken: heartbeats that queued while this
    // thread was busy (merging, receiving a large result) count
    if (drained) discountAway();
    for (int r = 1; drained && r < world.size(); ++r) {
      RankState& st = ranks[std::size_t(r)];
      const double silent = since(st.lastProgress);
      if (!st.lost && !st.finished && silent > options.rankTimeoutSeconds) {
        char why[160];
        std::snprintf(why, sizeof why, "showed no progress for %.3g s (--rank-timeout %g)%s", silent,
                      options.rankTimeoutSeconds,
                      st.chunks.empty() ? "" : ": no message, or heartbeats with no sample pass done");
        loseRank(r, why);
      }
    }
#endif
    watchDevices();
    if (threads.live() == 0 && remoteActive == 0 && !plan.settled()) {
      // every device lost, no rank left to take their chunks
      result.failure = "no device or rank is left to render the chunks of the lost device(s)";
      break;
    }
    if (stall.process && world.active() && (options.checkpoint ? checkpointed : merge.samplesDone()) > resumed)
      StallHook::forever();  // the test hook: a hung rank 0
    if (options.interrupted && options.interrupted()) {
      // under mpirun also what a dying rank brings: mpirun stops the job
      result.interrupted = true;
      result.silentLongest = silentLongest();
      break;
    }
    const double elapsed = since(t0);
    if (result.reason == HaltReason::None) {
      const HaltReason why = halting.check(merge.samplesDone(), elapsed);
      if (why == HaltReason::Time) plan.close();
      if (why == HaltReason::Time || why == HaltReason::Samples) result.reason = why;
    }
    if (options.checkpoint && options.checkpointSeconds > 0.0 && since(lastCheckpoint) >= options.checkpointSeconds &&
        merge.samplesDone() > checkpointed) {
      options.checkpoint(merge.merged());
      checkpointed = merge.samplesDone();
      lastCheckpoint = Clock::now();
    }
    if (!options.quiet && since(lastReport) > (tty ? 0.1 : 5.0)) progress(false);
    if (threads.allFinished() && remoteActive == 0) {
      if (stall.linger && !result.lostRanks.empty()) {  // the test hook: a lost rank comes back
        if (!lingerFrom) lingerFrom = Clock::now();
        if (since(*lingerFrom) < 2.0 * options.rankTimeoutSeconds) {
          std::this_thread::sleep_for(std::chrono::milliseconds(1));
          continue;
        }
      }
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
#if WT_MPI
  // ended early (a failure, a signal): the workers still running must not
  // end the job while rank 0 writes the image
  for (int r = 1, ending = 0; r < world.size(); ++r)
    if (!ranks[std::size_t(r)].lost && !ranks[std::size_t(r)].finished) {
      MpiGate::Call call(gate, "MPI_Send", r);
      MPI_Send(&ending, 1, MPI_INT, r, kTagRelease, MPI_COMM_WORLD);
    }
#endif
  watchdogEnd = true;
  if (watchdog.joinable()) watchdog.join();
  if (gate) gate->giveBack();
  stop = true;
  plan.cancel();
  threads.join();
  if (threads.leftBehind()) (void)shared.release();  // see Shared
  for (std::size_t d = 0; d < threads.size(); ++d)
    if (!threads.watch(d).lost) {
      result.outputDevice = int(d);
      break;
    }
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
                [[maybe_unused]] const std::function<bool()>& interrupted, [[maybe_unused]] double rankTimeoutSeconds) {
#if WT_MPI
  FedSource fed;
  const StallHook stall(world.rank());
  ResultQueue results;
  std::atomic<bool> stop{false};
  int requested = 0, status = 0, supplied = 0;
  bool stopped = false, paused = false;
  DeviceThreads threads(devices, fed, results, stop, stall.device);
  auto lastBeat = Clock::now(), lastHeard = Clock::now();
  bool released = false;
  // rank 0 sends a heartbeat as often as the workers do: a rank 0 that is
  // silent for the timeout is hung or dead, and with it the job (unless it
  // released this rank: then it ends the job itself)
  AwayClock awayClock(heartbeatSeconds(rankTimeoutSeconds));
  auto takeRootHeartbeats = [&] {
    lastHeard += awayClock.away();
    for (const int tag : {kTagHeartbeat, kTagRelease})
      for (int flag = 1; flag;) {
        MPI_Iprobe(0, tag, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
        if (!flag) break;
        int lost = 0;
        MPI_Recv(&lost, tag == kTagRelease ? 1 : 0, MPI_INT, 0, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        lastHeard = Clock::now();
        if (tag != kTagRelease) continue;
        released = true;
        if (lost)
          log::warnOnce("rank " + std::to_string(world.rank()) +
                        ": rank 0 gave up on this rank (no progress within --rank-timeout); it waits for rank 0 "
                        "to end the job");
      }
    lastHeard += awayClock.away();
    const double silent = since(lastHeard);
    if (released || silent <= rankTimeoutSeconds) return;
    char text[400];
    std::snprintf(text, sizeof text,
                  "rank %d: rank 0 (which merges and writes the image) sent nothing for %.3g s (--rank-timeout %g): "
                  "hung or dead; ending the job. Its merged samples are lost, except what its last checkpoint "
                  "holds (--checkpoint; --resume continues from it)",
                  world.rank(), silent, rankTimeoutSeconds);
    log::error(text);
    world.abort(1);
  };
  // a send polled, not blocking: a hung rank 0 never posts the receive of a large result
  auto sendToRoot = [&](const void* data, int bytes, int tag) {
    MPI_Request request;
    MPI_Isend(data, bytes, MPI_BYTE, 0, tag, MPI_COMM_WORLD, &request);
    for (int done = 0;;) {
      MPI_Test(&request, &done, MPI_STATUS_IGNORE);
      if (done) return;
      takeRootHeartbeats();
      std::this_thread::yield();
    }
  };
  // every finished chunk (or a device's error) to rank 0
  auto sendResults = [&] {
    while (std::optional<ChunkResult> r = results.pop(0.0)) {
      if (!r->error.empty()) {
        sendToRoot(r->error.data(), int(r->error.size()), kTagError);
        status = 1;
        continue;
      }
      const std::vector<std::uint8_t> bytes = packResult(*r);
      sendToRoot(bytes.data(), int(bytes.size()), kTagResult);
    }
  };
  while (true) {
    // results before requests: rank 0 merges a device's chunk before handing it the next
    sendResults();
    for (int n = stopped ? 0 : fed.wanting(requested); n > 0; --n, ++requested)
      MPI_Send(nullptr, 0, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
    takeRootHeartbeats();
    int flag = 1;
    bool busy = false;
    while (requested > 0) {
      MPI_Status st;
      MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
      if (!flag || st.MPI_TAG == kTagHeartbeat || st.MPI_TAG == kTagRelease) break;
      busy = true;
      lastHeard = Clock::now();
      int assign[3] = {0, 0, 0};
      MPI_Recv(assign, 3, MPI_INT, 0, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      --requested;
      if (st.MPI_TAG == kTagAssign && !stopped)
        fed.supply({assign[0], assign[1], assign[2]}), ++supplied;
      else if (st.MPI_TAG == kTagStop)
        stopped = true, fed.close();
    }
    if (stall.process && supplied > 0) StallHook::forever();
    if (stall.pause && supplied > 0 && !paused) paused = true, std::raise(SIGSTOP);
    // the sample passes done so far: rank 0 takes a count that stands still
    // while this rank holds a chunk for a hang (--rank-timeout)
    if (since(lastBeat) >= heartbeatSeconds(rankTimeoutSeconds)) {
      const std::uint64_t done = threads.passes();
      MPI_Send(&done, int(sizeof done), MPI_BYTE, 0, kTagHeartbeat, MPI_COMM_WORLD);
      lastBeat = Clock::now();
    }
    if (interrupted && interrupted()) {
      stop = true;
      fed.close();
      threads.join();
      return 130;
    }
    if (threads.allFinished() && requested == 0) {
      sendResults();
      break;
    }
    // a device that failed ends its own loop; the others stop asking too
    if (status != 0 && !stopped) stopped = true, fed.close();
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
