#include "device/context.h"

#include <algorithm>
#include <cctype>

namespace wt {

std::vector<DeviceInfo> listDevices() {
  std::vector<DeviceInfo> result;
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error&) {
    return result;  // no ICD or no platform: callers report "no OpenCL device"
  }
  for (cl::Platform& platform : platforms) {
    std::vector<cl::Device> devices;
    try {
      platform.getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error&) {
      continue;
    }
    for (cl::Device& device : devices) {
      DeviceInfo info;
      info.index = int(result.size());
      info.platformName = platform.getInfo<CL_PLATFORM_NAME>();
      info.name = device.getInfo<CL_DEVICE_NAME>();
      info.version = device.getInfo<CL_DEVICE_VERSION>();
      info.isGpu = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
      info.isCpu = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_CPU) != 0;
      info.fp64 = device.getInfo<CL_DEVICE_EXTENSIONS>().find("cl_khr_fp64") != std::string::npos;
      info.nativeFloatWidth = int(device.getInfo<CL_DEVICE_NATIVE_VECTOR_WIDTH_FLOAT>());
      info.globalCacheBytes = device.getInfo<CL_DEVICE_GLOBAL_MEM_CACHE_SIZE>();
      info.platform = platform;
      info.device = device;
      result.push_back(std::move(info));
    }
  }
  return result;
}

int defaultDeviceIndex(const std::vector<DeviceInfo>& devices) {
  for (const DeviceInfo& d : devices)
    if (d.isGpu) return d.index;
  return devices.empty() ? -1 : 0;
}

namespace {
std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}
}  // namespace

DeviceInfo selectDevice(const std::string& spec) {
  std::vector<DeviceInfo> devices = listDevices();
  if (devices.empty())
    throw DeviceError(
        "no OpenCL device found (is an ICD such as pocl-opencl-icd installed? see 'wavetrace devices')");
  if (spec.empty()) return devices[defaultDeviceIndex(devices)];
  bool numeric = std::all_of(spec.begin(), spec.end(), [](unsigned char c) { return std::isdigit(c); });
  if (numeric) {
    long index = std::stol(spec);
    if (index < 0 || index >= long(devices.size()))
      throw DeviceError("--device " + spec + ": no such device index (" +
                        std::to_string(devices.size()) + " devices; see 'wavetrace devices')");
    return devices[index];
  }
  std::string needle = lower(spec);
  for (const DeviceInfo& d : devices)
    if (lower(d.name).find(needle) != std::string::npos ||
        lower(d.platformName).find(needle) != std::string::npos)
      return d;
  throw DeviceError("--device " + spec + ": no device name contains '" + spec +
                    "' (see 'wavetrace devices')");
}

Context::Context(const DeviceInfo& device, bool profiling)
    : m_info(device), m_profiling(profiling),
      m_oclgrind(device.platformName.find("Oclgrind") != std::string::npos),
      m_widenFirstLaunches(device.isCpu && !device.isGpu &&
                           device.platformName.find("Portable Computing Language") != std::string::npos) {
  try {
    m_context = cl::Context(device.device);
    m_queue = cl::CommandQueue(m_context, device.device,
                               profiling ? CL_QUEUE_PROFILING_ENABLE : cl_command_queue_properties(0));
  } catch (const cl::Error& e) {
    throw DeviceError("cannot open OpenCL device '" + device.name + "': " + e.what() + " (" +
                      clErrorName(e.err()) + ")");
  }
}

void Context::launch(const char* stage, cl::Kernel& kernel, std::size_t count, std::size_t localSize,
                     cl::Event* out) {
  if (count == 0) return;
  std::size_t global = (count + localSize - 1) / localSize * localSize;
  // the extra work-items return at the kernels' count guard
  // PoCL keeps its work-group functions by program and kernel name, so a new
  // kernel object of a function launched before needs no wide launch
  if (m_widenFirstLaunches) {
    cl::Program program = kernel.getInfo<CL_KERNEL_PROGRAM>();
    LaunchedProgram& launched = m_launched.try_emplace(program(), LaunchedProgram{program, {}}).first->second;
    if (launched.kernels.emplace(kernel.getInfo<CL_KERNEL_FUNCTION_NAME>(), localSize).second)
      global = std::max(global, (kPoclSmallGridWidth + localSize - 1) / localSize * localSize);
  }
  m_lastGlobal = global;
  cl::Event event;
  try {
    m_queue.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(global), cl::NDRange(localSize),
                                 nullptr, m_profiling ? &event : nullptr);
#ifndef NDEBUG
    // Debug builds stop at the launch that failed, not at a later read.
    m_queue.finish();
#endif
  } catch (const cl::Error& e) {
    throw DeviceError(std::string("launching stage '") + stage + "' failed: " + e.what() + " (" +
                      clErrorName(e.err()) + ")");
  }
  if (m_profiling) {
    m_pending.emplace_back(stage, event);
    if (out) *out = event;
  }
}

void Context::finish() {
  m_queue.finish();
  for (auto& [stage, event] : m_pending) {
    auto start = event.getProfilingInfo<CL_PROFILING_COMMAND_START>();
    auto end = event.getProfilingInfo<CL_PROFILING_COMMAND_END>();
    m_times.seconds[stage] += double(end - start) * 1e-9;
    m_times.launches[stage] += 1;
  }
  m_pending.clear();
}

void Context::fill(cl::Buffer& buffer, cl_uint word, std::size_t offset, std::size_t bytes, cl::Event* event) {
  if (offset % sizeof(cl_uint) != 0 || bytes % sizeof(cl_uint) != 0)
    throw DeviceError("fill: offset " + std::to_string(offset) + " and size " + std::to_string(bytes) +
                      " must be multiples of 4 bytes");
  if (!m_oclgrind) {
    m_queue.enqueueFillBuffer(buffer, word, offset, bytes, nullptr, m_profiling ? event : nullptr);
    return;
  }
  // Oclgrind 21.10's uninitialised-value checker records a host write by
  // replacing the buffer's whole shadow with a fresh one the size of the
  // write (Uninitialized::hostMemoryStore -> ShadowMemory::allocate), and it
  // runs clEnqueueFillBuffer as one write per pattern: after a fill, or after
  // any write to part of a buffer, the rest of the buffer reads as
  // uninitialised (tests/oclgrind/fill_buffer.c). So under Oclgrind a fill is
  // one write of the whole buffer, read first when the fill covers only part
  // of it; the part not filled then counts as initialised, which holds for
  // the one buffer filled in part (the render counters, zeroed whole first).
  std::size_t size = buffer.getInfo<CL_MEM_SIZE>();
  if (offset + bytes > size)
    throw DeviceError("fill: bytes [" + std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                      ") lie outside a buffer of " + std::to_string(size));
  std::vector<cl_uint> words(size / sizeof(cl_uint));
  if (offset != 0 || bytes != size) m_queue.enqueueReadBuffer(buffer, CL_TRUE, 0, size, words.data());
  std::fill(words.begin() + std::ptrdiff_t(offset / 4), words.begin() + std::ptrdiff_t((offset + bytes) / 4), word);
  m_queue.enqueueWriteBuffer(buffer, CL_TRUE, 0, size, words.data());
}

std::string clErrorName(int code) {
  switch (code) {
    case CL_SUCCESS: return "CL_SUCCESS";
    case CL_DEVICE_NOT_FOUND: return "CL_DEVICE_NOT_FOUND";
    case CL_DEVICE_NOT_AVAILABLE: return "CL_DEVICE_NOT_AVAILABLE";
    case CL_COMPILER_NOT_AVAILABLE: return "CL_COMPILER_NOT_AVAILABLE";
    case CL_MEM_OBJECT_ALLOCATION_FAILURE: return "CL_MEM_OBJECT_ALLOCATION_FAILURE";
    case CL_OUT_OF_RESOURCES: return "CL_OUT_OF_RESOURCES";
    case CL_OUT_OF_HOST_MEMORY: return "CL_OUT_OF_HOST_MEMORY";
    case CL_BUILD_PROGRAM_FAILURE: return "CL_BUILD_PROGRAM_FAILURE";
    case CL_INVALID_VALUE: return "CL_INVALID_VALUE";
    case CL_INVALID_DEVICE: return "CL_INVALID_DEVICE";
    case CL_INVALID_BINARY: return "CL_INVALID_BINARY";
    case CL_INVALID_BUILD_OPTIONS: return "CL_INVALID_BUILD_OPTIONS";
    case CL_INVALID_PROGRAM: return "CL_INVALID_PROGRAM";
    case CL_INVALID_KERNEL_NAME: return "CL_INVALID_KERNEL_NAME";
    case CL_INVALID_KERNEL_ARGS: return "CL_INVALID_KERNEL_ARGS";
    case CL_INVALID_ARG_INDEX: return "CL_INVALID_ARG_INDEX";
    case CL_INVALID_ARG_VALUE: return "CL_INVALID_ARG_VALUE";
    case CL_INVALID_ARG_SIZE: return "CL_INVALID_ARG_SIZE";
    case CL_INVALID_WORK_GROUP_SIZE: return "CL_INVALID_WORK_GROUP_SIZE";
    case CL_INVALID_WORK_ITEM_SIZE: return "CL_INVALID_WORK_ITEM_SIZE";
    case CL_INVALID_GLOBAL_WORK_SIZE: return "CL_INVALID_GLOBAL_WORK_SIZE";
    case CL_INVALID_BUFFER_SIZE: return "CL_INVALID_BUFFER_SIZE";
    case CL_INVALID_MEM_OBJECT: return "CL_INVALID_MEM_OBJECT";
    case CL_PLATFORM_NOT_FOUND_KHR: return "CL_PLATFORM_NOT_FOUND_KHR";
    default: return "OpenCL error " + std::to_string(code);
  }
}

std::optional<cl::Program> Context::builtProgram(const std::string& key) const {
  for (const auto& [k, program] : m_programs)
    if (k == key) return program;
  return std::nullopt;
}

void Context::keepProgram(const std::string& key, const cl::Program& program) {
  if (m_programs.size() == kKeptPrograms) m_programs.erase(m_programs.begin());
  m_programs.emplace_back(key, program);
}

}  // namespace wt
