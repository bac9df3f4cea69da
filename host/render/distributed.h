// One image on several devices and, with MPI, several processes: the
// samples are cut into chunks of consecutive sample indices, handed out as
// devices ask for them (dynamic balancing), each chunk accumulated from
// zero on its device, and the chunks' moments merged on the host in chunk
// order, in double precision. Random numbers are a pure function of
// (pixel, sample, bounce, dimension, seed) and the merge order is the
// chunk order, so the image does not depend on which device or process
// rendered which chunk: for a chunk size it is the same, bit for bit, on
// any number of devices and ranks (docs/scale-out.md).
#pragma once

#include "render/renderer.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace wt {

/// Consecutive sample indices [firstSample, firstSample + sampleCount).
struct SampleChunk {
  int index = 0;        ///< position in the plan: the merge order
  int firstSample = 0;  ///< sample index of its first pass
  int sampleCount = 0;
};

/// Per-pixel running mean and second moment of a run of consecutive
/// samples, rgb, in double: what a chunk's device accumulation resolves to
/// and what the merge keeps.
struct Moments {
  int firstSample = 0;                 ///< the run is [firstSample, sampleEnd)
  int sampleEnd = 0;
  std::uint64_t nonFiniteSamples = 0;  ///< NaN/Inf samples discarded in the run
  std::vector<double> mean;            ///< 3 per pixel
  std::vector<double> m2;              ///< 3 per pixel: sum of squared deviations from the mean
  std::vector<std::uint32_t> count;    ///< finite samples per pixel
  /// With AOVs (RenderSettings::aovs): kernels/aov.cl's per-pixel sums, 16
  /// per pixel, summed over the run (a chunk's are its device's float sums,
  /// exact in double); else empty.
  std::vector<double> aovSum;
  /// With AOVs: the ids of sample 0 (4 per pixel), from the run that holds
  /// it; other runs' are whatever their device last wrote and are not kept.
  std::vector<std::uint32_t> aovIds;
  std::size_t pixels() const { return count.size(); }
  bool hasAovs() const { return !aovSum.empty(); }
};

/// An empty run of `pixels` pixels starting at sample `firstSample`, with
/// room for AOV sums when `aovs`.
Moments emptyMoments(std::size_t pixels, int firstSample, bool aovs = false);

/// The moments a device accumulation holds (accumulate.cl's state in
/// `mode`, WT_ACCUMULATE_*): kahan's compensation folded into the double
/// mean, double mode's values as they are. The run ends at
/// accumulation.samplesDone.
Moments momentsFromAccumulation(const Accumulation& accumulation, std::uint32_t mode, int firstSample);

/// The device state in `mode` that holds `moments` (kahan: the float value
/// and the compensation that carries its rounding), with samplesDone the
/// run's end: what Renderer::restoreAccumulation takes, and a checkpoint.
Accumulation accumulationFromMoments(const Moments& moments, std::uint32_t mode);

/// Fold the run `next` into `into` (Chan, Golub and LeVeque's pairwise
/// update of mean and M2), in double; AOV sums are added, and the ids come
/// from the run that starts at sample 0. `next` must start where `into`
/// ends; throws std::invalid_argument otherwise or when the pixel counts
/// or the presence of AOVs differ.
void mergeMoments(Moments& into, const Moments& next);

/// An Image (rgb mean, unbiased variance, sample counts; no srgba) of the
/// moments, for the error estimate.
Image imageFromMoments(const Moments& moments, int width, int height);

/// The Image (rgb mean, variance, sample counts, AOVs, samplesDone; no
/// srgba) that Renderer::readImage gives after
/// restoreAccumulation(accumulationFromMoments(moments, mode)) in any mode,
/// bit for bit, made on the host: the resolve only rounds the mean and M2
/// to float. So a thread that has no device of its own can write the image.
Image resolvedImage(const Moments& moments, int width, int height);

/// The chunks of samples [firstSample, samplesPerPixel) of chunkSpp
/// samples each (the last may be shorter), handed out in order; thread-safe.
/// A chunk handed out and then given back (its renderer was lost) is
/// handed out again before any new one, lowest index first.
class ChunkPlan {
 public:
  ChunkPlan(int firstSample, int samplesPerPixel, int chunkSpp);
  /// The next chunk to render: a given-back one, else a new one; none when
  /// there is neither (every chunk out, or closed).
  std::optional<SampleChunk> next();
  /// As next(), but while chunks are out (handed out, not completed) and
  /// none is to hand, wait: one of them may be given back. None when every
  /// chunk is completed, on cancel(), or when `stop` is set.
  std::optional<SampleChunk> nextOrWait(const std::atomic<bool>& stop);
  /// A chunk handed out is done (its result merged, or dropped).
  void complete(int index);
  /// A chunk handed out will not come back: hand it out again.
  void giveBack(int index);
  /// Hand out no new chunks (time budget); given-back ones still go out,
  /// so that the chunks out before still make a whole prefix.
  void close();
  /// Hand out nothing more (interrupt, a failure, the target error reached).
  void cancel();
  bool closed() const;
  /// Nothing to hand out and nothing out: every chunk completed, or the
  /// plan cancelled (a chunk out may still be given back until then).
  bool settled() const;
  int chunkCount() const { return m_count; }
  int issued() const;
  /// The chunk at `index` of the plan.
  SampleChunk chunk(int index) const;

 private:
  std::optional<SampleChunk> nextLocked();
  int m_first, m_end, m_chunkSpp, m_count;
  mutable std::mutex m_mutex;
  std::condition_variable m_cv;
  int m_next = 0;
  bool m_closed = false, m_cancelled = false;
  std::set<int> m_out, m_givenBack;
};

/// The chunk size when --chunk-spp is not given: a function of the sample
/// count only, never of the device or rank count, so that the image is the
/// same however many render it. About 64 chunks, of 1 to 64 samples.
int defaultChunkSpp(int samplesPerPixel);

/// Merges finished chunks in chunk order; chunks that arrive early wait.
/// The merged run is always a prefix [start, samplesDone()) of the plan's
/// samples, so what it holds is a valid image and checkpoint at any time.
class OrderedMerge {
 public:
  explicit OrderedMerge(Moments start, int firstChunkIndex = 0);
  /// Take a finished chunk (any order); merges every chunk now in order.
  /// A chunk already merged or waiting is dropped (false): a chunk given
  /// back and rendered again may arrive twice.
  bool add(int chunkIndex, Moments moments);
  /// Called after each chunk merged with the merged prefix; returning false
  /// ends the merge there (later chunks are dropped): --target-error stops
  /// at the first chunk boundary that meets it, whatever arrives after.
  void onMerged(std::function<bool(const Moments&)> callback) { m_onMerged = std::move(callback); }
  bool ended() const { return m_ended; }
  const Moments& merged() const { return m_merged; }
  int samplesDone() const { return m_merged.sampleEnd; }
  int mergedChunks() const { return m_nextIndex; }
  std::size_t waiting() const { return m_waiting.size(); }
  double mergeSeconds() const { return m_seconds; }

 private:
  Moments m_merged;
  int m_nextIndex;
  std::map<int, Moments> m_waiting;
  double m_seconds = 0.0;
  std::function<bool(const Moments&)> m_onMerged;
  bool m_ended = false;
};

/// Render one chunk on `renderer` (its accumulation reset to the chunk's
/// first sample) and read its moments back; none when `stop` is set
/// between two passes. `passes`, if given, counts every sample pass done
/// (a worker rank's heartbeat reports it).
std::optional<Moments> renderChunk(Renderer& renderer, const SampleChunk& chunk, const std::atomic<bool>* stop,
                                   std::atomic<std::uint64_t>* passes = nullptr);

/// A finished chunk, or the failure of the device that had it.
struct ChunkResult {
  SampleChunk chunk;
  Moments moments;
  std::string error;            ///< non-empty: the device failed; moments empty
  std::uint64_t raysTraced = 0;
  double seconds = 0.0;         ///< the chunk's render time on its device
  double overheadSeconds = 0.0; ///< of the chunk's time on its device, not rendering: reset, read-back, conversion
};

/// Thread-safe hand-over of results from device threads to the merging thread.
class ResultQueue {
 public:
  void push(ChunkResult result);
  /// The oldest result, waiting up to `timeoutSeconds`.
  std::optional<ChunkResult> pop(double timeoutSeconds);

 private:
  std::mutex m_mutex;
  std::condition_variable m_cv;
  std::deque<ChunkResult> m_results;
};

/// Where a device thread gets its chunks: a ChunkPlan in-process, or (on an
/// MPI worker rank) chunks that rank 0 sends.
class ChunkSource {
 public:
  virtual ~ChunkSource() = default;
  virtual std::optional<SampleChunk> next() = 0;
};

class PlanSource : public ChunkSource {
 public:
  explicit PlanSource(ChunkPlan& plan) : m_plan(plan) {}
  std::optional<SampleChunk> next() override { return m_plan.next(); }

 private:
  ChunkPlan& m_plan;
};

/// The device threads' loop: take chunks from `source` until it has none or
/// `stop` is set, render each on `renderer`, push the results (a failure is
/// pushed as an error result and ends the loop).
void runDeviceWorker(Renderer& renderer, ChunkSource& source, ResultQueue& results, const std::atomic<bool>& stop,
                     const std::string& deviceName, std::atomic<std::uint64_t>* passes = nullptr);

/// The devices --device names: "" (the default device), an index or name
/// substring, a comma-separated list of those, or "all". A device named
/// twice gets two contexts (two queues on one device). Throws DeviceError
/// naming the entry that matches none.
std::vector<DeviceInfo> selectDevices(const std::string& spec);

}  // namespace wt
