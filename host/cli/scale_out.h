// `render` on several devices (--device 0,1 / all) and, in a build with
// MPI, on several processes (mpirun -np N wavetrace render ...): the job's
// coordinator (rank 0, or the only process) hands out sample chunks and
// merges them in order (render/distributed.h); worker ranks render the
// chunks rank 0 sends them. The protocol is in docs/scale-out.md.
#pragma once

#include "render/distributed.h"
#include "render/halting.h"

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace wt {

/// This process's place in an MPI job: size 1 when the build has no MPI or
/// the process was not started by an MPI launcher (mpirun, srun).
class MpiWorld {
 public:
  /// MPI_Init_thread (funneled: only the main thread calls MPI) when an MPI
  /// launcher started the process.
  MpiWorld(int& argc, char**& argv);
  ~MpiWorld();
  int rank() const { return m_rank; }
  int size() const { return m_size; }
  bool active() const { return m_size > 1; }
  /// End every rank of the job now with `code` (a failure rank 0 has
  /// reported; the others may be blocked or gone). A non-zero code under
  /// Open MPI's `mpirun --enable-recovery`, which exits 0 after any
  /// MPI_Abort, stops the launcher with SIGTERM instead (docs/scale-out.md).
  [[noreturn]] void abort(int code) const;
  /// Under `mpirun --enable-recovery`: a non-zero exit status after
  /// MPI_Finalize would not reach the user, only abort's would.
  bool launcherIgnoresExitStatus() const;
  /// End this process with `code` without calling MPI (from a thread other
  /// than the one that calls MPI, which may be blocked inside it): under
  /// `mpirun --enable-recovery` a non-zero code first stops the launcher, as
  /// abort does.
  [[noreturn]] void exitWithoutMpi(int code) const;
  /// Started by Slurm's srun (not by mpirun, also where mpirun runs in a
  /// Slurm job): Slurm kills every task when one ends without MPI_Finalize,
  /// so an MPI_Abort(0) reaches the user as the killed tasks' 137.
  bool launchedBySrun() const;
  /// The exit status of a job that wrote its whole image but lost a rank or
  /// a device, under srun, where 0 cannot be had (docs/scale-out.md, Faults).
  static constexpr int kCompleteWithLosses = 3;
  /// The host a rank runs on (MPI_Get_processor_name, exchanged at start).
  std::string host(int rank) const;
  /// Under `mpirun --enable-recovery`, started by Open MPI's daemon (orted):
  /// there any non-zero exit status, even after MPI_Finalize, leaves mpirun
  /// waiting forever (Open MPI 4.1.4), so only 0 ends the job.
  bool onRecoveringDaemon() const;
  /// Why this rank must not run ("" if it may): under `mpirun
  /// --enable-recovery` a rank started by Open MPI's daemon (orted, on a
  /// machine other than mpirun's), where Open MPI 4.1 cannot end a job whose
  /// rank died or hung (docs/scale-out.md).
  std::string unsupportedLaunch() const;
  /// Every rank passes its start-up failure ("" if none) and the hash of
  /// what it will render; all return normally only if every rank started
  /// and all hashes agree, else every rank throws. Rank 0's exception names
  /// each failed rank and its message; the others' is empty (rank 0 reports).
  /// A rank that has not reached this point `timeoutSeconds` after rank 0
  /// did (hung while loading, or dead) makes rank 0 name it and end the job;
  /// a rank 0 that has not, `timeoutSeconds` after a worker did, makes that
  /// worker name rank 0 and end the job.
  void agreeOnStart(const std::string& error, std::uint64_t renderHash, double timeoutSeconds = 120.0);
  static bool builtWithMpi();

 private:
  int m_rank = 0, m_size = 1;
  bool m_initialized = false;
  std::vector<std::string> m_hosts;
};

/// The devices of one process, each with its own context and renderer.
struct DeviceSet {
  std::vector<std::unique_ptr<Context>> contexts;
  std::vector<std::unique_ptr<Renderer>> renderers;
  std::vector<std::string> names;  ///< "device 1 (cpu-haswell)"
};

struct ScaleOutResult;

struct ScaleOutOptions {
  int samplesPerPixel = 64;  ///< total, counting resumed samples
  int chunkSpp = 0;          ///< samples per chunk
  double timeSeconds = 0.0;  ///< stop handing out chunks after this long; 0: no limit
  bool quiet = false;
  double checkpointSeconds = 0.0;  ///< call `checkpoint` this often with the merged prefix; 0: never
  std::function<void(const Moments&)> checkpoint;
  std::function<bool()> interrupted;  ///< a signal asked the job to stop
  double targetError = 0.0;  ///< stop at the first chunk boundary whose merged estimate meets it; 0: none
  /// Called with the merged prefix after each chunk merged, in chunk order
  /// (--reference's error log).
  std::function<void(const Moments&)> merged;
  /// Rank 0's last resort, called on a watchdog thread when its main thread
  /// is stuck inside one MPI call (0.3 s once a signal has come, else
  /// --rank-timeout): the devices are stopped and `result` holds what was
  /// merged; it writes that and ends the process without calling MPI.
  std::function<void(ScaleOutResult&)> rescue;
  /// A worker rank that shows no progress for this long (no message, or
  /// heartbeats whose pass count stands still while it holds a chunk) is
  /// lost: its chunks go to the others (--rank-timeout).
  double rankTimeoutSeconds = kDefaultRankTimeout;
  static constexpr double kDefaultRankTimeout = 120.0;
  /// A job of several ranks checkpoints (and writes its outputs) this often
  /// when --checkpoint is not given, or less often where a write takes long.
  static constexpr double kJobCheckpointSeconds = 60.0;
};

/// How often a worker rank sends its heartbeat for a rank timeout: four
/// beats per timeout, at most one a second.
double heartbeatSeconds(double rankTimeoutSeconds);

struct ScaleOutResult {
  Moments merged;            ///< the merged prefix of the samples
  std::string failure;       ///< a device or rank failed: who and why
  bool interrupted = false;  ///< stopped by a signal (under mpirun also: a rank died)
  /// When stopped by a signal: the running worker rank heard from least recently,
  /// "rank N on host H, for S s" ("" if none): under mpirun likely the one that died.
  std::string silentLongest;
  HaltReason reason = HaltReason::None;
  double seconds = 0.0;      ///< wall time from the first chunk
  double mergeSeconds = 0.0; ///< of it, merging on this process
  double receiveSeconds = 0.0;     ///< of it, receiving and unpacking other ranks' results
  double localOverheadSeconds = 0.0;  ///< this process's devices' chunk time outside sample passes
  int localChunks = 0;
  std::uint64_t bytesReceived = 0; ///< result bytes from other ranks
  std::uint64_t raysTraced = 0;
  int chunks = 0;            ///< chunks merged
  std::vector<int> chunksByRank;  ///< chunks each rank rendered (this process: all, in-process)
  /// Worker ranks lost to --rank-timeout, each "rank N: why" (their chunks
  /// were rendered again by the others; the ranks are still running, or hung).
  std::vector<std::string> lostRanks;
  /// This process's devices lost the same way (a sample pass that never
  /// ends): their threads are left behind, so the process must end by
  /// MpiWorld::abort, never by returning.
  std::vector<std::string> lostDevices;
  int outputDevice = 0;      ///< a device not lost: the one to write the image with
  double lastError = -1.0;   ///< with a target error: the last estimate, and its sample count
  int lastErrorSamples = 0;
};

/// Rank 0 (or the only process): hand out the chunks of
/// [start.sampleEnd, samplesPerPixel) to this process's devices and to the
/// other ranks, merge them in order, report progress. `start`: the moments
/// already merged (a resumed checkpoint's, else empty).
ScaleOutResult coordinateRender(DeviceSet& devices, const ScaleOutOptions& options, Moments start,
                                const MpiWorld& world);

/// A rank other than 0: render the chunks rank 0 sends until it says stop,
/// with a heartbeat (its sample-pass count) every
/// heartbeatSeconds(rankTimeoutSeconds). Ends the job (MpiWorld::abort(1),
/// with an error naming rank 0) when rank 0 sends nothing, not even its
/// heartbeat, for `rankTimeoutSeconds`. Returns non-zero after a local
/// failure (reported to rank 0).
int serveRender(DeviceSet& devices, const MpiWorld& world, const std::function<bool()>& interrupted,
                double rankTimeoutSeconds);

}  // namespace wt
