// OpenCL platforms and devices, the context and queue of the chosen one, and
// the single launch helper every stage goes through.
#pragma once

#include <CL/opencl.hpp>

#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace wt {

/// No platform, no device matching the request, a failed build or launch.
struct DeviceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct DeviceInfo {
  int index = 0;              ///< position in listDevices(), across all platforms
  std::string platformName;
  std::string name;
  std::string version;        ///< CL_DEVICE_VERSION
  bool isGpu = false;
  bool isCpu = false;         ///< CL_DEVICE_TYPE_CPU (Oclgrind's simulator claims GPU and CPU)
  bool fp64 = false;
  int nativeFloatWidth = 1;   ///< CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT
  std::uint64_t globalCacheBytes = 0;  ///< CL_DEVICE_GLOBAL_MEM_CACHE_SIZE (0: not reported)
  cl::Platform platform;
  cl::Device device;
};

/// Every device of every platform, in a stable order.
std::vector<DeviceInfo> listDevices();

/// The default device: the first GPU, else the first device.
int defaultDeviceIndex(const std::vector<DeviceInfo>& devices);

/// Pick by index ("1") or by a case-insensitive substring of the device or
/// platform name ("pthread"); "" picks the default. Throws DeviceError.
DeviceInfo selectDevice(const std::string& spec);

/// Per-stage kernel time from profiling events (benchmarks).
struct StageTimes {
  std::map<std::string, double> seconds;
  std::map<std::string, std::size_t> launches;
};

class Context {
 public:
  explicit Context(const DeviceInfo& device, bool profiling = false);

  const DeviceInfo& info() const { return m_info; }
  cl::Context& context() { return m_context; }
  cl::CommandQueue& queue() { return m_queue; }

  /// Enqueue `kernel` over `count` work-items in groups of `localSize`
  /// (global size rounded up; kernels guard with `if (i >= count) return`).
  /// On PoCL's CPU devices a kernel's first launch here is at least
  /// kPoclSmallGridWidth wide (widenFirstLaunches()).
  /// With profiling on, the kernel time is added to stageTimes()[stage].
  /// `event`, where given and profiling is on, receives the launch's event
  /// (no event at all with profiling off: that path must cost nothing).
  void launch(const char* stage, cl::Kernel& kernel, std::size_t count,
              std::size_t localSize = kLocalSize, cl::Event* event = nullptr);
  /// Wait for the queue and fold pending profiling events into the totals.
  void finish();

  /// Set `bytes` bytes of `buffer` from `offset` (both multiples of 4) to
  /// copies of `word`, in queue order. Every buffer fill goes through here.
  void fill(cl::Buffer& buffer, cl_uint word, std::size_t offset, std::size_t bytes, cl::Event* event = nullptr);

  /// The device is Oclgrind's simulator (scripts/oclgrind), which needs a
  /// few accommodations; each is documented where it is made.
  bool underOclgrind() const { return m_oclgrind; }

  /// PoCL compiles a second work-group function for a kernel first launched
  /// narrower than kPoclSmallGridWidth ("-smallgrid" in its cache) and
  /// reuses a wide one for later narrower launches in the process, so a
  /// wide first launch makes every image size share one compiled variant.
  bool widenFirstLaunches() const { return m_widenFirstLaunches; }
  /// The global size launch() last enqueued (0: none yet).
  std::size_t lastGlobalSize() const { return m_lastGlobal; }

  /// A program built here before with the same key (programCacheKey, hex):
  /// a second renderer or tracer with the same switches takes it instead of
  /// building it again. Kept: the last kKeptPrograms built.
  std::optional<cl::Program> builtProgram(const std::string& key) const;
  void keepProgram(const std::string& key, const cl::Program& program);
  static constexpr std::size_t kKeptPrograms = 16;

  /// The queue was made with CL_QUEUE_PROFILING_ENABLE.
  bool profiling() const { return m_profiling; }
  const StageTimes& stageTimes() const { return m_times; }
  void resetStageTimes() { m_times = {}; }

  static constexpr std::size_t kLocalSize = 64;
  /// Work-items per group of the stream kernels (kernels/bvh_stream.cl):
  /// each takes WT_STREAM_WINDOW rays, so groups of 64 would leave a
  /// 200 000-ray batch 13 groups to share among the threads.
  static constexpr std::size_t kStreamLocalSize = 4;
  /// PoCL's grid_width_specialization_limit on CPU devices (USHRT_MAX):
  /// grids narrower than this get their own work-group function.
  static constexpr std::size_t kPoclSmallGridWidth = 65535;

 private:
  DeviceInfo m_info;
  cl::Context m_context;
  cl::CommandQueue m_queue;
  bool m_profiling;
  bool m_oclgrind;
  bool m_widenFirstLaunches;
  /// Programs launched here, each held (so a released program's address
  /// cannot come back as a new one's), with its (kernel, local size) launched.
  struct LaunchedProgram {
    cl::Program program;
    std::set<std::pair<std::string, std::size_t>> kernels;
  };
  std::map<cl_program, LaunchedProgram> m_launched;
  std::size_t m_lastGlobal = 0;
  std::vector<std::pair<std::string, cl::Event>> m_pending;
  std::vector<std::pair<std::string, cl::Program>> m_programs;  ///< oldest first
  StageTimes m_times;
};

/// "CL_OUT_OF_RESOURCES" for -5, etc.
std::string clErrorName(int code);

}  // namespace wt
