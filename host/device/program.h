// Kernel sources (embedded at build time, or a folder on disk for kernel
// development) and the program build, specialised by the scene's features.
#pragma once

#include "device/context.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace wt {

/// What a scene needs compiled in; becomes -D options (kernelDefines). Keep
/// the set coarse so few variants exist and PoCL's cache keeps them warm.
struct KernelFeatures {
  bool integratorMinimal = true;  ///< the brute-force reference (the only integrator so far)
  int bvhStackSize = 64;          ///< traversal stack entries; >= BVH depth + 1, rounded up to 32
  bool pbr = false;               ///< a material uses the metallic-roughness model (else all are Lambertian)
  bool transmission = false;      ///< a metallic-roughness material transmits (KHR_materials_transmission)
  int packetWidth = 8;            ///< rays per packet (WT_PACKET_WIDTH): 8 or 16, packetWidthFor
};

/// Rays per packet for a device: `requested` (8 or 16) when non-zero, else
/// 16 where the device's native float vector is 16 wide (AVX-512 CPUs),
/// else 8. Throws DeviceError for any other request.
int packetWidthFor(const DeviceInfo& device, int requested = 0);

/// The build options for a feature set, e.g. "-D WT_INTEGRATOR_MINIMAL=1 ...".
std::vector<std::string> kernelDefines(const KernelFeatures& features);

/// Read kernels from this folder instead of the embedded copies (developer
/// option, --kernel-dir; also the WT_KERNEL_DIR environment variable).
void setKernelDirectory(const std::optional<std::filesystem::path>& dir);

/// The source of `file` (relative to kernels/) with every `#include "..."`
/// expanded once, resolved against the including file's folder and then the
/// kernels root; `#line` directives keep build logs pointing at real files.
std::string expandKernelSource(const std::string& file);

/// Build kernels/<root> (the renderer's program by default) for the
/// context's device. Throws DeviceError carrying the device's build log.
cl::Program buildProgram(Context& context, const KernelFeatures& features,
                         const std::string& root = "wavetrace.cl");

}  // namespace wt
