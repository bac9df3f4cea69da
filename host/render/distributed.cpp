#include "render/distributed.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <stdexcept>

namespace wt {
namespace {

/// float(x) - x, as a float. Out of line: inlined into the loop below, GCC
/// 12.2 at -O3 made it 0 in two of the three channels
/// (DistributedMerge.AccumulationStateRoundTrip fails without this).
[[gnu::noinline]] float roundingExcess(double x) {
  const float rounded = float(x);
  return float(double(rounded) - x);
}

}  // namespace

Moments emptyMoments(std::size_t pixels, int firstSample, bool aovs) {
  Moments m;
  m.firstSample = m.sampleEnd = firstSample;
  m.mean.assign(3 * pixels, 0.0);
  m.m2.assign(3 * pixels, 0.0);
  m.count.assign(pixels, 0u);
  if (aovs) {
    m.aovSum.assign(16 * pixels, 0.0);
    m.aovIds.assign(4 * pixels, 0xffffffffu);  // Aovs::kNoId until sample 0 is merged
  }
  return m;
}

Moments momentsFromAccumulation(const Accumulation& a, std::uint32_t mode, int firstSample) {
  const std::size_t pixels = a.samples.size();
  if (a.state.size() != pixels * kAccumulationStateBytes)
    throw std::invalid_argument("accumulation state of " + std::to_string(a.state.size()) + " bytes for " +
                                std::to_string(pixels) + " pixels");
  if (!a.aovs.empty() && a.aovs.size() != pixels * (kAovSumBytes + kAovIdBytes))
    throw std::invalid_argument("AOV accumulation of " + std::to_string(a.aovs.size()) + " bytes for " +
                                std::to_string(pixels) + " pixels");
  Moments m = emptyMoments(pixels, firstSample, !a.aovs.empty());
  m.sampleEnd = a.samplesDone;
  m.nonFiniteSamples = a.nonFiniteSamples;
  m.count = a.samples;
  if (!a.aovs.empty()) {
    std::vector<float> sums(16 * pixels);
    std::memcpy(sums.data(), a.aovs.data(), pixels * kAovSumBytes);
    std::copy(sums.begin(), sums.end(), m.aovSum.begin());
    std::memcpy(m.aovIds.data(), a.aovs.data() + pixels * kAovSumBytes, pixels * kAovIdBytes);
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint8_t* s = a.state.data() + i * kAccumulationStateBytes;
    if (mode == WT_ACCUMULATE_DOUBLE) {
      double d[8];  // double4 mean, double4 m2
      std::memcpy(d, s, sizeof d);
      for (int c = 0; c < 3; ++c) m.mean[3 * i + c] = d[c], m.m2[3 * i + c] = d[4 + c];
      continue;
    }
    float f[16];  // float4 mean, m2, and kahan's compensations
    std::memcpy(f, s, sizeof f);
    const bool kahan = mode == WT_ACCUMULATE_KAHAN;
    for (int c = 0; c < 3; ++c) {
      // kahan's compensation is the excess the stored value carries
      m.mean[3 * i + c] = double(f[c]) - (kahan ? double(f[8 + c]) : 0.0);
      m.m2[3 * i + c] = double(f[4 + c]) - (kahan ? double(f[12 + c]) : 0.0);
    }
  }
  return m;
}

Accumulation accumulationFromMoments(const Moments& m, std::uint32_t mode) {
  const std::size_t pixels = m.pixels();
  Accumulation a;
  a.samplesDone = m.sampleEnd;
  a.nonFiniteSamples = m.nonFiniteSamples;
  a.samples = m.count;
  a.state.assign(pixels * kAccumulationStateBytes, 0u);
  if (m.hasAovs()) {
    // the device holds float sums: one rounding of the double sums
    std::vector<float> sums(m.aovSum.begin(), m.aovSum.end());
    a.aovs.resize(pixels * (kAovSumBytes + kAovIdBytes));
    std::memcpy(a.aovs.data(), sums.data(), pixels * kAovSumBytes);
    std::memcpy(a.aovs.data() + pixels * kAovSumBytes, m.aovIds.data(), pixels * kAovIdBytes);
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    std::uint8_t* s = a.state.data() + i * kAccumulationStateBytes;
    if (mode == WT_ACCUMULATE_DOUBLE) {
      double d[8] = {};
      for (int c = 0; c < 3; ++c) d[c] = m.mean[3 * i + c], d[4 + c] = m.m2[3 * i + c];
      std::memcpy(s, d, sizeof d);
      continue;
    }
    float f[16] = {};
    for (int c = 0; c < 3; ++c) {
      f[c] = float(m.mean[3 * i + c]);
      f[4 + c] = float(m.m2[3 * i + c]);
      if (mode == WT_ACCUMULATE_KAHAN) {
        // the rounding to float, carried as the compensation (value - excess = exact)
        f[8 + c] = roundingExcess(m.mean[3 * i + c]);
        f[12 + c] = roundingExcess(m.m2[3 * i + c]);
      }
    }
    std::memcpy(s, f, sizeof f);
  }
  return a;
}

void mergeMoments(Moments& into, const Moments& next) {
  if (next.pixels() != into.pixels())
    throw std::invalid_argument("merging moments of " + std::to_string(next.pixels()) + " pixels into " +
                                std::to_string(into.pixels()));
  if (next.firstSample != into.sampleEnd)
    throw std::invalid_argument("merging samples from " + std::to_string(next.firstSample) +
                                " into a run that ends at " + std::to_string(into.sampleEnd));
  if (next.hasAovs() != into.hasAovs())
    throw std::invalid_argument(std::string("merging moments ") + (next.hasAovs() ? "with" : "without") +
                                " AOVs into a run " + (into.hasAovs() ? "with" : "without"));
  const std::size_t pixels = into.pixels();
  if (into.hasAovs()) {
    for (std::size_t k = 0; k < 16 * pixels; ++k) into.aovSum[k] += next.aovSum[k];
    if (next.firstSample == 0) into.aovIds = next.aovIds;  // the device writes the ids at sample 0 only
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint32_t nb = next.count[i];
    if (nb == 0) continue;
    const std::uint32_t na = into.count[i];
    const double n = double(na) + double(nb);
    const double wb = double(nb) / n, wab = double(na) * double(nb) / n;
    for (int c = 0; c < 3; ++c) {
      const std::size_t k = 3 * i + c;
      const double delta = next.mean[k] - into.mean[k];
      into.mean[k] += delta * wb;
      into.m2[k] += next.m2[k] + delta * delta * wab;
    }
    into.count[i] = na + nb;
  }
  into.sampleEnd = next.sampleEnd;
  into.nonFiniteSamples += next.nonFiniteSamples;
}

namespace {

/// The mean and the unbiased variance of the moments; `asDevice`: M2 rounded
/// to float before the division, as the device's resolve does.
Image momentsImage(const Moments& m, int width, int height, bool asDevice) {
  Image image;
  image.width = width;
  image.height = height;
  image.samples = m.count;
  const std::size_t pixels = m.pixels();
  image.rgb.resize(3 * pixels);
  image.rgbVariance.resize(3 * pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    const std::uint32_t n = m.count[i];
    for (int c = 0; c < 3; ++c) {
      const double m2 = m.m2[3 * i + c];
      image.rgb[3 * i + c] = float(m.mean[3 * i + c]);
      image.rgbVariance[3 * i + c] =
          n <= 1 ? 0.0f : asDevice ? float(m2) / float(n - 1) : float(m2 / double(n - 1));
    }
  }
  return image;
}

}  // namespace

Image imageFromMoments(const Moments& m, int width, int height) { return momentsImage(m, width, height, false); }

Image resolvedImage(const Moments& m, int width, int height) {
  // accumulate_resolve's float mean and M2; the variance as Renderer::readResolved divides, in float
  Image image = momentsImage(m, width, height, true);
  image.samplesDone = m.sampleEnd;
  const std::size_t pixels = m.pixels();
  if (m.hasAovs()) {
    // the device's float sums, as accumulationFromMoments restores them
    const std::vector<float> sums(m.aovSum.begin(), m.aovSum.end());
    image.aovs = decodeAovs(sums.data(), m.aovIds.data(), pixels);
  }
  return image;
}

ChunkPlan::ChunkPlan(int firstSample, int samplesPerPixel, int chunkSpp)
    : m_first(firstSample), m_end(std::max(firstSample, samplesPerPixel)), m_chunkSpp(std::max(1, chunkSpp)) {
  m_count = (m_end - m_first + m_chunkSpp - 1) / m_chunkSpp;
}

SampleChunk ChunkPlan::chunk(int index) const {
  SampleChunk c;
  c.index = index;
  c.firstSample = m_first + index * m_chunkSpp;
  c.sampleCount = std::min(m_chunkSpp, m_end - c.firstSample);
  return c;
}

std::optional<SampleChunk> ChunkPlan::nextLocked() {
  if (m_cancelled) return std::nullopt;
  int index;
  if (!m_givenBack.empty()) {
    index = *m_givenBack.begin();
    m_givenBack.erase(m_givenBack.begin());
  } else if (!m_closed && m_next < m_count) {
    index = m_next++;
  } else {
    return std::nullopt;
  }
  m_out.insert(index);
  return chunk(index);
}

std::optional<SampleChunk> ChunkPlan::next() {
  std::lock_guard<std::mutex> lock(m_mutex);
  return nextLocked();
}

std::optional<SampleChunk> ChunkPlan::nextOrWait(const std::atomic<bool>& stop) {
  std::unique_lock<std::mutex> lock(m_mutex);
  while (!stop.load()) {
    if (std::optional<SampleChunk> c = nextLocked()) return c;
    if (m_cancelled || m_out.empty()) return std::nullopt;
    // bounded: `stop` is set without notifying
    m_cv.wait_for(lock, std::chrono::milliseconds(50));
  }
  return std::nullopt;
}

void ChunkPlan::complete(int index) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_out.erase(index);
  }
  m_cv.notify_all();
}

void ChunkPlan::giveBack(int index) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    if (m_out.erase(index)) m_givenBack.insert(index);
  }
  m_cv.notify_all();
}

void ChunkPlan::close() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_closed = true;
  }
  m_cv.notify_all();
}

void ChunkPlan::cancel() {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_closed = m_cancelled = true;
  }
  m_cv.notify_all();
}

bool ChunkPlan::closed() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_cancelled || ((m_closed || m_next >= m_count) && m_givenBack.empty());
}

bool ChunkPlan::settled() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_cancelled || ((m_closed || m_next >= m_count) && m_givenBack.empty() && m_out.empty());
}

int ChunkPlan::issued() const {
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_next;
}

int defaultChunkSpp(int samplesPerPixel) { return std::clamp((samplesPerPixel + 63) / 64, 1, 64); }

OrderedMerge::OrderedMerge(Moments start, int firstChunkIndex)
    : m_merged(std::move(start)), m_nextIndex(firstChunkIndex) {}

bool OrderedMerge::add(int chunkIndex, Moments moments) {
  if (m_ended || chunkIndex < m_nextIndex || m_waiting.count(chunkIndex)) return false;
  const auto start = std::chrono::steady_clock::now();
  m_waiting.emplace(chunkIndex, std::move(moments));
  // merge in chunk order only: the same sums in the same order on any device count
  for (auto it = m_waiting.find(m_nextIndex); it != m_waiting.end(); it = m_waiting.find(m_nextIndex)) {
    mergeMoments(m_merged, it->second);
    m_waiting.erase(it);
    ++m_nextIndex;
    if (m_onMerged && !m_onMerged(m_merged)) {
      m_ended = true;
      m_waiting.clear();
      break;
    }
  }
  m_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return true;
}

std::optional<Moments> renderChunk(Renderer& renderer, const SampleChunk& chunk, const std::atomic<bool>* stop,
                                   std::atomic<std::uint64_t>* passes) {
  renderer.resetAccumulation(chunk.firstSample);
  for (int k = 0; k < chunk.sampleCount; ++k) {
    if (stop && stop->load()) return std::nullopt;
    renderer.renderSample();
    if (passes) ++*passes;
  }
  return momentsFromAccumulation(renderer.saveAccumulation(), renderer.settings().accumulation, chunk.firstSample);
}

void ResultQueue::push(ChunkResult result) {
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_results.push_back(std::move(result));
  }
  m_cv.notify_one();
}

std::optional<ChunkResult> ResultQueue::pop(double timeoutSeconds) {
  std::unique_lock<std::mutex> lock(m_mutex);
  if (!m_cv.wait_for(lock, std::chrono::duration<double>(timeoutSeconds), [&] { return !m_results.empty(); }))
    return std::nullopt;
  ChunkResult r = std::move(m_results.front());
  m_results.pop_front();
  return r;
}

void runDeviceWorker(Renderer& renderer, ChunkSource& source, ResultQueue& results, const std::atomic<bool>& stop,
                     const std::string& deviceName, std::atomic<std::uint64_t>* passes) {
  while (!stop.load()) {
    std::optional<SampleChunk> chunk = source.next();
    if (!chunk) return;
    ChunkResult r;
    r.chunk = *chunk;
    const RenderStats before = renderer.stats();
    const auto start = std::chrono::steady_clock::now();
    try {
      std::optional<Moments> m = renderChunk(renderer, *chunk, &stop, passes);
      if (!m) return;  // stopped mid-chunk: its passes are dropped
      r.moments = std::move(*m);
    } catch (const std::exception& e) {
      r.error = deviceName + ": " + e.what();
      results.push(std::move(r));
      return;
    }
    r.raysTraced = renderer.stats().raysTraced - before.raysTraced;
    r.seconds = renderer.stats().seconds - before.seconds;
    r.overheadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() - r.seconds;
    results.push(std::move(r));
  }
}

std::vector<DeviceInfo> selectDevices(const std::string& spec) {
  if (spec == "all") {
    std::vector<DeviceInfo> devices = listDevices();
    if (devices.empty())
      throw DeviceError("--device all: no OpenCL device found (is an ICD such as pocl-opencl-icd installed?)");
    return devices;
  }
  std::vector<DeviceInfo> devices;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = spec.find(',', start);
    const std::string entry = spec.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (entry.empty() && spec.find(',') != std::string::npos)
      throw DeviceError("--device " + spec + ": an empty entry in the list");
    devices.push_back(selectDevice(entry));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return devices;
}

}  // namespace wt
