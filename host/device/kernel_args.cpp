#include "device/kernel_args.h"

namespace wt {
namespace {

/// The kernel's argument info of kind `Info` per argument; empty where the
/// program carries none (built without -cl-kernel-arg-info).
template <cl_kernel_arg_info Info>
std::optional<std::vector<std::string>> argInfo(const cl::Kernel& kernel) {
  const cl_uint count = kernel.getInfo<CL_KERNEL_NUM_ARGS>();
  std::vector<std::string> out;
  out.reserve(count);
  for (cl_uint i = 0; i < count; ++i) {
    try {
      out.push_back(kernel.getArgInfo<Info>(i));
    } catch (const cl::Error& e) {
      if (e.err() == CL_KERNEL_ARG_INFO_NOT_AVAILABLE) return std::nullopt;
      throw;
    }
    // some drivers count the terminating zero in the string's size
    while (!out.back().empty() && out.back().back() == '\0') out.back().pop_back();
  }
  return out;
}

}  // namespace

std::optional<std::vector<std::string>> kernelArgNames(const cl::Kernel& kernel) {
  return argInfo<CL_KERNEL_ARG_NAME>(kernel);
}

std::optional<std::vector<std::string>> kernelArgTypeNames(const cl::Kernel& kernel) {
  return argInfo<CL_KERNEL_ARG_TYPE_NAME>(kernel);
}

KernelBinding::KernelBinding(const cl::Program& program, std::string_view kernelName,
                             std::span<const KernelParam> declared, ParamFeatures features)
    : m_name(kernelName), m_declared(declared), m_position(declared.size(), -1), m_bound(declared.size(), false) {
  try {
    m_kernel = cl::Kernel(program, m_name.c_str());
  } catch (const cl::Error& e) {
    throw DeviceError("kernel '" + m_name + "' is not in the program (" + clErrorName(e.err()) + ")");
  }
  std::vector<std::string_view> expected;
  for (std::size_t i = 0; i < declared.size(); ++i) {
    if (!features.has(declared[i].when)) continue;
    m_position[i] = int(expected.size());
    expected.push_back(declared[i].name);
  }
  const cl_uint count = m_kernel.getInfo<CL_KERNEL_NUM_ARGS>();
  if (count != expected.size())
    throw DeviceError("kernel '" + m_name + "' takes " + std::to_string(count) + " arguments, its host declaration " +
                      std::to_string(expected.size()));
  if (std::optional<std::vector<std::string>> names = kernelArgNames(m_kernel)) {
    for (std::size_t i = 0; i < expected.size(); ++i)
      if ((*names)[i] != expected[i])
        throw DeviceError("kernel '" + m_name + "' argument " + std::to_string(i) + " is '" + (*names)[i] +
                          "', its host declaration says '" + std::string(expected[i]) + "'");
  }
}

int KernelBinding::position(std::size_t param) const {
  if (m_position[param] < 0)
    throw DeviceError("kernel '" + m_name + "' has no argument '" + std::string(m_declared[param].name) +
                      "' in this build (a feature it depends on is compiled out)");
  return m_position[param];
}

void KernelBinding::requireBound() const {
  for (std::size_t i = 0; i < m_declared.size(); ++i)
    if (m_position[i] >= 0 && !m_bound[i])
      throw DeviceError("kernel '" + m_name + "' launched with argument '" + std::string(m_declared[i].name) +
                        "' (" + std::to_string(m_position[i]) + ") never set");
}

}  // namespace wt
